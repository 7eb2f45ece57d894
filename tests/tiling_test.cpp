#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "core/colour_wavefront.h"
#include "core/serial_exec.h"
#include "core/tiling.h"

using namespace snow;

// §7.1: two cells of one colour never share a cell of their crosses (self + 4 neighbours).
TEST(CrossTiling, SameColourCrossesNeverOverlap) {
  const int w = 23, h = 19;
  const int dx[5] = {0, 1, -1, 0, 0}, dy[5] = {0, 0, 0, 1, -1};
  for (int colour = 0; colour < 5; ++colour) {
    std::vector<int> owner(w * h, -1);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (cellColour(x, y) != colour) continue;
        for (int k = 0; k < 5; ++k) {
          const int nx = x + dx[k], ny = y + dy[k];
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          ASSERT_EQ(owner[ny * w + nx], -1) << "colour " << colour << ": cell (" << nx << "," << ny << ") in two crosses";
          owner[ny * w + nx] = y * w + x;
        }
      }
  }
}

// forEachCellOfColour visits exactly the cells of that colour; the five passes cover each cell once.
TEST(CrossTiling, FiveColourPassesVisitEveryCellOnce) {
  const int w = 17, h = 13;
  std::vector<int> visits(w * h, 0);
  SerialExec exec;
  for (int colour = 0; colour < 5; ++colour)
    exec.forEachCellOfColour(w, h, colour, [&](int x, int y) {
      EXPECT_EQ(cellColour(x, y), colour);
      ++visits[y * w + x];
    });
  for (int v : visits) EXPECT_EQ(v, 1);
}

TEST(CrossTiling, MatchesThePaperFigure) {
  // The paper's §7.1 table, first row "5 1 2 3 4 5" read as colours 4 0 1 2 3 4 and each row
  // shifted by two: colour = (x + 2y) mod 5 up to a relabelling.
  EXPECT_EQ(cellColour(0, 0), 0);
  EXPECT_EQ(cellColour(1, 0), 1);
  EXPECT_EQ(cellColour(0, 1), 2);
  EXPECT_EQ(cellColour(3, 1), 0);
  EXPECT_EQ(firstColumnOfColour(1, 0), 3);
  EXPECT_EQ(firstColumnOfColour(0, 0), 0);
}

// colourWavefront (the TBB executor's colour passes): every row and colour once; every pair of
// rows within kColourReachRows in colour order, whatever order its bands and seams run in; and no
// two tasks that may run side by side touching such a pair of different colours.
TEST(CrossTiling, ColourWavefrontKeepsEveryOverlappingPairInColourOrder) {
  for (int height : {0, 1, 7, 35, 36, 71, 72, 200, 333}) {
    for (bool reversed : {false, true}) {
      const size_t n = static_cast<size_t>(height) * kColours;
      std::vector<int> when(n, -1), task(n, -1), phase(n, -1);
      int clock = 0, phases = 0, current = -1;
      auto forEach = [&](int count, const auto& run) {
        ++phases;
        for (int i = 0; i < count; ++i) {
          current = reversed ? count - 1 - i : i;
          run(current);
        }
      };
      colourWavefront(height, kColourMinBandRows, forEach, [&](int y, int colour) {
        ASSERT_TRUE(y >= 0 && y < height && colour >= 0 && colour < kColours) << y << " " << colour;
        const size_t i = static_cast<size_t>(y) * kColours + colour;
        ASSERT_EQ(when[i], -1) << "row " << y << " colour " << colour << " twice";
        when[i] = clock++, task[i] = current, phase[i] = phases;
      });
      ASSERT_EQ(clock, height * kColours) << "height " << height;
      for (int y = 0; y < height; ++y)
        for (int k = 0; k < kColours; ++k)
          for (int j = 0; j < kColours; ++j)
            for (int z = std::max(0, y - kColourReachRows); z <= std::min(height - 1, y + kColourReachRows); ++z) {
              if (j == k) continue;  // crosses of one colour never overlap
              const size_t a = static_cast<size_t>(y) * kColours + k, b = static_cast<size_t>(z) * kColours + j;
              if (k < j)
                ASSERT_LT(when[a], when[b]) << "height " << height << (reversed ? ", tasks reversed" : "") << ": colour " << k
                                            << " on row " << y << " after colour " << j << " on row " << z;
              ASSERT_FALSE(phase[a] == phase[b] && task[a] != task[b])
                  << "height " << height << ": rows " << y << " and " << z << " in two tasks side by side";
            }
    }
  }
}
