// Numbers as the logs and the manifest's descriptions print them.
#pragma once
#include <iomanip>
#include <sstream>
#include <string>

namespace snow {

// `v` with `digits` digits after the point.
inline std::string fixed(double v, int digits) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << v;
  return o.str();
}

}  // namespace snow
