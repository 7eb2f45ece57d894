#include "scene.h"

namespace snow {

int Scene::startDayOfYear() const {
  static const int cumulative[12] = {0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334};
  const bool leap = (startYear % 4 == 0 && startYear % 100 != 0) || startYear % 400 == 0;
  return cumulative[startMonth - 1] + startDay + (leap && startMonth > 2 ? 1 : 0);
}

std::string Scene::keyLocation(const std::string& dottedKey) const {
  const auto it = keyLocations.find(dottedKey);
  return it != keyLocations.end() ? it->second : sourceName;
}

}  // namespace snow
