// The 5-colour cross tiling of the paper's §7.1: colour(x, y) = (x + 2y) mod 5. The cross of a
// cell (itself and its four neighbours) never overlaps the cross of another cell of the same
// colour, so a transport kernel that writes only into its own cross can run all cells of one
// colour at once without races or atomics.
#pragma once
#include "hd.h"

namespace snow {

SNOW_HD SNOW_INLINE int cellColour(int x, int y) { return (x + 2 * y) % 5; }
// In row y the cells of colour c start at this column and repeat every 5.
SNOW_HD SNOW_INLINE int firstColumnOfColour(int y, int colour) { return ((colour - 2 * y) % 5 + 5) % 5; }

constexpr int kColours = 5;
// Two cells whose crosses overlap lie at most this many rows apart: an executor may run the
// colours' passes in any order that keeps every such pair in colour order (forEachCellInColourOrder).
constexpr int kColourReachRows = 2;

}  // namespace snow
