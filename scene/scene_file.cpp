// Scene files: TOML, validated against the schema's rules (scene_schema.cpp, and the parameter
// table of core/parameters.cpp), then read through the rules' bindings and checked across keys,
// one function per section. Every error names the file (or the --set argument), the line and the
// dotted key.
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/errors.h"
#include "embedded_presets.h"
#include "scene/layers.h"
#include "scene.h"
#include "scene_schema.h"
#include "tile_sizes.h"

namespace snow {
namespace {

namespace fs = std::filesystem;

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

  // Every list of names names files (layers, encodings, mesh formats and parts): a repeat would
  // write one file from two tasks at once.
  void checkNoRepeats(const toml::array& list, const std::string& path) {
    for (size_t i = 0; i < list.size(); ++i)
      for (size_t j = 0; j < i; ++j)
        if (list[i].as_string()->get() == list[j].as_string()->get())
          fail(source_, list[i], path, "'" + list[i].as_string()->get() + "' is listed twice (each names its own files)");
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
        checkNoRepeats(*node.as_array(), path);
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

// --- applying the schema's bindings

// Every rule bound into a T, in the table's order: its value in `table` (the scene's root, or one
// element of the array of tables `prefix`), when given, goes where the rule says.
template <class T>
void applyBindings(T& target, const toml::table& table, const std::string& prefix, const std::string& source, const Scene& scene) {
  for (const Rule& rule : sceneRules()) {
    const Bind<T>* bind = std::get_if<Bind<T>>(&rule.bind);
    if (!bind) continue;
    const toml::node* node = table.at_path(prefix.empty() ? rule.path : rule.path.substr(prefix.size() + 1)).node();
    if (node) bind->set(target, *node, BindContext{source, rule.path, scene});
  }
}

void requireKeys(const toml::table& t, std::initializer_list<const char*> keys, const std::string& source, const std::string& prefix) {
  for (const char* key : keys)
    if (!t.contains(key)) throw InputError(where(source, t.source()) + ": " + prefix + "." + key + ": missing");
}

// --- sections read element by element

void readOccluders(Scene& scene, const toml::table& root, const std::string& source) {
  const toml::array* occluders = root["occluders"].as_array();
  if (!occluders) return;
  for (auto&& element : *occluders) {
    const toml::table& o = *element.as_table();
    requireKeys(o, {"file"}, source, "occluders");
    OccluderSource occ;
    applyBindings(occ, o, "occluders", source, scene);
    scene.occluders.push_back(occ);
  }
}

void readWeather(Scene& scene, const toml::table& root, const std::string& source) {
  if (const toml::array* keys = root["weather"]["keyframe"].as_array()) {
    double previous = -1.0;
    for (auto&& element : *keys) {
      const toml::table& k = *element.as_table();
      if (!k.contains("day")) throw InputError(where(source, k.source()) + ": weather.keyframe.day: missing (each keyframe needs a day)");
      WeatherKeyframe kf;
      if (!scene.weather.keyframes.empty()) kf.state = scene.weather.keyframes.back().state;  // omitted values carry over
      applyBindings(kf, k, "weather.keyframe", source, scene);
      if (kf.day <= previous) fail(source, *k.get("day"), "weather.keyframe.day", "keyframes must be in increasing order of day");
      previous = kf.day;
      scene.weather.keyframes.push_back(kf);
    }
  }
  if (const toml::array* periods = root["weather"]["snowfall"].as_array()) {
    for (auto&& element : *periods) {
      const toml::table& s = *element.as_table();
      requireKeys(s, {"start_day", "end_day"}, source, "weather.snowfall");
      SnowfallPeriod p;
      applyBindings(p, s, "weather.snowfall", source, scene);
      if (!(p.endDay > p.startDay)) fail(source, *s.get("end_day"), "weather.snowfall.end_day", "must be after start_day");
      scene.weather.snowfallPeriods.push_back(p);
    }
  }
}

void readMasks(Scene& scene, const toml::table& root, const std::string& source) {
  const toml::table* masks = root["masks"].as_table();
  if (!masks) return;
  for (auto&& [key, node] : *masks) {
    const std::string name(key.str());
    const std::string path = "masks." + name;
    if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") != std::string::npos)
      fail(source, node, path, "a mask name takes letters, digits, '_' and '-' only");
    RasterRef r = rasterFromTable(*node.as_table(), source, scene.baseDir, path);
    r.name = name;
    scene.masks[name] = r;
  }
}

void validateEdit(const EditSpec& ed, const toml::table& e, const Scene& scene, const std::string& source) {
  const bool move = ed.op == EditOp::Move;
  if (ed.day > scene.days) fail(source, *e.get("day"), "edits.day", "day " + std::to_string(ed.day) + " is after the season's end");
  if (!move && !ed.depthM)
    throw InputError(ed.declaredAt + ": edits.depth_m: missing (op = \"" + enumName(ed.op) + "\" needs a depth in metres)");
  if (move && ed.to.empty()) throw InputError(ed.declaredAt + ": edits.to: missing (op = \"move\" needs the layer that receives)");
  if (!move && !ed.to.empty()) fail(source, *e.get("to"), "edits.to", "only op = \"move\" has a destination layer");
  if (move && ed.to == ed.layer) fail(source, *e.get("to"), "edits.to", "moves snow to the layer it takes it from");
}

void readEdits(Scene& scene, const toml::table& root, const std::string& source) {
  const toml::array* edits = root["edits"].as_array();
  if (!edits) return;
  for (auto&& element : *edits) {
    const toml::table& e = *element.as_table();
    requireKeys(e, {"day", "op", "layer"}, source, "edits");
    EditSpec ed;
    ed.declaredAt = where(source, e.source());
    applyBindings(ed, e, "edits", source, scene);
    validateEdit(ed, e, scene, source);
    scene.edits.push_back(ed);
  }
  std::stable_sort(scene.edits.begin(), scene.edits.end(), [](const EditSpec& a, const EditSpec& b) { return a.day < b.day; });
}

// An avalanche or skier event: at a point (grid or map metres) or in a mask, one of them.
void addPointEvent(Scene& scene, const EventSpec& ev, const toml::table& e, const std::string& source) {
  const bool skier = ev.type == EventType::Skier;
  const int given = static_cast<int>(ev.positionM.has_value()) + static_cast<int>(ev.mapPosition.has_value()) + static_cast<int>(ev.mask.has_value());
  if (given != 1)
    throw InputError(where(source, e.source()) + ": events: " + (skier ? "a skier" : "an avalanche") +
                     " needs position_m = [x, y], map_position = [easting, northing] or mask = ... (one of them)");
  Scene::AvalancheEvent a;
  a.day = ev.day;
  a.line = static_cast<int>(e.source().begin.line);
  a.mask = ev.mask;
  if (const auto& xy = ev.positionM ? ev.positionM : ev.mapPosition) a.xM = (*xy)[0], a.yM = (*xy)[1];
  a.mapCoordinates = ev.mapPosition.has_value();
  if (skier) {
    a.count = ev.count;
    scene.userSkiers.push_back(a);
    return;
  }
  if (e.contains("count")) fail(source, *e.get("count"), "events.count", "only skier events have a count");
  scene.userAvalanches.push_back(a);
}

void readEvents(Scene& scene, const toml::table& root, const std::string& source) {
  const toml::array* events = root["events"].as_array();
  if (!events) return;
  for (auto&& element : *events) {
    const toml::table& e = *element.as_table();
    requireKeys(e, {"type", "day"}, source, "events");
    EventSpec ev;
    applyBindings(ev, e, "events", source, scene);
    if (ev.day > scene.days)
      fail(source, *e.get("day"), "events.day", "day " + numberText(ev.day) + " is after the season's end (season.days = " + numberText(scene.days) + ")");
    if (ev.type != EventType::Snowfall) {
      addPointEvent(scene, ev, e, source);
      continue;
    }
    if (ev.mask) fail(source, *e.get("mask"), "events.mask", "only avalanche and skier events take a mask");
    if (!ev.durationDays) throw InputError(where(source, e.source()) + ": events.duration_days: missing");
    scene.userSnowfalls.push_back({ev.day, ev.day + *ev.durationDays});
  }
}

void readParameters(Scene& scene, const toml::table& root, const std::string& source) {
  if (const toml::table* params = root["parameters"].as_table())
    for (auto&& [key, node] : *params) scene.params.*(findParameter(std::string(key.str()))->member) = node.value<double>().value();
  // Ranges that depend on each other.
  const ModelParameters& p = scene.params;
  if (!(p.freezeTemperatureC < p.coolTemperatureC && p.coolTemperatureC < p.warmTemperatureC))
    throw InputError(source + ": parameters: need freeze_temperature_c < cool_temperature_c < warm_temperature_c");
}

// --- checks across keys, one section each

// Before anything is read: the terrain table and exactly one source.
void requireTerrainSource(const toml::table& root, const std::string& source) {
  const toml::table* terrain = root["terrain"].as_table();
  if (!terrain) throw InputError(source + ": terrain: missing [terrain] table (give terrain.file or terrain.builtin)");
  if (terrain->contains("file") == terrain->contains("builtin"))
    throw InputError(where(source, terrain->source()) + ": terrain: give exactly one of terrain.file and terrain.builtin");
}

void validateTerrain(Scene& scene, const toml::table& root, const std::string& source) {
  const toml::table& terrain = *root["terrain"].as_table();
  TerrainSource& src = scene.terrain;
  if (src.heightRangeM && (src.heightScaleM || src.heightOffsetM))
    fail(source, *terrain.get("height_range_m"), "terrain.height_range_m", "give either height_range_m or height_scale_m/height_offset_m, not both");
  if (src.resampleCellSizeM && src.resampleSize)
    fail(source, *terrain.get("resample_size"), "terrain.resample_size", "give either resample_size or resample_cell_size_m, not both");
  if (!src.builtin) {
    const toml::node& fileNode = *terrain.get("file");
    for (const char* builtinOnly : {"size", "seed", "min_altitude_m", "max_altitude_m"})
      if (terrain.contains(builtinOnly)) fail(source, *terrain.get(builtinOnly), std::string("terrain.") + builtinOnly, "only applies to terrain.builtin");
    std::error_code ec;
    if (!fs::exists(src.file, ec)) fail(source, fileNode, "terrain.file", "terrain file '" + src.file + "' does not exist");
    if (fs::is_directory(src.file, ec)) fail(source, fileNode, "terrain.file", "'" + src.file + "' is a folder, not a terrain file");
    return;
  }
  DefaultTerrainOptions& o = src.builtinOptions;
  o.cellSizeM = src.cellSizeM.value_or(o.cellSizeM);
  if (!(o.maxAltitudeM > o.minAltitudeM))
    throw InputError(where(source, terrain.source()) + ": terrain.max_altitude_m: must be above terrain.min_altitude_m");
}

// [outputs.tiles]: a convention and a size it allows.
void validateTiles(const Scene& scene, const toml::table& root, const std::string& source) {
  const toml::table* t = root["outputs"]["tiles"].as_table();
  if (!t) return;
  const OutputTiles& tiles = scene.outputs.tiles;
  if (!t->contains("convention")) throw InputError(where(source, t->source()) + ": outputs.tiles: needs convention = \"unreal\", \"unity\" or \"grid\"");
  if (!t->contains("size_px")) throw InputError(where(source, t->source()) + ": outputs.tiles: needs size_px");
  const std::vector<int> allowed = allowedTileSizes(tiles.convention);
  if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), tiles.sizePx) == allowed.end())
    fail(source, *t->get("size_px"), "outputs.tiles.size_px",
         std::to_string(tiles.sizePx) + " is not a " + enumName(tiles.convention) + " tile size (allowed: " + tileSizeList(tiles.convention) + ")");
  if (t->contains("overlap_px")) {
    if (tiles.convention != TileConvention::Grid)
      fail(source, *t->get("overlap_px"), "outputs.tiles.overlap_px", std::string(enumName(tiles.convention)) + " tiles always share one row and column");
    if (tiles.overlapPx >= tiles.sizePx) fail(source, *t->get("overlap_px"), "outputs.tiles.overlap_px", "must be less than size_px");
  }
  // Unreal's and Unity's tiled imports take whole tiles: n tiles sharing their edges cover n (size - 1) + 1 pixels.
  if (tiles.resizeWidth > 0 && !allowed.empty()) {
    const int step = tiles.sizePx - 1;
    for (int side : {tiles.resizeWidth, tiles.resizeHeight})
      if (side < tiles.sizePx || (side - 1) % step != 0) {
        std::string sizes;
        for (int n = 1; n <= 4; ++n) sizes += std::to_string(n * step + 1) + ", ";
        fail(source, *t->get("resize"), "outputs.tiles.resize",
             std::to_string(side) + " pixels is not a whole number of " + enumName(tiles.convention) + " tiles of " + std::to_string(tiles.sizePx) +
                 " (allowed: " + sizes + "... n x " + std::to_string(step) + " + 1)");
      }
  }
}

