// The constants and the wall-clock timer that many files need, written once. kPi is a plain
// constexpr double, so host code and kernels compiled by nvcc read the same value.
#pragma once
#include <chrono>

namespace snow {

inline constexpr double kPi = 3.14159265358979323846;

// The clock of every printed or reported timing (monotonic: unaffected by clock changes).
using WallClock = std::chrono::steady_clock;
inline double elapsedSeconds(WallClock::time_point start) {
  return std::chrono::duration<double>(WallClock::now() - start).count();
}

}  // namespace snow
