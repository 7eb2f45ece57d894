#include <gtest/gtest.h>

#include <vector>

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