// A frame's files are tagged with its day rounded to a whole day (frames/STEM.DDDD): two frame
// days with one tag would write the same files.
void validateOutputs(const Scene& scene, const toml::table& root, const std::string& source) {
  validateTiles(scene, root, source);
  const toml::array* frames = root["outputs"]["frames_days"].as_array();
  if (!frames) return;
  for (size_t i = 0; i < frames->size(); ++i) {
    const toml::node& e = (*frames)[i];
    const double day = e.value<double>().value();
    if (day > scene.days) fail(source, e, "outputs.frames_days", "day " + std::to_string(day) + " is after the season's end");
    for (size_t j = 0; j < i; ++j) {
      const double other = (*frames)[j].value<double>().value();
      if (std::lround(other) == std::lround(day))
        fail(source, e, "outputs.frames_days",
             "day " + numberText(day) + " and day " + numberText(other) + " would both write the frame files of day " +
                 std::to_string(std::lround(day)) + " (frames are named by the whole day)");
    }
  }
}

bool wantsLayer(const Scene& scene, const std::string& layer) {
  return std::find(scene.outputs.layers.begin(), scene.outputs.layers.end(), layer) != scene.outputs.layers.end();
}

void validateBedforms(Scene& scene, const toml::table& root, const std::string& source) {
  if (const toml::table* bt = root["bedforms"].as_table()) {
    if (!bt->contains("enabled")) scene.bedforms.enabled = true;  // the table alone turns the model on
    if (scene.bedforms.enabled && scene.mode == SceneMode::Occlusion)
      throw InputError(source + ": bedforms: mode = \"occlusion\" has no season to move snow in");
  }
  if (!scene.bedforms.enabled && wantsLayer(scene, "bedform_cohesion"))
    fail(source, *root["outputs"]["layers"].node(), "outputs.layers", "'bedform_cohesion' needs [bedforms]");
}

