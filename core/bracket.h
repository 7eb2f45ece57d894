// The two samples around a time in a sorted list and the weight of the later one: the linear
// interpolation shared by the weather keyframes, the wind fields and the exposure days. Before
// the first sample or after the last, both indices are that sample (held constant).
#pragma once
#include <cstddef>

namespace snow {

struct Bracket {
  size_t first = 0, second = 0;
  double weight = 0.0;  // of `second`
};

// `dayOf(i)` gives the time of sample i (non-decreasing); count > 0.
template <class DayOf>
Bracket bracketOf(size_t count, double day, const DayOf& dayOf) {
  if (day <= dayOf(0)) return {0, 0, 0.0};
  if (day >= dayOf(count - 1)) return {count - 1, count - 1, 0.0};
  for (size_t i = 1; i < count; ++i)
    if (day <= dayOf(i)) {
      const double d0 = dayOf(i - 1), d1 = dayOf(i);
      return {i - 1, i, d1 > d0 ? (day - d0) / (d1 - d0) : 1.0};
    }
  return {count - 1, count - 1, 0.0};
}

}  // namespace snow
