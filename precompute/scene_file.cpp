// Scene files: TOML, validated against one table of rules (kSceneRules below, and the parameter
// table of core/parameters.cpp). Every error names the file (or the --set argument), the line
// and the dotted key.
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/errors.h"
#include "embedded_presets.h"
#include "scene.h"

namespace snow {
namespace {

namespace fs = std::filesystem;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Any: a value of several shapes (a raster reference: a string or a table), checked where it is read.
enum class Kind { Table, TableArray, String, Number, Integer, Bool, Date, NumberArray, StringArray, Any };

const char* kindName(Kind k) {
  switch (k) {
    case Kind::Table: return "a table";
    case Kind::TableArray: return "an array of tables ([[...]])";
    case Kind::String: return "a string";
    case Kind::Number: return "a number";
    case Kind::Integer: return "an integer";
    case Kind::Bool: return "true or false";
    case Kind::Date: return "a date (YYYY-MM-DD)";
    case Kind::NumberArray: return "an array of numbers";
    case Kind::StringArray: return "an array of strings";
    case Kind::Any: return "a value";
  }
  return "?";
}

struct Rule {
  std::string path;
  Kind kind;
  double minValue = -kInf;
  double maxValue = kInf;
  std::vector<std::string> choices = {};
};

const std::vector<std::string> kLayerChoices = {"compacted", "stable", "unstable", "powder", "depth", "bedrock", "surface",
                                                "valid_mask", "wind_speed", "wind_direction", "wind_shadow_depth",
                                                "wind_shadow_mask", "sun_exposure", "temperature", "wind_scour",
                                                "wind_deposit", "melt", "avalanche_scour", "avalanche_deposit",
                                                "avalanche_preview", "preview", "ambient_occlusion", "sun_visibility",
                                                "occlusion_accumulation", "occlusion_dissipation", "ski_tracks", "ski_route_map",
                                                "bedform_cohesion"};
// Layers only occlusion mode has.
const std::vector<std::string> kOcclusionLayers = {"ambient_occlusion", "sun_visibility", "occlusion_accumulation",
                                                   "occlusion_dissipation"};

const std::vector<Rule>& sceneRules() {
  static const std::vector<Rule> rules = {
      {"name", Kind::String},
      {"mode", Kind::String, -kInf, kInf, {"season", "occlusion", "mesh"}},
      {"mesh_snow", Kind::Table},
      {"mesh_snow.depth_m", Kind::Number, 0, 100},
      {"mesh_snow.site_spacing_m", Kind::Number, 1e-4, 100},
      {"mesh_snow.sky_cell_sites", Kind::Integer, 1, 64},
      {"mesh_snow.flakes_per_site", Kind::Integer, 1, 1024},
      {"mesh_snow.flutter_mean_m", Kind::Number, 0, 10},
      {"mesh_snow.flutter_sigma_m", Kind::Number, 0, 10},
      {"mesh_snow.swirl_height_m", Kind::Number, 1e-4, 100},
      {"mesh_snow.max_coverage_diff", Kind::Number, 0, 1},
      {"mesh_snow.repose_angle_deg", Kind::Number, 0, 89},
      {"mesh_snow.transition_width_deg", Kind::Number, 0, 90},
      {"mesh_snow.deposit_rounds", Kind::Integer, 1, 100},
      {"mesh_snow.stop_fraction", Kind::Number, 1e-7, 0.5},
      {"mesh_snow.max_passes_per_round", Kind::Integer, 1, 10000000},
      {"mesh_snow.connect_angle_deg", Kind::Number, 1, 89},
      {"mesh_snow.voxel_size_m", Kind::Number, 0, 100},
      {"mesh_snow.smoothing_steps", Kind::Integer, 0, 20},
      {"mesh_snow.adaptivity", Kind::Number, 0, 1},
      {"mesh_snow.density_kg_per_m3", Kind::Number, 1, 1000},
      {"occlusion", Kind::Table},
      {"occlusion.s_max_m", Kind::Number, 0, 1000},
      {"occlusion.tau_ambient", Kind::Number, 0, 10},
      {"occlusion.tau_sun", Kind::Number, 0, 10},
      {"occlusion.sun_positions", Kind::Integer, 0, 1000},
      {"occlusion.ao_rays", Kind::Integer, 0, 65536},
      {"occlusion.ao_radius_m", Kind::Number, 0, 1e7},
      {"occlusion.day", Kind::Number, 0, 3650},
      {"occlusion.turbidity", Kind::Number, 1.7, 10},
      {"terrain", Kind::Table},
      {"terrain.file", Kind::String},
      {"terrain.builtin", Kind::String, -kInf, kInf, {"ridged"}},
      {"terrain.format", Kind::String, -kInf, kInf, {"auto", "dem", "heightmap", "raw", "mesh"}},
      {"terrain.coordinates", Kind::String, -kInf, kInf, {"auto", "geographic", "metres"}},
      {"terrain.fill_nodata", Kind::Bool},
      {"terrain.height_range_m", Kind::NumberArray, -12000, 12000},
      {"terrain.height_scale_m", Kind::Number, -1e6, 1e6},
      {"terrain.height_offset_m", Kind::Number, -1e6, 1e6},
      {"terrain.raw_width", Kind::Integer, 1, 1 << 20},
      {"terrain.raw_height", Kind::Integer, 1, 1 << 20},
      {"terrain.byte_order", Kind::String, -kInf, kInf, {"little", "big"}},
      {"terrain.up_axis", Kind::String, -kInf, kInf, {"z", "y"}},
      {"terrain.resample_cell_size_m", Kind::Number, 0.01, 100000},
      {"terrain.crop_m", Kind::NumberArray, 0, 1e8},
      {"terrain.resample_size", Kind::NumberArray, 3, 1 << 20},
      {"occluders", Kind::TableArray},
      {"occluders.file", Kind::String},
      {"occluders.up_axis", Kind::String, -kInf, kInf, {"z", "y"}},
      {"occluders.offset_m", Kind::NumberArray, -1e7, 1e7},
      {"occluders.scale", Kind::Number, 1e-6, 1e6},
      {"terrain.size", Kind::Integer, 8, 16384},
      {"terrain.cell_size_m", Kind::Number, 0.01, 10000},
      {"terrain.seed", Kind::Integer, 0, 4294967295.0},
      {"terrain.min_altitude_m", Kind::Number, -500, 9000},
      {"terrain.max_altitude_m", Kind::Number, -500, 9000},
      {"site", Kind::Table},
      {"site.latitude_deg", Kind::Number, -90, 90},
      {"site.longitude_deg", Kind::Number, -180, 180},
      {"season", Kind::Table},
      {"season.start_date", Kind::Date},
      {"season.days", Kind::Number, 0.01, 3650},
      {"weather", Kind::Table},
      {"weather.keyframe", Kind::TableArray},
      {"weather.keyframe.day", Kind::Number, 0, 3650},
      {"weather.keyframe.sea_level_temperature_c", Kind::Number, -80, 60},
      {"weather.keyframe.wind_direction_deg", Kind::Number, 0, 360},
      {"weather.keyframe.wind_speed_mps", Kind::Number, 0, 100},
      {"weather.keyframe.snowfall_intensity", Kind::Number, 0, 100},
      {"weather.snowfall", Kind::TableArray},
      {"weather.snowfall.start_day", Kind::Number, 0, 3650},
      {"weather.snowfall.end_day", Kind::Number, 0, 3650},
      {"events", Kind::TableArray},
      {"events.type", Kind::String, -kInf, kInf, {"snowfall", "avalanche", "skier"}},
      {"events.count", Kind::Integer, 1, 10000},
      {"events.position_m", Kind::NumberArray, -1e7, 1e7},
      {"events.map_position", Kind::NumberArray, -1e9, 1e9},
      {"events.day", Kind::Number, 0, 3650},
      {"events.duration_days", Kind::Number, 0.001, 365},
      {"events.mask", Kind::Any},
      {"masks", Kind::Table},
      {"masks.*", Kind::Table},
      {"masks.*.file", Kind::String},
      {"masks.*.values", Kind::NumberArray, -1e30, 1e30},
      {"masks.*.range", Kind::NumberArray, -1e30, 1e30},
      {"masks.*.invert", Kind::Bool},
      {"initial_snow", Kind::Table},
      {"initial_snow.compacted", Kind::Any},
      {"initial_snow.stable", Kind::Any},
      {"initial_snow.unstable", Kind::Any},
      {"initial_snow.powder", Kind::Any},
      {"multipliers", Kind::Table},
      {"multipliers.snowfall", Kind::Any},
      {"multipliers.melt", Kind::Any},
      {"multipliers.wind_erosion", Kind::Any},
      {"multipliers.avalanche_release", Kind::Any},
      {"multipliers.skier_spawn", Kind::Any},
      {"multipliers.no_snow", Kind::Any},
      {"edits", Kind::TableArray},
      {"edits.day", Kind::Number, 0, 3650},
      {"edits.op", Kind::String, -kInf, kInf, {"add", "remove", "set", "move"}},
      {"edits.layer", Kind::String, -kInf, kInf, {"compacted", "stable", "unstable", "powder"}},
      {"edits.to", Kind::String, -kInf, kInf, {"compacted", "stable", "unstable", "powder"}},
      {"edits.depth_m", Kind::Number, 0, 10000},
      {"edits.mask", Kind::Any},
      {"bedforms", Kind::Table},
      {"bedforms.enabled", Kind::Bool},
      {"bedforms.mask", Kind::Any},
      {"bedforms.slab_m", Kind::Number, 0.001, 10},
      {"bedforms.hop_length_m", Kind::Number, 0.01, 1000},
      {"bedforms.reference_wind_mps", Kind::Number, 0.1, 100},
      {"bedforms.threshold_wind_mps", Kind::Number, 0, 100},
      {"bedforms.deposit_on_snow", Kind::Number, 0.001, 1},
      {"bedforms.deposit_on_bare", Kind::Number, 0.001, 1},
      {"bedforms.shadow_angle_deg", Kind::Number, 1, 89},
      {"bedforms.shadow_length_m", Kind::Number, 0, 1000},
      {"bedforms.repose_angle_deg", Kind::Number, 1, 89},
      {"bedforms.speedup_linear", Kind::Number, 0, 100},
      {"bedforms.speedup_quadratic_per_m", Kind::Number, 0, 100},
      {"bedforms.max_slope_deg", Kind::Number, 0, 89},
      {"bedforms.sintering_per_day", Kind::Number, 0, 1000},
      {"bedforms.sintering_scale_c", Kind::Number, 0.1, 100},
      {"bedforms.rounds_per_hour", Kind::Number, 0.01, 3600},
      {"bedforms.batches", Kind::Integer, 1, 64},
      {"bedforms.periodic", Kind::Bool},
      {"parameters", Kind::Table},
      {"precompute", Kind::Table},
      {"precompute.sun", Kind::Bool},
      {"precompute.sun_quality", Kind::String, -kInf, kInf, {"draft", "production", "reference"}},
      {"precompute.sun_method", Kind::String, -kInf, kInf, {"auto", "horizon", "embree"}},
      {"outputs", Kind::Table},
      {"outputs.layers", Kind::StringArray, -kInf, kInf, kLayerChoices},
      {"outputs.format", Kind::String, -kInf, kInf, {"exr", "tiff"}},
      {"outputs.encodings", Kind::StringArray, -kInf, kInf, {"png16", "png8", "r16"}},
      {"outputs.multichannel_exr", Kind::Bool},
      {"outputs.vdb", Kind::Bool},
      {"outputs.ski_track_factor", Kind::Integer, 1, 16},
      {"outputs.meshes", Kind::StringArray, -kInf, kInf, {"ply", "obj", "glb", "fbx"}},
      {"outputs.mesh_parts", Kind::StringArray, -kInf, kInf, {"surface", "body"}},
      {"outputs.mesh_max_error_m", Kind::Number, 0, 10000},
      {"outputs.mesh_tile_size_m", Kind::Number, 0, 1e7},
      {"outputs.vdb_voxel_size_m", Kind::Number, 0.01, 1000},
      {"outputs.compression_level", Kind::Integer, 0, 9},
      {"outputs.displacement_size", Kind::NumberArray, 1, 65536},
      {"outputs.avalanche_maps", Kind::Bool},
      {"outputs.avalanche_frame_interval_s", Kind::Number, 0.01, 3600},
      {"outputs.frames_days", Kind::NumberArray, 0, 3650},
      {"run", Kind::Table},
      {"run.seed", Kind::Integer, 0, 9.007199254740992e15},
      {"run.backend", Kind::String, -kInf, kInf, {"cpu", "cuda", "auto"}},
      {"run.threads", Kind::Integer, 0, 4096},
  };
  return rules;
}

std::string where(const std::string& fallbackSource, const toml::source_region& src) {
  std::ostringstream o;
  o << (src.path && !src.path->empty() ? *src.path : fallbackSource);
  if (src.begin.line > 0) o << ":" << src.begin.line;
  return o.str();
}

[[noreturn]] void fail(const std::string& source, const toml::node& node, const std::string& key, const std::string& what) {
  throw InputError(where(source, node.source()) + ": " + key + ": " + what);
}

// Levenshtein distance, to suggest the key the user probably meant.
size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string suggestion(const std::string& path, const std::vector<std::string>& known) {
  std::string best;
  size_t bestDistance = 4;
  for (const auto& k : known) {
    const size_t d = editDistance(path, k);
    if (d < bestDistance) bestDistance = d, best = k;
  }
  return best.empty() ? "" : " (did you mean '" + best + "'?)";
}

class Validator {
 public:
  explicit Validator(std::string source) : source_(std::move(source)) {
    for (const auto& r : sceneRules()) known_.push_back(r.path);
    for (const auto& p : parameterTable()) known_.push_back(std::string("parameters.") + p.key);
  }