void validateOcclusion(const Scene& scene, const toml::table& root, const std::string& source) {
  const auto& day = scene.occlusion.day;
  if (day && *day > scene.days)
    fail(source, *root["occlusion"]["day"].node(), "occlusion.day", "day " + std::to_string(*day) + " is after the season's end");
}

void validateMeshSnow(Scene& scene, const toml::table& root, const std::string& source) {
  const bool given = root["mesh_snow"].node() != nullptr;
  scene.meshSnow.onOccluders = given && scene.mode == SceneMode::Season;
  if (given && scene.mode == SceneMode::Occlusion)
    throw InputError(source + ": mesh_snow: mode = \"occlusion\" does not use it (mode = \"mesh\", or a season with [[occluders]])");
  if (scene.meshSnow.onOccluders && scene.occluders.empty())
    throw InputError(source + ": mesh_snow: in a season it puts snow on the [[occluders]] meshes, and the scene has none");
  if (scene.meshSnow.onOccluders && scene.outputs.meshes.empty())
    throw InputError(source + ": mesh_snow: the occluders' snow bodies need outputs.meshes (the formats to write them in)");
}

// mode = "mesh": snow on the mesh itself (Fearing): no grid, no season; the snow body is the output.
void validateMeshMode(const Scene& scene, const toml::table& root, const std::string& source) {
  const OutputRequest& out = scene.outputs;
  if (scene.terrain.builtin) throw InputError(source + ": mode = \"mesh\" needs terrain.file to name a mesh (.obj, .ply, .glb, .gltf, .fbx)");
  if (root["outputs"]["layers"].node() || !out.encodings.empty() || out.multichannelExr || out.displacementWidth > 0 || !out.frameDays.empty() ||
      out.avalancheMaps || out.resizeWidth > 0 || root["outputs"]["tiles"].node() || root["outputs"]["ranges"].node())
    throw InputError(source + ": outputs: mode = \"mesh\" writes the snow body only (outputs.meshes, outputs.vdb); grid layers, "
                     "encodings, displacement maps, frames, resize, tiles and ranges need a height field");
  if (root["outputs"]["mesh_parts"].node()) throw InputError(source + ": outputs.mesh_parts: mode = \"mesh\" writes the snow body (snow_body.EXT)");
  if (out.meshes.empty() && !out.vdb) throw InputError(source + ": outputs: mode = \"mesh\" needs outputs.meshes or outputs.vdb = true");
  if (!scene.userAvalanches.empty() || !scene.userSkiers.empty() || !scene.edits.empty() || scene.bedforms.enabled)
    throw InputError(source + ": mode = \"mesh\" has no season: no events, edits or bedforms");
}

