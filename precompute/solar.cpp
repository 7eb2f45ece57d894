#include "solar.h"

#include <algorithm>
#include <cmath>

#include "core/util.h"

namespace snow {

namespace {
constexpr double kDeg = kPi / 180.0;
}  // namespace

SunPosition sunPosition(double latitudeDeg, double doy, double solarHour) {
  // NOAA: fractional year (radians), declination series.
  const double gamma = 2.0 * kPi / 365.0 * (doy - 1.0 + (solarHour - 12.0) / 24.0);
  const double decl = 0.006918 - 0.399912 * std::cos(gamma) + 0.070257 * std::sin(gamma) - 0.006758 * std::cos(2 * gamma) +
                      0.000907 * std::sin(2 * gamma) - 0.002697 * std::cos(3 * gamma) + 0.00148 * std::sin(3 * gamma);
  const double hourAngle = (solarHour - 12.0) * 15.0 * kDeg;  // negative in the morning
  const double lat = latitudeDeg * kDeg;
  const double cosZenith = std::clamp(std::sin(lat) * std::sin(decl) + std::cos(lat) * std::cos(decl) * std::cos(hourAngle), -1.0, 1.0);
  const double zenith = std::acos(cosZenith);
  SunPosition s;
  s.declinationDeg = decl / kDeg;
  s.elevationDeg = 90.0 - zenith / kDeg;
  // Direction from the local east/north/up components (exact, no azimuth-quadrant formulas).
  const double east = -std::cos(decl) * std::sin(hourAngle);
  const double north = std::cos(lat) * std::sin(decl) - std::sin(lat) * std::cos(decl) * std::cos(hourAngle);
  const double up = cosZenith;
  const double norm = std::sqrt(east * east + north * north + up * up);
  s.direction[0] = east / norm;
  s.direction[1] = north / norm;
  s.direction[2] = up / norm;
  s.azimuthDeg = std::fmod(std::atan2(east, north) / kDeg + 360.0, 360.0);
  return s;
}

int dayOfYear(int year, int month, int day) {
  static const int cumulative[12] = {0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334};
  const bool leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
  return cumulative[month - 1] + day + (leap && month > 2 ? 1 : 0);
}

}  // namespace snow