  void checkTable(const toml::table& table, const std::string& prefix) {
    for (auto&& [key, node] : table) {
      const std::string path = prefix.empty() ? std::string(key.str()) : prefix + "." + std::string(key.str());
      if (prefix == "parameters") {
        const ParameterInfo* info = findParameter(std::string(key.str()));
        if (!info) fail(source_, node, path, "unknown parameter" + suggestion(path, known_));
        checkValue(node, path, Rule{path, Kind::Number, info->minValue, info->maxValue});
        continue;
      }
      const Rule* rule = findRule(path);
      if (!rule) fail(source_, node, path, "unknown key" + suggestion(path, known_));
      checkValue(node, path, *rule);
      if (rule->kind == Kind::Table) checkTable(*node.as_table(), path);
      if (rule->kind == Kind::TableArray)
        for (auto&& element : *node.as_array()) checkTable(*element.as_table(), path);
    }
  }

 private:
  const Rule* findRule(std::string path) const {
    // [masks.NAME]: any name, the same keys.
    if (path.rfind("masks.", 0) == 0) {
      const size_t end = path.find('.', 6);
      path = "masks.*" + (end == std::string::npos ? std::string() : path.substr(end));
    }
    for (const auto& r : sceneRules())
      if (r.path == path) return &r;
    return nullptr;
  }

