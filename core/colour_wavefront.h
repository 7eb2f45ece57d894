// The five colour passes of the cross tiling (tiling.h) in one sweep of the rows: colour k runs on
// row y two rows behind colour k - 1 (a wavefront; at each step the colours in turn), so it comes
// after colour k - 1 on rows y - 2 .. y + 2 and before colour k + 1 there. That orders every pair of overlapping crosses
// (kColourReachRows) as five whole passes do: the same bytes, with each row's cache lines
// fetched once instead of five times. Bands of rows run side by side, each leaving colour k's
// 2k rows at an inner edge to the seam there; the seams then run their colours in turn, side by
// side (seams lie a band apart, farther than their rows reach).
#pragma once
#include <algorithm>

#include "tiling.h"

namespace snow {

// A band's fewest rows: more than the seams' rows on both sides of it and their reach.
constexpr int kColourSeamRows = 2 * kColourReachRows * (kColours - 1);
constexpr int kColourMinBandRows = 2 * kColourSeamRows + kColourReachRows + 1;

// Calls row(y, colour) once for each row y in [0, height) and colour in [0, kColours), each after
// the calls of lower colours on rows within kColourReachRows of it and before those of higher
// colours there; bands of about `bandRows` rows (kColourMinBandRows at least). forEach(n, task)
// runs task(0) .. task(n - 1), in any order or side by side.
template <class ForEach, class Row>
void colourWavefront(int height, int bandRows, const ForEach& forEach, const Row& row) {
  if (height <= 0) return;
  const int bands = std::max(1, height / std::max(bandRows, kColourMinBandRows));
  auto start = [&](int b) { return static_cast<int>(static_cast<long long>(height) * b / bands); };
  constexpr int lag = kColourReachRows;
  forEach(bands, [&](int b) {
    const int b0 = start(b), b1 = start(b + 1);
    for (int t = 0; t < b1 - b0 + lag * (kColours - 1); ++t)
      for (int k = 0; k < kColours; ++k) {
        const int y = b0 + t - lag * k;
        const int lo = b0 + (b > 0 ? kColourReachRows * k : 0), hi = b1 - (b + 1 < bands ? kColourReachRows * k : 0);
        if (y >= lo && y < hi) row(y, k);
      }
  });
  if (bands > 1)
    forEach(bands - 1, [&](int seam) {
      const int s = start(seam + 1);
      for (int k = 1; k < kColours; ++k)
        for (int y = s - kColourReachRows * k; y < s + kColourReachRows * k; ++y) row(y, k);
    });
}

}  // namespace snow
