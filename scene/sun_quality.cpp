#include "sun_quality.h"

#include "core/errors.h"

namespace snow {

const std::vector<SunQuality>& sunQualities() {
  static const std::vector<SunQuality> table{
      {"draft", 8, 6, 1.0, 30.0, 8, 4, 200.0, 64},
      {"production", 16, 9, 0.5, 10.0, 16, 8, 400.0, 256},
      {"reference", 64, 12, 0.125, 5.0, 32, 16, 800.0, 1024},
  };
  return table;
}

const std::vector<std::string>& sunQualityNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const SunQuality& q : sunQualities()) n.push_back(q.name);
    return n;
  }();
  return names;
}

SunQuality sunQuality(const std::string& name) {
  for (const SunQuality& q : sunQualities())
    if (q.name == name) return q;
  throw InputError("sun quality '" + name + "' is not one of: draft, production, reference");
}

}  // namespace snow
