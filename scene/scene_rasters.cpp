// Art direction's raster references in a scene file: a table {file, values, range, invert}, or a
// string: the name of a [masks] entry, else (with an extension or a folder in it) a file path.
#include <cmath>
#include <filesystem>

#include "core/errors.h"
#include "scene_schema.h"

namespace snow {
namespace {

namespace fs = std::filesystem;

std::array<double, 2> numberPair(const std::string& source, const toml::node& node, const std::string& key) {
  const toml::array* a = node.as_array();
  if (!a || a->size() != 2 || !(*a)[0].is_number() || !(*a)[1].is_number()) fail(source, node, key, "needs two numbers [first, second]");
  return {(*a)[0].value<double>().value(), (*a)[1].value<double>().value()};
}

}  // namespace

std::string resolvePath(const std::string& file, const std::string& baseDir) {
  fs::path p = file;
  if (p.is_relative() && !baseDir.empty()) p = fs::path(baseDir) / p;
  return p.lexically_normal().string();
}

RasterRef rasterFromTable(const toml::table& t, const std::string& source, const std::string& baseDir, const std::string& key) {
  RasterRef r;
  for (auto&& [k, node] : t) {
    const std::string name(k.str());
    if (name != "file" && name != "values" && name != "range" && name != "invert")
      fail(source, node, key + "." + name, "unknown key (a raster takes file, values, range, invert)");
  }
  const toml::node* file = t.get("file");
  if (!file || !file->is_string()) throw InputError(where(source, t.source()) + ": " + key + ".file: missing (the raster's path)");
  r.file = resolvePath(file->as_string()->get(), baseDir);
  r.declaredAt = where(source, file->source()) + ": " + key;
  std::error_code ec;
  if (!fs::exists(r.file, ec)) fail(source, *file, key + ".file", "raster file '" + r.file + "' does not exist");
  if (const toml::node* v = t.get("values")) {
    r.values = numberPair(source, *v, key + ".values");
    if (!((*r.values)[1] != (*r.values)[0]) || !std::isfinite((*r.values)[0]) || !std::isfinite((*r.values)[1]))
      fail(source, *v, key + ".values", "needs two different finite numbers [value meaning 0, value meaning 1]");
  }
  if (const toml::node* v = t.get("range")) {
    r.range = numberPair(source, *v, key + ".range");
    if (!std::isfinite((*r.range)[0]) || !std::isfinite((*r.range)[1])) fail(source, *v, key + ".range", "needs finite numbers");
  }
  if (const toml::node* v = t.get("invert")) {
    if (!v->is_boolean()) fail(source, *v, key + ".invert", "must be true or false");
    r.invert = v->as_boolean()->get();
  }
  return r;
}

RasterRef rasterRef(const toml::node& node, const std::string& source, const Scene& scene, const std::string& key) {
  if (const toml::table* t = node.as_table()) return rasterFromTable(*t, source, scene.baseDir, key);
  if (!node.is_string()) fail(source, node, key, "must be a mask name from [masks], a raster file path, or a table {file = ...}");
  const std::string text = node.as_string()->get();
  if (auto it = scene.masks.find(text); it != scene.masks.end()) {
    RasterRef r = it->second;
    r.declaredAt = where(source, node.source()) + ": " + key + " (mask '" + text + "')";
    return r;
  }
  if (text.find_first_of("./\\") == std::string::npos)
    fail(source, node, key, "no mask named '" + text + "' in [masks] (a file name needs its extension)");
  RasterRef r;
  r.file = resolvePath(text, scene.baseDir);
  r.declaredAt = where(source, node.source()) + ": " + key;
  std::error_code ec;
  if (!fs::exists(r.file, ec)) fail(source, node, key, "raster file '" + r.file + "' does not exist");
  return r;
}

}  // namespace snow