// mode = "occlusion" has no season: the outputs and art direction only a season makes are errors,
// not silently empty files.
void validateOcclusionMode(const Scene& scene, const toml::table& root, const std::string& source) {
  for (const auto& layer : scene.outputs.layers)
    if (!(findLayer(layer)->modes & kOcclusionMode))
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
}

void validateMode(const Scene& scene, const toml::table& root, const std::string& source) {
  if (scene.mode == SceneMode::Mesh) validateMeshMode(scene, root, source);
  if (scene.mode == SceneMode::Occlusion) {
    validateOcclusionMode(scene, root, source);
    return;
  }
  for (const auto& layer : scene.outputs.layers)
    if (!(findLayer(layer)->modes & kSeasonMode))
      fail(source, *root["outputs"]["layers"].node(), "outputs.layers", "'" + layer + "' needs mode = \"occlusion\"");
}

// The keys bound to the Scene go in first (each checks only its own value); the masks before
// them, since rasters (initial_snow, multipliers, bedforms.mask) may name one; then the arrays of
// tables and the checks across keys.
// Where each key was given (the tables' keys, not those inside arrays of tables), for checks
// made after loading (the memory model's).
void recordKeyLocations(const toml::table& table, const std::string& prefix, const std::string& source, Scene& scene) {
  for (auto&& [key, node] : table) {
    const std::string path = prefix.empty() ? std::string(key.str()) : prefix + "." + std::string(key.str());
    scene.keyLocations[path] = where(source, node.source());
    if (const toml::table* t = node.as_table()) recordKeyLocations(*t, path, source, scene);
  }
}