  void checkNumber(const toml::node& node, const std::string& path, const Rule& rule, double v) {
    if (!std::isfinite(v)) fail(source_, node, path, "must be a finite number");
    if (v < rule.minValue || v > rule.maxValue) {
      std::ostringstream o;
      o << "value " << v << " is out of range [" << rule.minValue << ", " << rule.maxValue << "]";
      fail(source_, node, path, o.str());
    }
  }
  void checkChoice(const toml::node& node, const std::string& path, const Rule& rule, const std::string& v) {
    if (rule.choices.empty() || std::find(rule.choices.begin(), rule.choices.end(), v) != rule.choices.end()) return;
    std::string list;
    for (const auto& c : rule.choices) list += (list.empty() ? "" : ", ") + c;
    fail(source_, node, path, "'" + v + "' is not one of: " + list);
  }

  void checkValue(const toml::node& node, const std::string& path, const Rule& rule) {
    auto wrongType = [&] { fail(source_, node, path, std::string("must be ") + kindName(rule.kind) + ", not " + typeName(node)); };
    switch (rule.kind) {
      case Kind::Table:
        if (!node.is_table()) wrongType();
        break;
      case Kind::Any:
        break;
      case Kind::TableArray:
        if (!node.is_array_of_tables()) wrongType();
        break;
      case Kind::String:
        if (!node.is_string()) wrongType();
        checkChoice(node, path, rule, node.as_string()->get());
        break;
      case Kind::Bool:
        if (!node.is_boolean()) wrongType();
        break;
      case Kind::Integer:
        if (!node.is_integer()) wrongType();
        checkNumber(node, path, rule, static_cast<double>(node.as_integer()->get()));
        break;
      case Kind::Number:
        if (!node.is_number()) wrongType();
        checkNumber(node, path, rule, node.value<double>().value());
        break;
      case Kind::Date:
        if (!node.is_date() && !(node.is_string() && parseDate(node.as_string()->get())))
          wrongType();
        break;
      case Kind::NumberArray:
        if (!node.is_array()) wrongType();
        for (auto&& e : *node.as_array()) {
          if (!e.is_number()) fail(source_, e, path, "every element must be a number, not " + typeName(e));
          checkNumber(e, path, rule, e.value<double>().value());
        }
        break;
      case Kind::StringArray:
        if (!node.is_array()) wrongType();
        for (auto&& e : *node.as_array()) {
          if (!e.is_string()) fail(source_, e, path, "every element must be a string, not " + typeName(e));
          checkChoice(e, path, rule, e.as_string()->get());
        }
        break;
    }
  }

 public:
  static std::string typeName(const toml::node& n) {
    switch (n.type()) {
      case toml::node_type::table: return "a table";
      case toml::node_type::array: return "an array";
      case toml::node_type::string: return "a string";
      case toml::node_type::integer: return "an integer";
      case toml::node_type::floating_point: return "a number";
      case toml::node_type::boolean: return "a boolean";
      case toml::node_type::date: return "a date";
      case toml::node_type::time: return "a time";
      case toml::node_type::date_time: return "a date-time";
      default: return "nothing";
    }
  }
  static std::optional<toml::date> parseDate(const std::string& s) {
    int y, m, d;
    char c1, c2;
    std::istringstream in(s);
    if (!(in >> y >> c1 >> m >> c2 >> d) || c1 != '-' || c2 != '-' || m < 1 || m > 12 || d < 1 || d > 31) return {};
    return toml::date{y, m, d};
  }

