// The resolved scene (scene.resolved.toml beside the outputs): the merged document the scene
// was built from (canonicalToml: file, preset and --set overrides), with every key it left out
// written at its default and every path made absolute, so that baking it from anywhere is the
// same bake.
#include <algorithm>
#include <filesystem>
#include <sstream>

#include "core/parameters.h"
#include "scene.h"
#include "scene_schema.h"

namespace snow {
namespace fs = std::filesystem;
namespace {

// The table at `path`'s parent (created on the way), or null where an array or value is in the way.
toml::table* parentTable(toml::table& root, const std::string& path, std::string& leaf) {
  toml::table* t = &root;
  size_t start = 0;
  for (size_t dot; (dot = path.find('.', start)) != std::string::npos; start = dot + 1) {
    const std::string part = path.substr(start, dot - start);
    if (!t->contains(part)) t->insert(part, toml::table{});
    t = (*t)[part].as_table();
    if (!t) return nullptr;
  }
  leaf = path.substr(start);
  return t;
}

// The rule's value as the schema shows it, where that is a TOML value ("none" is not).
std::optional<toml::table> shownValue(const std::string& shown) {
  try {
    return toml::parse("v = " + shown);
  } catch (const toml::parse_error&) {
    return std::nullopt;
  }
}

// Whether the schema accepts the value: defaults that mean "off" or "automatic" (0 where the range
// starts above it) cannot be written, and are left out as the scene left them.
bool writable(const Rule& rule, const toml::node& v) {
  if (const auto number = v.value<double>(); number && (v.is_number()))
    return *number >= rule.minValue && *number <= rule.maxValue;
  if (const auto text = v.value<std::string>(); text && text->empty()) return false;  // no file, no name
  if (const auto text = v.value<std::string>(); text && !rule.choices.empty())
    return std::find(rule.choices.begin(), rule.choices.end(), *text) != rule.choices.end();
  return true;
}

// Sections whose mere presence changes nothing; a [mesh_snow] or [bedforms] table the scene did
// not write turns a model on, so such sections are filled only where the scene has them.
bool alwaysFilled(const std::string& section) {
  for (const char* s : {"", "run", "season", "precompute", "outputs", "site", "terrain"})
    if (section == s) return true;
  return false;
}

// The table a rule's key would go in when the scene left it out, as "[name]": its section when
// that is absent and not always filled, else its sub-table ([outputs.tiles]) when that is absent
// (each is a choice the scene makes); "" when the key can be written.
std::string absentScope(const toml::table& root, const std::string& path) {
  const std::string section = path.find('.') == std::string::npos ? "" : path.substr(0, path.find('.'));
  if (!alwaysFilled(section) && !root.contains(section)) return "[" + section + "]";
  const std::string parent = path.substr(0, path.rfind('.'));
  if (parent.find('.') != std::string::npos && !root.at_path(parent).node()) return "[" + parent + "]";
  return "";
}

// The keys left out, with the defaults that cannot be written listed in `unwritten`.
void addDefaults(toml::table& root, const Scene& scene, std::vector<std::string>& unwritten) {
  for (const Rule& rule : sceneRules()) {
    const auto* bind = std::get_if<Bind<Scene>>(&rule.bind);
    if (!bind || !bind->show || rule.path.find('*') != std::string::npos || rule.kind == Kind::Any) continue;
    // --seed and --backend set the Scene, not the document (the thread count changes no byte, and
    // is left as the scene has it so that the resolved scene is the same for any).
    const bool fromCommandLine = rule.path == "run.seed" || rule.path == "run.backend";
    if (root.at_path(rule.path).node() && !fromCommandLine) continue;
    if (const std::string scope = absentScope(root, rule.path); !scope.empty()) {
      if (unwritten.empty() || unwritten.back() != scope) unwritten.push_back(scope);
      continue;
    }
    static const Scene defaults;
    std::optional<toml::table> value = shownValue(bind->show(rule.path == "run.threads" ? defaults : scene));
    if (!value || !writable(rule, *value->get("v"))) {
      unwritten.push_back(rule.path);
      continue;
    }
    std::string leaf;
    if (toml::table* parent = parentTable(root, rule.path, leaf)) parent->insert_or_assign(leaf, *value->get("v"));
  }
  for (const ParameterInfo& p : parameterTable()) {
    std::string leaf;
    const std::string path = std::string("parameters.") + p.key;
    if (root.at_path(path).node()) continue;
    if (toml::table* parent = parentTable(root, path, leaf)) parent->insert(leaf, scene.params.*(p.member));
  }
}

// A path string made absolute against the scene's folder; mask names and builtin names stay.
void absolutePath(toml::node& node, const std::string& baseDir) {
  if (toml::value<std::string>* s = node.as_string(); s && s->get().find_first_of("./\\") != std::string::npos)
    *s = fs::absolute(resolvePath(s->get(), baseDir)).lexically_normal().string();
}

// Every `file` key, and every raster given as a bare path, wherever it sits (tables, arrays of tables).
void absolutePaths(toml::node& node, const std::string& baseDir, const std::string& key) {
  if (toml::table* t = node.as_table()) {
    for (auto&& [k, child] : *t) absolutePaths(child, baseDir, std::string(k.str()));
  } else if (toml::array* a = node.as_array()) {
    for (auto&& child : *a)
      if (child.is_table()) absolutePaths(child, baseDir, key);
  } else if (key == "file" || node.is_string()) {
    // Other strings with a dot or slash are names or choices (sun_quality = "high", a date is not a string).
    const toml::value<std::string>* s = node.as_string();
    if (key == "file" || (s && fs::exists(resolvePath(s->get(), baseDir)))) absolutePath(node, baseDir);
  }
}

}  // namespace

std::string resolvedSceneToml(const Scene& scene) {
  toml::table root = toml::parse(scene.canonicalToml);
  std::vector<std::string> unwritten;
  addDefaults(root, scene, unwritten);
  absolutePaths(root, scene.baseDir, "");
  std::ostringstream o;
  o << "# " << scene.sourceName << " resolved: every key with its value, defaults and --set overrides included, paths absolute.\n"
    << "# Left out, at defaults that mean none, off or automatic, or in sections whose presence turns a model on:";
  for (const std::string& path : unwritten) o << " " << path;
  o << "\n" << root << "\n";
  return o.str();
}

}  // namespace snow
