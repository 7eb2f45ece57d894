// Solar geometry (NOAA's general solar position equations, in local solar time): the sun's
// direction for a latitude, a day of the year and an hour, so that exposure follows the season.
#pragma once

namespace snow {

struct SunPosition {
  double elevationDeg = 0.0;   // above the horizon
  double azimuthDeg = 0.0;     // clockwise from north
  double declinationDeg = 0.0;
  double direction[3] = {0, 0, 0};  // unit vector toward the sun: x east, y north, z up
};

// `solarHour` is local solar time (12 = solar noon); dayOfYear 1..366.
SunPosition sunPosition(double latitudeDeg, double dayOfYear, double solarHour);

// Day of the year (1..366) of a date.
int dayOfYear(int year, int month, int day);

}  // namespace snow