Scene buildScene(const toml::table& root, const std::string& source, const std::string& baseDir) {
  Scene scene;
  scene.sourceName = source;
  scene.baseDir = baseDir;
  requireTerrainSource(root, source);
  readMasks(scene, root, source);
  applyBindings(scene, root, "", source, scene);
  validateTerrain(scene, root, source);
  readOccluders(scene, root, source);
  readWeather(scene, root, source);
  readEdits(scene, root, source);
  readEvents(scene, root, source);
  readParameters(scene, root, source);
  // Frames of each avalanche's motion come with its maps (the key's text): one switch for the
  // season's peak records, the runner and the writer.
  if (scene.outputs.avalancheFrameIntervalS > 0) scene.outputs.avalancheMaps = true;
  validateOutputs(scene, root, source);
  validateBedforms(scene, root, source);
  validateOcclusion(scene, root, source);
  validateMeshSnow(scene, root, source);
  validateMode(scene, root, source);
  recordKeyLocations(root, "", source, scene);

  std::ostringstream canonical;
  canonical << root;
  scene.canonicalToml = canonical.str();
  return scene;
}

// --terrain FILE: a [terrain] table of its own, so that no key the scene wrote for its terrain
// (a builtin's size and cell size, a heightmap's mapping) is applied to another file.
void replaceTerrainTable(toml::table& root, const std::string& terrainFile) {
  toml::table terrain;
  terrain.insert("file", fs::absolute(terrainFile).lexically_normal().string());
  root.insert_or_assign("terrain", std::move(terrain));
}

