// The scene file's schema: one rule per key with its kind, range or choices, unit, one-line doc
// and its binding (where the value goes, and how the reference prints a default). The loader
// (scene_file.cpp) validates and applies it; the reference (scene_reference.cpp) prints it.
// Internal to precompute/ (it needs toml++).
#pragma once
#include <toml++/toml.h>

#include <array>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "scene.h"

namespace snow {

// Any: a value of several shapes (a raster reference: a string or a table), checked where it is read.
enum class Kind { Table, TableArray, String, Number, Integer, Bool, Date, NumberArray, StringArray, Any };
const char* kindName(Kind k);

// What a setter sees besides the value: the source for messages, the key, and the scene built so
// far (its masks and base folder, for raster references).
struct BindContext {
  const std::string& source;
  const std::string& path;
  const Scene& scene;
};

// One [[events]] entry as written; readEvents turns it into a snowfall, an avalanche or a skier.
struct EventSpec {
  EventType type = EventType::Snowfall;
  double day = 0;
  int count = 1;
  std::optional<std::array<double, 2>> positionM, mapPosition;
  std::optional<double> durationDays;
  std::optional<RasterRef> mask;
};

// Where a key's value goes in an object of type T (the Scene, or one element of an array of
// tables), and how the object's value of it is printed.
template <class T>
struct Bind {
  std::function<void(T&, const toml::node&, const BindContext&)> set;
  std::function<std::string(const T&)> show;
};
using Binding = std::variant<std::monostate, Bind<Scene>, Bind<OccluderSource>, Bind<WeatherKeyframe>, Bind<SnowfallPeriod>,
                             Bind<EventSpec>, Bind<EditSpec>>;

struct Rule {
  std::string path;
  Kind kind;
  double minValue = -std::numeric_limits<double>::infinity();
  double maxValue = std::numeric_limits<double>::infinity();
  std::vector<std::string> choices = {};
  std::string unit = {};
  std::string doc = {};
  Binding bind = {};
  std::string defaultText = {};  // printed instead of the binding's default (a default that depends on other keys)
};

// The names outputs.layers takes (scene/layers.h's table).
extern const std::vector<std::string> kLayerChoices;

const std::vector<Rule>& sceneRules();
// The rule of a dotted path ([masks.NAME] keys match masks.*), or null.
const Rule* findRule(std::string path);

// The reference's sections, in order: the top-level key ("" for keys with no table) and a title;
// [parameters] comes last, from the parameter table.
struct SceneSection {
  std::string key;
  std::string title;
};
const std::vector<SceneSection>& sceneSections();

std::string where(const std::string& fallbackSource, const toml::source_region& src);
[[noreturn]] void fail(const std::string& source, const toml::node& node, const std::string& key, const std::string& what);

// Art direction: a raster reference (a [masks] name, a file path, or a table {file, values,
// range, invert}), resolved against the scene's masks and base folder.
RasterRef rasterRef(const toml::node& node, const std::string& source, const Scene& scene, const std::string& key);
RasterRef rasterFromTable(const toml::table& t, const std::string& source, const std::string& baseDir, const std::string& key);
std::optional<toml::date> parseDate(const std::string& s);
// The Gregorian calendar's days in a month (0 for no month), and whether a date is one of them.
int daysInMonth(int year, int month);
bool isCalendarDate(const toml::date& d);
// A number as the reference prints it (15 significant digits: ranges and defaults exactly).
std::string numberText(double v);
// `file` against the scene file's folder when relative, normalised.
std::string resolvePath(const std::string& file, const std::string& baseDir);

}  // namespace snow