 private:
  std::string source_;
  std::vector<std::string> known_;
};

// --set KEY=VALUE: VALUE is read as a TOML value; anything that is not valid TOML is a string,
// so `--set terrain.file=dem.tif` needs no quotes.
void applyOverride(toml::table& root, const std::string& assignment) {
  const std::string source = "--set " + assignment;
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError(source + ": expected KEY=VALUE, e.g. --set season.days=30");
  const std::string key = assignment.substr(0, eq);
  const std::string value = assignment.substr(eq + 1);
  std::vector<std::string> parts;
  std::stringstream ss(key);
  for (std::string part; std::getline(ss, part, '.');) {
    if (part.empty()) throw InputError(source + ": empty part in key '" + key + "'");
    parts.push_back(part);
  }
  toml::table parsed;
  try {
    parsed = toml::parse("value = " + value, std::string_view(source));
  } catch (const toml::parse_error&) {
    parsed = toml::table{};
    parsed.insert("value", value);
  }
  toml::table* table = &root;
  for (size_t i = 0; i + 1 < parts.size(); ++i) {
    toml::node* child = table->get(parts[i]);
    if (!child) {
      table->insert(parts[i], toml::table{});
      child = table->get(parts[i]);
    }
    if (!child->is_table())
      throw InputError(source + ": '" + parts[i] + "' in '" + key + "' is not a table (arrays cannot be set from the command line)");
    table = child->as_table();
  }
  table->insert_or_assign(parts.back(), std::move(*parsed.get("value")));
}

double number(const toml::node_view<const toml::node>& n, double fallback) { return n.value<double>().value_or(fallback); }

// Art direction: raster references. A table {file, values, range, invert}, or a string: the name
// of a [masks] entry, else (with an extension or a folder in it) a file path.
std::array<double, 2> numberPair(const std::string& source, const toml::node& node, const std::string& key) {
  const toml::array* a = node.as_array();
  if (!a || a->size() != 2 || !(*a)[0].is_number() || !(*a)[1].is_number()) fail(source, node, key, "needs two numbers [first, second]");
  return {(*a)[0].value<double>().value(), (*a)[1].value<double>().value()};
}

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

bool checkRangePositive(const RasterRef& r) { return !r.range || ((*r.range)[0] >= 0.0 && (*r.range)[1] >= 0.0); }

Scene buildScene(const toml::table& root, const std::string& source, const std::string& baseDir) {
  Scene scene;
  scene.sourceName = source;
  scene.baseDir = baseDir;
  if (auto n = root["name"].value<std::string>()) scene.name = *n;

  // terrain: exactly one of file / builtin
  const toml::table* terrain = root["terrain"].as_table();
  if (!terrain) throw InputError(source + ": terrain: missing [terrain] table (give terrain.file or terrain.builtin)");
  const bool hasFile = terrain->contains("file"), hasBuiltin = terrain->contains("builtin");
  if (hasFile == hasBuiltin)
    throw InputError(where(source, terrain->source()) + ": terrain: give exactly one of terrain.file and terrain.builtin");
  auto& src = scene.terrain;
  auto arrayOf = [&](const char* key, size_t n) -> std::vector<double> {
    const toml::node* node = terrain->get(key);
    std::vector<double> values;
    for (auto&& e : *node->as_array()) values.push_back(e.value<double>().value());
    if (values.size() != n)
      fail(source, *node, std::string("terrain.") + key, "needs " + std::to_string(n) + " numbers, has " + std::to_string(values.size()));
    return values;
  };
  if (auto f = (*terrain)["format"].value<std::string>()) src.format = *f;
  if (auto c = (*terrain)["coordinates"].value<std::string>()) src.coordinates = *c;
  if (auto b = (*terrain)["fill_nodata"].value<bool>()) src.fillNodata = *b;
  if (auto c = (*terrain)["cell_size_m"].value<double>()) src.cellSizeM = *c;
  if (terrain->contains("height_range_m")) {
    const auto r = arrayOf("height_range_m", 2);
    if (!(r[1] > r[0])) fail(source, *terrain->get("height_range_m"), "terrain.height_range_m", "needs [lowest, highest] with highest > lowest");
    src.heightRangeM = std::array<double, 2>{r[0], r[1]};
  }
  if (auto v = (*terrain)["height_scale_m"].value<double>()) src.heightScaleM = *v;
  if (auto v = (*terrain)["height_offset_m"].value<double>()) src.heightOffsetM = *v;
  if (src.heightRangeM && (src.heightScaleM || src.heightOffsetM))
    fail(source, *terrain->get("height_range_m"), "terrain.height_range_m", "give either height_range_m or height_scale_m/height_offset_m, not both");
  if (auto v = (*terrain)["raw_width"].value<int64_t>()) src.rawWidth = static_cast<int>(*v);
  if (auto v = (*terrain)["raw_height"].value<int64_t>()) src.rawHeight = static_cast<int>(*v);
  if (auto v = (*terrain)["byte_order"].value<std::string>()) src.byteOrder = *v;
  if (auto v = (*terrain)["up_axis"].value<std::string>()) src.upAxis = *v;
  if (auto v = (*terrain)["resample_cell_size_m"].value<double>()) src.resampleCellSizeM = *v;
  if (terrain->contains("crop_m")) {
    const auto r = arrayOf("crop_m", 4);
    if (!(r[2] > r[0] && r[3] > r[1]))
      fail(source, *terrain->get("crop_m"), "terrain.crop_m", "needs [west, north, east, south] metres from the north-west corner, east > west and south > north");
    src.cropM = std::array<double, 4>{r[0], r[1], r[2], r[3]};
  }
  if (terrain->contains("resample_size")) {
    const auto r = arrayOf("resample_size", 2);
    for (double v : r)
      if (v != std::floor(v)) fail(source, *terrain->get("resample_size"), "terrain.resample_size", "needs whole numbers [width, height]");
    src.resampleSize = std::array<int, 2>{static_cast<int>(r[0]), static_cast<int>(r[1])};
  }
  if (src.resampleCellSizeM && src.resampleSize)
    fail(source, *terrain->get("resample_size"), "terrain.resample_size", "give either resample_size or resample_cell_size_m, not both");

  if (hasFile) {
    const toml::node& fileNode = *terrain->get("file");
    fs::path p = fileNode.as_string()->get();
    if (p.is_relative() && !baseDir.empty()) p = fs::path(baseDir) / p;
    src.file = p.lexically_normal().string();
    src.declaredAt = where(source, fileNode.source());
    for (const char* builtinOnly : {"size", "seed", "min_altitude_m", "max_altitude_m"})
      if (terrain->contains(builtinOnly))
        fail(source, *terrain->get(builtinOnly), std::string("terrain.") + builtinOnly, "only applies to terrain.builtin");
    std::error_code ec;
    if (!fs::exists(src.file, ec))
      fail(source, fileNode, "terrain.file", "terrain file '" + src.file + "' does not exist");
    if (fs::is_directory(src.file, ec))
      fail(source, fileNode, "terrain.file", "'" + src.file + "' is a folder, not a terrain file");
  } else {
    src.builtin = true;
    auto& o = src.builtinOptions;
    o.size = static_cast<int>((*terrain)["size"].value<int64_t>().value_or(o.size));
    o.cellSizeM = src.cellSizeM.value_or(o.cellSizeM);
    o.seed = static_cast<uint64_t>((*terrain)["seed"].value<int64_t>().value_or(static_cast<int64_t>(o.seed)));
    o.minAltitudeM = (*terrain)["min_altitude_m"].value<double>().value_or(o.minAltitudeM);
    o.maxAltitudeM = (*terrain)["max_altitude_m"].value<double>().value_or(o.maxAltitudeM);
    if (!(o.maxAltitudeM > o.minAltitudeM))
      throw InputError(where(source, terrain->source()) + ": terrain.max_altitude_m: must be above terrain.min_altitude_m");
    src.declaredAt = where(source, terrain->get("builtin")->source());
  }

  if (const toml::array* occluders = root["occluders"].as_array()) {
    for (auto&& element : *occluders) {
      const toml::table& o = *element.as_table();
      if (!o.contains("file")) throw InputError(where(source, o.source()) + ": occluders.file: missing");
      OccluderSource occ;
      const toml::node& fileNode = *o.get("file");
      fs::path p = fileNode.as_string()->get();
      if (p.is_relative() && !baseDir.empty()) p = fs::path(baseDir) / p;
      occ.file = p.lexically_normal().string();
      occ.declaredAt = where(source, fileNode.source());
      std::error_code ec;
      if (!fs::exists(occ.file, ec)) fail(source, fileNode, "occluders.file", "occluder file '" + occ.file + "' does not exist");
      if (auto v = o["up_axis"].value<std::string>()) occ.upAxis = *v;
      if (auto v = o["scale"].value<double>()) occ.scale = *v;
      if (const toml::node* off = o.get("offset_m")) {
        std::vector<double> values;
        for (auto&& e : *off->as_array()) values.push_back(e.value<double>().value());
        if (values.size() != 3) fail(source, *off, "occluders.offset_m", "needs 3 numbers [x, y, z]");
        occ.offsetM = {values[0], values[1], values[2]};
      }
      scene.occluders.push_back(occ);
    }
  }

  if (auto v = root["site"]["latitude_deg"].value<double>()) scene.latitudeDeg = *v;
  if (auto v = root["site"]["longitude_deg"].value<double>()) scene.longitudeDeg = *v;

  if (const toml::node* d = root["season"]["start_date"].node()) {
    const auto date = d->is_date() ? std::optional<toml::date>(d->as_date()->get()) : Validator::parseDate(d->as_string()->get());
    scene.startYear = date->year;
    scene.startMonth = date->month;
    scene.startDay = date->day;
  }
  scene.days = number(root["season"]["days"], scene.days);

  if (const toml::array* keys = root["weather"]["keyframe"].as_array()) {
    double previous = -1.0;
    for (auto&& element : *keys) {
      const toml::table& k = *element.as_table();
      WeatherKeyframe kf;
      if (!k.contains("day")) throw InputError(where(source, k.source()) + ": weather.keyframe.day: missing (each keyframe needs a day)");
      kf.day = k["day"].value<double>().value();
      if (kf.day <= previous)
        fail(source, *k.get("day"), "weather.keyframe.day", "keyframes must be in increasing order of day");
      previous = kf.day;
      WeatherState defaults = scene.weather.keyframes.empty() ? WeatherState{} : scene.weather.keyframes.back().state;
      kf.state.seaLevelTemperatureC = number(k["sea_level_temperature_c"], defaults.seaLevelTemperatureC);
      kf.state.windDirectionDeg = number(k["wind_direction_deg"], defaults.windDirectionDeg);
      kf.state.windSpeedMps = number(k["wind_speed_mps"], defaults.windSpeedMps);
      kf.state.snowfallIntensity = number(k["snowfall_intensity"], defaults.snowfallIntensity);
      scene.weather.keyframes.push_back(kf);
    }
  }
  if (const toml::array* periods = root["weather"]["snowfall"].as_array()) {
    for (auto&& element : *periods) {
      const toml::table& s = *element.as_table();
      for (const char* required : {"start_day", "end_day"})
        if (!s.contains(required))
          throw InputError(where(source, s.source()) + ": weather.snowfall." + required + ": missing");
      SnowfallPeriod p{s["start_day"].value<double>().value(), s["end_day"].value<double>().value()};
      if (!(p.endDay > p.startDay)) fail(source, *s.get("end_day"), "weather.snowfall.end_day", "must be after start_day");
      scene.weather.snowfallPeriods.push_back(p);
    }
  }
  if (const toml::table* masks = root["masks"].as_table()) {
    for (auto&& [key, node] : *masks) {
      const std::string name(key.str());
      const std::string path = "masks." + name;
      if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") != std::string::npos)
        fail(source, node, path, "a mask name takes letters, digits, '_' and '-' only");
      RasterRef r = rasterFromTable(*node.as_table(), source, baseDir, path);
      r.name = name;
      scene.masks[name] = r;
    }
  }
  if (const toml::table* initial = root["initial_snow"].as_table()) {
    const char* names[] = {"compacted", "stable", "unstable", "powder"};
    for (int l = 0; l < 4; ++l) {
      const toml::node* node = initial->get(names[l]);
      if (!node) continue;
      const std::string key = std::string("initial_snow.") + names[l];
      InitialSnowLayer& layer = scene.initialSnow[l];
      if (node->is_number()) {
        layer.kind = InitialSnowLayer::Kind::Constant;
        layer.depthM = node->value<double>().value();
        if (!(layer.depthM >= 0.0 && layer.depthM <= 10000.0)) fail(source, *node, key, "a depth in metres, 0 to 10000");
      } else if (const toml::table* t = node->as_table(); t && t->contains("mask")) {
        for (auto&& [k, v] : *t)
          if (k.str() != "mask" && k.str() != "depth_m") fail(source, v, key + "." + std::string(k.str()), "unknown key (a masked depth takes mask and depth_m)");
        if (!t->contains("depth_m") || !t->get("depth_m")->is_number())
          throw InputError(where(source, t->source()) + ": " + key + ".depth_m: missing (the depth where the mask is 1, metres)");
        layer.kind = InitialSnowLayer::Kind::Mask;
        layer.depthM = t->get("depth_m")->value<double>().value();
        if (!(layer.depthM >= 0.0 && layer.depthM <= 10000.0)) fail(source, *t->get("depth_m"), key + ".depth_m", "a depth in metres, 0 to 10000");
        layer.raster = rasterRef(*t->get("mask"), source, scene, key + ".mask");
      } else {
        layer.kind = InitialSnowLayer::Kind::Raster;
        layer.raster = rasterRef(*node, source, scene, key);
        if (!checkRangePositive(layer.raster)) fail(source, *node, key, "a depth raster's range must not be negative");
      }
    }
  }
  if (const toml::table* m = root["multipliers"].as_table()) {
    Multipliers& mu = scene.multipliers;
    const std::pair<const char*, std::optional<RasterRef>*> entries[] = {
        {"snowfall", &mu.snowfall}, {"melt", &mu.melt}, {"wind_erosion", &mu.windErosion},
        {"avalanche_release", &mu.avalancheRelease}, {"skier_spawn", &mu.skierSpawn}, {"no_snow", &mu.noSnow}};
    for (const auto& [name, slot] : entries)
      if (const toml::node* node = m->get(name)) {
        *slot = rasterRef(*node, source, scene, std::string("multipliers.") + name);
        if (!checkRangePositive(**slot)) fail(source, *node, std::string("multipliers.") + name, "a multiplier's range must not be negative");
      }
  }
  if (const toml::array* edits = root["edits"].as_array()) {
    for (auto&& element : *edits) {
      const toml::table& e = *element.as_table();
      for (const char* required : {"day", "op", "layer"})
        if (!e.contains(required)) throw InputError(where(source, e.source()) + ": edits." + required + ": missing");
      EditSpec ed;
      ed.day = e["day"].value<double>().value();
      ed.op = e["op"].value<std::string>().value();
      ed.layer = e["layer"].value<std::string>().value();
      ed.declaredAt = where(source, e.source());
      if (ed.day > scene.days)
        fail(source, *e.get("day"), "edits.day", "day " + std::to_string(ed.day) + " is after the season's end");
      if (auto d = e["depth_m"].value<double>()) ed.depthM = *d;
      if (ed.op != "move" && !ed.depthM)
        throw InputError(ed.declaredAt + ": edits.depth_m: missing (op = \"" + ed.op + "\" needs a depth in metres)");
      if (auto to = e["to"].value<std::string>()) ed.to = *to;
      if (ed.op == "move" && ed.to.empty())
        throw InputError(ed.declaredAt + ": edits.to: missing (op = \"move\" needs the layer that receives)");
      if (ed.op != "move" && !ed.to.empty()) fail(source, *e.get("to"), "edits.to", "only op = \"move\" has a destination layer");
      if (ed.op == "move" && ed.to == ed.layer) fail(source, *e.get("to"), "edits.to", "moves snow to the layer it takes it from");
      if (const toml::node* mask = e.get("mask")) ed.mask = rasterRef(*mask, source, scene, "edits.mask");
      scene.edits.push_back(ed);
    }
    std::stable_sort(scene.edits.begin(), scene.edits.end(), [](const EditSpec& a, const EditSpec& b) { return a.day < b.day; });
  }
  if (const toml::array* events = root["events"].as_array()) {
    for (auto&& element : *events) {
      const toml::table& e = *element.as_table();
      for (const char* required : {"type", "day"})
        if (!e.contains(required)) throw InputError(where(source, e.source()) + ": events." + required + ": missing");
      const double day = e["day"].value<double>().value();
      const std::string type = e["type"].value<std::string>().value();
      if (type == "avalanche" || type == "skier") {
        const bool metres = e.contains("position_m"), map = e.contains("map_position"), masked = e.contains("mask");
        if (static_cast<int>(metres) + static_cast<int>(map) + static_cast<int>(masked) != 1)
          throw InputError(where(source, e.source()) + ": events: " + (type == "skier" ? "a skier" : "an avalanche") +
                           " needs position_m = [x, y], map_position = [easting, northing] or mask = ... (one of them)");
        Scene::AvalancheEvent a;
        a.day = day;
        a.line = static_cast<int>(e.source().begin.line);
        if (masked) {
          a.mask = rasterRef(*e.get("mask"), source, scene, "events.mask");
        } else {
          const char* key = metres ? "position_m" : "map_position";
          const toml::array& xy = *e.get(key)->as_array();
          if (xy.size() != 2) fail(source, *e.get(key), std::string("events.") + key, "needs two numbers");
          a.xM = xy[0].value<double>().value();
          a.yM = xy[1].value<double>().value();
          a.mapCoordinates = map;
        }
        if (type == "skier") {
          a.count = static_cast<int>(e["count"].value<int64_t>().value_or(1));
          scene.userSkiers.push_back(a);
        } else {
          if (e.contains("count")) fail(source, *e.get("count"), "events.count", "only skier events have a count");
          scene.userAvalanches.push_back(a);
        }
        continue;
      }
      if (e.contains("mask")) fail(source, *e.get("mask"), "events.mask", "only avalanche and skier events take a mask");
      if (!e.contains("duration_days")) throw InputError(where(source, e.source()) + ": events.duration_days: missing");
      scene.userSnowfalls.push_back({day, day + e["duration_days"].value<double>().value()});
    }
  }
  if (const toml::table* params = root["parameters"].as_table())
    for (auto&& [key, node] : *params) scene.params.*(findParameter(std::string(key.str()))->member) = node.value<double>().value();
  // Ranges that depend on each other.
  const ModelParameters& p = scene.params;
  if (!(p.freezeTemperatureC < p.coolTemperatureC && p.coolTemperatureC < p.warmTemperatureC))
    throw InputError(source + ": parameters: need freeze_temperature_c < cool_temperature_c < warm_temperature_c");

  if (const toml::node* layers = root["outputs"]["layers"].node()) {
    scene.outputs.layers.clear();
    for (auto&& e : *layers->as_array()) scene.outputs.layers.push_back(e.as_string()->get());
  }
  if (auto f = root["outputs"]["format"].value<std::string>()) scene.outputs.format = *f;
  if (auto v = root["outputs"]["avalanche_maps"].value<bool>()) scene.outputs.avalancheMaps = *v;
  if (const toml::node* enc = root["outputs"]["encodings"].node())
    for (auto&& e : *enc->as_array()) scene.outputs.encodings.push_back(e.as_string()->get());
  if (auto v = root["outputs"]["multichannel_exr"].value<bool>()) scene.outputs.multichannelExr = *v;
  if (auto v = root["outputs"]["vdb"].value<bool>()) scene.outputs.vdb = *v;
  if (auto v = root["outputs"]["ski_track_factor"].value<int64_t>()) scene.outputs.skiTrackFactor = static_cast<int>(*v);
  if (const toml::node* meshes = root["outputs"]["meshes"].node())
    for (auto&& e : *meshes->as_array()) scene.outputs.meshes.push_back(e.as_string()->get());
  if (const toml::node* parts = root["outputs"]["mesh_parts"].node()) {
    scene.outputs.meshParts.clear();
    for (auto&& e : *parts->as_array()) scene.outputs.meshParts.push_back(e.as_string()->get());
    if (scene.outputs.meshParts.empty()) fail(source, *parts, "outputs.mesh_parts", "needs \"surface\", \"body\" or both");
  }
  scene.outputs.meshMaxErrorM = number(root["outputs"]["mesh_max_error_m"], scene.outputs.meshMaxErrorM);
  scene.outputs.meshTileSizeM = number(root["outputs"]["mesh_tile_size_m"], scene.outputs.meshTileSizeM);
  if (auto v = root["outputs"]["vdb_voxel_size_m"].value<double>()) scene.outputs.vdbVoxelSizeM = *v;
  if (auto v = root["outputs"]["compression_level"].value<int64_t>()) scene.outputs.compressionLevel = static_cast<int>(*v);
  if (const toml::node* size = root["outputs"]["displacement_size"].node()) {
    const toml::array& a = *size->as_array();
    if (a.size() != 2 || a[0].value<double>().value() != std::floor(a[0].value<double>().value()) ||
        a[1].value<double>().value() != std::floor(a[1].value<double>().value()))
      fail(source, *size, "outputs.displacement_size", "needs whole numbers [width, height]");
    scene.outputs.displacementWidth = static_cast<int>(a[0].value<double>().value());
    scene.outputs.displacementHeight = static_cast<int>(a[1].value<double>().value());
  }
  if (auto v = root["outputs"]["avalanche_frame_interval_s"].value<double>()) scene.outputs.avalancheFrameIntervalS = *v;
  if (const toml::node* frames = root["outputs"]["frames_days"].node()) {
    for (auto&& e : *frames->as_array()) {
      const double day = e.value<double>().value();
      if (day > scene.days) fail(source, e, "outputs.frames_days", "day " + std::to_string(day) + " is after the season's end");
      scene.outputs.frameDays.push_back(day);
    }
  }
  if (auto v = root["mode"].value<std::string>()) scene.mode = *v;
  if (const toml::table* bt = root["bedforms"].as_table()) {
    BedformScene& b = scene.bedforms;
    BedformParameters& bp = b.params;
    const toml::node_view<const toml::node> t{bt};
    b.enabled = t["enabled"].value<bool>().value_or(true);
    bp.slabM = number(t["slab_m"], bp.slabM);
    bp.hopLengthM = number(t["hop_length_m"], bp.hopLengthM);
    bp.referenceWindMps = number(t["reference_wind_mps"], bp.referenceWindMps);
    bp.thresholdWindMps = number(t["threshold_wind_mps"], bp.thresholdWindMps);
    bp.depositSnow = number(t["deposit_on_snow"], bp.depositSnow);
    bp.depositBare = number(t["deposit_on_bare"], bp.depositBare);
    bp.shadowAngleDeg = number(t["shadow_angle_deg"], bp.shadowAngleDeg);
    bp.shadowLengthM = number(t["shadow_length_m"], bp.shadowLengthM);
    bp.reposeAngleDeg = number(t["repose_angle_deg"], bp.reposeAngleDeg);
    bp.speedupLinear = number(t["speedup_linear"], bp.speedupLinear);
    bp.speedupQuadraticPerM = number(t["speedup_quadratic_per_m"], bp.speedupQuadraticPerM);
    bp.maxSlopeDeg = number(t["max_slope_deg"], bp.maxSlopeDeg);
    bp.sinteringPerDay = number(t["sintering_per_day"], bp.sinteringPerDay);
    bp.sinteringScaleC = number(t["sintering_scale_c"], bp.sinteringScaleC);
    bp.roundsPerHour = number(t["rounds_per_hour"], bp.roundsPerHour);
    bp.batches = static_cast<int>(t["batches"].value<int64_t>().value_or(bp.batches));
    bp.periodic = t["periodic"].value<bool>().value_or(bp.periodic);
    if (const toml::node* mask = bt->get("mask")) b.mask = rasterRef(*mask, source, scene, "bedforms.mask");
    if (b.enabled && scene.mode == "occlusion") throw InputError(source + ": bedforms: mode = \"occlusion\" has no season to move snow in");
  }
  if (!scene.bedforms.enabled && std::find(scene.outputs.layers.begin(), scene.outputs.layers.end(), "bedform_cohesion") != scene.outputs.layers.end())
    fail(source, *root["outputs"]["layers"].node(), "outputs.layers", "'bedform_cohesion' needs [bedforms]");
  {
    OcclusionParameters& o = scene.occlusion;
    o.sMaxM = number(root["occlusion"]["s_max_m"], o.sMaxM);
    o.tauAmbient = number(root["occlusion"]["tau_ambient"], o.tauAmbient);
    o.tauSun = number(root["occlusion"]["tau_sun"], o.tauSun);
    o.sunPositions = static_cast<int>(root["occlusion"]["sun_positions"].value<int64_t>().value_or(o.sunPositions));
    o.aoRays = static_cast<int>(root["occlusion"]["ao_rays"].value<int64_t>().value_or(o.aoRays));
    o.aoRadiusM = number(root["occlusion"]["ao_radius_m"], o.aoRadiusM);
    if (const toml::node* day = root["occlusion"]["day"].node()) {
      o.day = number(root["occlusion"]["day"], 0.0);
      if (*o.day > scene.days) fail(source, *day, "occlusion.day", "day " + std::to_string(*o.day) + " is after the season's end");
    }
    o.turbidity = number(root["occlusion"]["turbidity"], o.turbidity);
  }
  {
    MeshSnowScene& m = scene.meshSnow;
    const auto t = root["mesh_snow"];
    m.placement.depthM = number(t["depth_m"], m.placement.depthM);
    m.placement.siteSpacingM = number(t["site_spacing_m"], m.placement.siteSpacingM);
    m.placement.skyCellSites = static_cast<int>(t["sky_cell_sites"].value<int64_t>().value_or(m.placement.skyCellSites));
    m.placement.flakesPerSite = static_cast<int>(t["flakes_per_site"].value<int64_t>().value_or(m.placement.flakesPerSite));
    m.placement.flutterMeanM = number(t["flutter_mean_m"], m.placement.flutterMeanM);
    m.placement.flutterSigmaM = number(t["flutter_sigma_m"], m.placement.flutterSigmaM);
    m.placement.swirlHeightM = number(t["swirl_height_m"], m.placement.swirlHeightM);
    m.placement.maxCoverageDiff = number(t["max_coverage_diff"], m.placement.maxCoverageDiff);
    m.stability.reposeAngleDeg = number(t["repose_angle_deg"], m.stability.reposeAngleDeg);
    m.stability.transitionWidthDeg = number(t["transition_width_deg"], m.stability.transitionWidthDeg);
    m.stability.depositRounds = static_cast<int>(t["deposit_rounds"].value<int64_t>().value_or(m.stability.depositRounds));
    m.stability.stopFraction = number(t["stop_fraction"], m.stability.stopFraction);
    m.stability.maxPassesPerRound = static_cast<int>(t["max_passes_per_round"].value<int64_t>().value_or(m.stability.maxPassesPerRound));
    m.stability.connectAngleDeg = number(t["connect_angle_deg"], m.stability.connectAngleDeg);
    m.body.voxelSizeM = number(t["voxel_size_m"], m.body.voxelSizeM);
    m.body.smoothingSteps = static_cast<int>(t["smoothing_steps"].value<int64_t>().value_or(m.body.smoothingSteps));
    m.body.adaptivity = number(t["adaptivity"], m.body.adaptivity);
    m.body.densityKgPerM3 = number(t["density_kg_per_m3"], m.body.densityKgPerM3);
    m.onOccluders = root["mesh_snow"].node() != nullptr && scene.mode == "season";
    if (root["mesh_snow"].node() && scene.mode == "occlusion")
      throw InputError(source + ": mesh_snow: mode = \"occlusion\" does not use it (mode = \"mesh\", or a season with [[occluders]])");
    if (m.onOccluders && scene.occluders.empty())
      throw InputError(source + ": mesh_snow: in a season it puts snow on the [[occluders]] meshes, and the scene has none");
    if (m.onOccluders && scene.outputs.meshes.empty())
      throw InputError(source + ": mesh_snow: the occluders' snow bodies need outputs.meshes (the formats to write them in)");
  }
  if (scene.mode == "mesh") {
    // Snow on the mesh itself (Fearing): no grid, no season; the snow body is the output.
    if (scene.terrain.builtin) throw InputError(source + ": mode = \"mesh\" needs terrain.file to name a mesh (.obj, .ply, .glb, .gltf, .fbx)");
    if (root["outputs"]["layers"].node() || !scene.outputs.encodings.empty() || scene.outputs.multichannelExr ||
        scene.outputs.displacementWidth > 0 || !scene.outputs.frameDays.empty() || scene.outputs.avalancheMaps)
      throw InputError(source + ": outputs: mode = \"mesh\" writes the snow body only (outputs.meshes, outputs.vdb); grid layers, "
                       "encodings, displacement maps and frames need a height field");
    if (root["outputs"]["mesh_parts"].node()) throw InputError(source + ": outputs.mesh_parts: mode = \"mesh\" writes the snow body (snow_body.EXT)");
    if (scene.outputs.meshes.empty() && !scene.outputs.vdb)
      throw InputError(source + ": outputs: mode = \"mesh\" needs outputs.meshes or outputs.vdb = true");
    if (!scene.userAvalanches.empty() || !scene.userSkiers.empty() || !scene.edits.empty() || scene.bedforms.enabled)
      throw InputError(source + ": mode = \"mesh\" has no season: no events, edits or bedforms");
  }
  if (scene.mode == "occlusion") {
    // No season: the outputs that only a season makes are errors, not silently empty files.
    for (const auto& layer : scene.outputs.layers)
      for (const char* seasonOnly : {"wind_scour", "wind_deposit", "melt", "avalanche_scour", "avalanche_deposit", "avalanche_preview", "ski_tracks", "ski_route_map",
                                     "sun_exposure", "temperature", "wind_speed", "wind_direction", "wind_shadow_depth", "wind_shadow_mask"})
        if (layer == seasonOnly)
          fail(source, *root["outputs"]["layers"].node(), "outputs.layers", "'" + layer + "' needs a season; mode = \"occlusion\" has none");
    if (!scene.outputs.frameDays.empty())
      fail(source, *root["outputs"]["frames_days"].node(), "outputs.frames_days", "mode = \"occlusion\" has no season to take frames of");
    if (scene.outputs.avalancheMaps || scene.outputs.avalancheFrameIntervalS > 0)
      throw InputError(source + ": outputs.avalanche_*: mode = \"occlusion\" has no avalanches");
    if (!scene.userAvalanches.empty() || !scene.userSkiers.empty())
      throw InputError(source + ": events: mode = \"occlusion\" has no season for avalanche or skier events");
    if (!scene.edits.empty()) throw InputError(source + ": edits: mode = \"occlusion\" has no season to edit");
    for (const auto& l : scene.initialSnow)
      if (l.kind != InitialSnowLayer::Kind::None) throw InputError(source + ": initial_snow: mode = \"occlusion\" has no season to start");
    const Multipliers& mu = scene.multipliers;
    if (mu.melt || mu.windErosion || mu.avalancheRelease || mu.skierSpawn)
      throw InputError(source + ": multipliers: mode = \"occlusion\" takes only snowfall and no_snow (melt, wind, avalanches and skiers need a season)");
  } else {
    for (const auto& layer : scene.outputs.layers)
      if (std::find(kOcclusionLayers.begin(), kOcclusionLayers.end(), layer) != kOcclusionLayers.end())
        fail(source, *root["outputs"]["layers"].node(), "outputs.layers", "'" + layer + "' needs mode = \"occlusion\"");
  }
  if (auto v = root["precompute"]["sun"].value<bool>()) scene.sunExposure = *v;
  if (auto v = root["precompute"]["sun_quality"].value<std::string>()) scene.sunQuality = *v;
  if (auto v = root["precompute"]["sun_method"].value<std::string>()) scene.sunMethod = *v;
  scene.seed = static_cast<uint64_t>(root["run"]["seed"].value<int64_t>().value_or(1));
  if (auto b = root["run"]["backend"].value<std::string>()) scene.backend = *b;
  scene.threads = static_cast<int>(root["run"]["threads"].value<int64_t>().value_or(0));

  std::ostringstream canonical;
  canonical << root;
  scene.canonicalToml = canonical.str();
  return scene;
}

Scene parseAndBuild(toml::table root, const std::string& source, const std::string& baseDir,
                    const std::vector<std::string>& overrides) {
  for (const auto& o : overrides) applyOverride(root, o);
  Validator(source).checkTable(root, "");
  return buildScene(root, source, baseDir);
}

[[noreturn]] void rethrowParseError(const toml::parse_error& e, const std::string& source) {
  std::ostringstream o;
  o << source << ":" << e.source().begin.line << ": TOML syntax error: " << e.description();
  throw InputError(o.str());
}

}  // namespace

Scene loadSceneText(const std::string& text, const std::string& sourceName, const std::string& baseDir,
                    const std::vector<std::string>& overrides) {
  toml::table root;
  try {
    root = toml::parse(text, std::string_view(sourceName));
  } catch (const toml::parse_error& e) {
    rethrowParseError(e, sourceName);
  }
  return parseAndBuild(std::move(root), sourceName, baseDir, overrides);
}

Scene loadSceneFile(const std::string& path, const std::vector<std::string>& overrides) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": scene file does not exist");
  if (fs::is_directory(path, ec)) throw InputError(path + ": is a folder, not a scene file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the scene file for reading");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string base = fs::path(path).parent_path().string();
  return loadSceneText(buffer.str(), path, base.empty() ? "." : base, overrides);
}

Scene loadScene(const std::string& pathOrPreset, const std::vector<std::string>& overrides) {
  const std::string prefix = "preset:";
  if (pathOrPreset.rfind(prefix, 0) == 0) {
    const std::string name = pathOrPreset.substr(prefix.size());
    if (name != "default") throw InputError(pathOrPreset + ": unknown preset (available: preset:default)");
    return loadSceneText(presets::kDefault, pathOrPreset, fs::current_path().string(), overrides);
  }
  return loadSceneFile(pathOrPreset, overrides);
}

}  // namespace snow