Scene parseAndBuild(toml::table root, const std::string& source, const std::string& baseDir,
                    const std::vector<std::string>& overrides, const std::optional<std::string>& terrainFile) {
  if (terrainFile) replaceTerrainTable(root, *terrainFile);
  for (const auto& o : overrides) applyOverride(root, o);
  Validator(source).checkTable(root, "");
  Scene scene = buildScene(root, source, baseDir);
  if (terrainFile) scene.terrain.declaredAt = "--terrain";
  return scene;
}

[[noreturn]] void rethrowParseError(const toml::parse_error& e, const std::string& source) {
  std::ostringstream o;
  o << source << ":" << e.source().begin.line << ": TOML syntax error: " << e.description();
  throw InputError(o.str());
}

}  // namespace

Scene loadSceneText(const std::string& text, const std::string& sourceName, const std::string& baseDir,
                    const std::vector<std::string>& overrides, const std::optional<std::string>& terrainFile) {
  toml::table root;
  try {
    root = toml::parse(text, std::string_view(sourceName));
  } catch (const toml::parse_error& e) {
    rethrowParseError(e, sourceName);
  }
  return parseAndBuild(std::move(root), sourceName, baseDir, overrides, terrainFile);
}

Scene loadSceneFile(const std::string& path, const std::vector<std::string>& overrides, const std::optional<std::string>& terrainFile) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": scene file does not exist");
  if (fs::is_directory(path, ec)) throw InputError(path + ": is a folder, not a scene file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the scene file for reading");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string base = fs::path(path).parent_path().string();
  return loadSceneText(buffer.str(), path, base.empty() ? "." : base, overrides, terrainFile);
}

Scene loadScene(const std::string& pathOrPreset, const std::vector<std::string>& overrides, const std::optional<std::string>& terrainFile) {
  const std::string prefix = "preset:";
  if (pathOrPreset.rfind(prefix, 0) == 0) {
    const std::string name = pathOrPreset.substr(prefix.size());
    if (name != "default") throw InputError(pathOrPreset + ": unknown preset (available: preset:default)");
    return loadSceneText(presets::kDefault, pathOrPreset, fs::current_path().string(), overrides, terrainFile);
  }
  return loadSceneFile(pathOrPreset, overrides, terrainFile);
}

}  // namespace snow
