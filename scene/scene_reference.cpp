// The scene reference: every key of the schema and every model parameter, with type, range or
// choices, default, unit and doc, as plain text or Markdown. The defaults are the bindings' values
// in a default-constructed Scene (or array element), so they cannot drift from the loader.
#include "scene_reference.h"

#include <cmath>
#include <sstream>

#include "scene/layers.h"
#include "scene_schema.h"

namespace snow {
namespace {

const char* typeName(Kind k) {
  switch (k) {
    case Kind::Table: return "table";
    case Kind::TableArray: return "array of tables";
    case Kind::String: return "string";
    case Kind::Number: return "number";
    case Kind::Integer: return "integer";
    case Kind::Bool: return "bool";
    case Kind::Date: return "date";
    case Kind::NumberArray: return "array of numbers";
    case Kind::StringArray: return "array of strings";
    case Kind::Any: return "raster";
  }
  return "?";
}

// [min, max], as the range errors print it but to 15 digits.
std::string rangeText(double minValue, double maxValue) {
  if (!std::isfinite(minValue) && !std::isfinite(maxValue)) return "";
  // Appended, not "[" + ...: GCC 12 warns (-Wrestrict, a false positive) on const char* + string&&.
  std::string text = "[";
  return text.append(numberText(minValue)).append(", ").append(numberText(maxValue)).append("]");
}

std::string ruleRange(const Rule& r) {
  if (!r.choices.empty()) {
    std::string list;
    for (const auto& c : r.choices) list += (list.empty() ? "" : ", ") + c;
    return list;
  }
  return rangeText(r.minValue, r.maxValue);
}

template <class T>
std::string defaultOf(const Bind<T>& bind) {
  return bind.show(T{});
}
std::string defaultOf(const std::monostate&) { return ""; }

std::string ruleDefault(const Rule& r) {
  if (!r.defaultText.empty()) return r.defaultText;
  return std::visit([](const auto& bind) { return defaultOf(bind); }, r.bind);
}

std::string sectionOf(const std::string& path) {
  const size_t dot = path.find('.');
  if (dot != std::string::npos) return path.substr(0, dot);
  for (const auto& s : sceneSections())
    if (s.key == path) return path;  // the table's own rule
  return "";
}

const char* kIntro =
    "TOML. Unknown keys, wrong types and out-of-range values are errors naming the file, the line and the key (with a suggestion for "
    "misspelt keys). Relative paths are relative to the scene file. `presets/default.toml` is a complete example; "
    "`presets/art_direction.toml` adds masks, edits and masked events; `presets/bedforms.toml` grows snow barchans on a tileable window. "
    "Any key can be overridden from the command line by its dotted path: `snowbake bake SCENE --set season.days=30`.";
const char* kRasterNote =
    "A raster (type `raster`) is a mask name from `[masks]`, a file path (with its extension), or a table "
    "`{ file = ..., values = [v0, v1], range = [r0, r1], invert = false }`.";
const char* kParametersIntro =
    "Every constant of the paper's Table 2 in world units, with the paper's defaults (k_w and k_c are kept as printed, 10^4 m/day, "
    "which makes the stability change all-or-nothing within a step: see docs/models/season.md), plus the event frequencies of section 3.2/7.4. Powder diffusion's k_m is "
    "turned into a creep speed in world units, k_m x `diffusion_length_m` metres a day per unit of slope above the rest slope "
    "(200 m/day by default), so a 2 m and a 10 m run move the same distance of snow per day. Each is a number under `[parameters]`.";

std::string cell(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}
std::string code(const std::string& s) { return s.empty() ? "" : "`" + s + "`"; }

const char* kLayersIntro =
    "What `outputs.layers` names, from the layer table (scene/layers.cpp). A float layer is written as a float image "
    "(`outputs.format`), in each of `outputs.encodings` and as a channel of the multi-channel EXR; a preview is an RGB PNG. "
    "NODATA cells are 0 in every layer (`valid_mask` says which they are).";

std::string layerModes(const LayerInfo& l) {
  if ((l.modes & kGridModes) == kGridModes) return "season, occlusion";
  return l.modes & kSeasonMode ? "season" : "occlusion";
}

}  // namespace

std::vector<SceneKeyDoc> sceneKeyDocs() {
  std::vector<SceneKeyDoc> docs;
  for (const auto& section : sceneSections())
    for (const Rule& r : sceneRules())
      if (sectionOf(r.path) == section.key && r.path != "parameters")
        docs.push_back({section.key, r.path, typeName(r.kind), ruleRange(r), ruleDefault(r), r.unit, r.doc});
  const Rule& params = *findRule("parameters");
  docs.push_back({"parameters", params.path, typeName(params.kind), "", "", "", params.doc});
  const ModelParameters defaults;
  for (const auto& p : parameterTable())
    docs.push_back({"parameters", std::string("parameters.") + p.key, "number", rangeText(p.minValue, p.maxValue), numberText(defaults.*p.member),
                    p.unit, p.description});
  return docs;
}

std::string sceneValueText(const Scene& scene, const std::string& path) {
  const Rule* r = findRule(path);
  if (!r) return "";
  const auto* bind = std::get_if<Bind<Scene>>(&r->bind);
  return bind ? bind->show(scene) : "";
}

std::string sceneReferenceText() {
  std::ostringstream o;
  o << "Scene file reference (generated from the schema; snowbake help scene --markdown prints it as Markdown)\n\n"
    << kIntro << "\n" << kRasterNote << "\n";
  std::string section = "-";
  for (const SceneKeyDoc& d : sceneKeyDocs()) {
    if (d.section != section) {
      section = d.section;
      o << "\n" << (section.empty() ? "top level" : section == "parameters" ? "[parameters] (model parameters)" : "[" + section + "]") << "\n";
      if (section == "parameters") o << kParametersIntro << "\n";
    }
    o << "  " << d.path << " (" << d.type;
    if (!d.range.empty()) o << (d.range[0] == '[' ? " in " : ": ") << d.range;
    if (!d.unit.empty()) o << ", " << d.unit;
    if (!d.defaultValue.empty()) o << (d.defaultValue == "required" ? "; required" : "; default " + d.defaultValue);
    o << ")\n      " << d.doc << "\n";
  }
  o << "\noutput layers (outputs.layers)\n" << kLayersIntro << "\n";
  for (const LayerInfo& l : layerTable())
    o << "  " << l.name << " (" << (l.kind == LayerKind::Preview ? "RGB preview" : "float") << ", " << l.unit << "; " << layerModes(l)
      << ")\n      " << l.content << "\n";
  return o.str();
}

std::string sceneReferenceMarkdown() {
  std::ostringstream o;
  o << "<!-- Generated by `snowbake help scene --markdown > docs/scene.md`; edit scene/scene_schema.cpp and "
       "core/parameters.cpp instead. -->\n"
    << "# Scene files\n\n" << kIntro << "\n\n" << kRasterNote << "\n";
  std::string section = "-";
  for (const SceneKeyDoc& d : sceneKeyDocs()) {
    if (d.section != section) {
      section = d.section;
      if (section == "parameters") {
        o << "\n## Model parameters (`[parameters]`)\n\n" << kParametersIntro << "\n\n"
          << "| key | default | unit | range | meaning |\n|---|---|---|---|---|\n";
      } else {
        for (const auto& s : sceneSections())
          if (s.key == section) o << "\n## " << (section.empty() ? s.title : "`" + s.title + "`") << "\n\n";
        o << "| key | type | range or choices | default | unit | meaning |\n|---|---|---|---|---|---|\n";
      }
    }
    if (section == "parameters")
      o << "| " << code(d.path.rfind("parameters.", 0) == 0 ? d.path.substr(11) : d.path) << " | " << cell(d.defaultValue) << " | " << cell(d.unit) << " | " << cell(d.range) << " | "
        << cell(d.doc) << " |\n";
    else
      o << "| " << code(d.path) << " | " << d.type << " | " << cell(d.range) << " | " << cell(d.defaultValue) << " | " << cell(d.unit) << " | "
        << cell(d.doc) << " |\n";
  }
  o << "\n## Output layers (`outputs.layers`)\n\n" << kLayersIntro << "\n\n"
    << "| layer | kind | unit | modes | content |\n|---|---|---|---|---|\n";
  for (const LayerInfo& l : layerTable())
    o << "| " << code(l.name) << " | " << (l.kind == LayerKind::Preview ? "RGB preview" : "float") << " | " << l.unit << " | "
      << layerModes(l) << " | " << cell(l.content) << " |\n";
  return o.str();
}

}  // namespace snow
