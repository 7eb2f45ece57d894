#include "decomposition.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace snow::dist {

namespace {
int cut(int extent, int parts, int k) { return static_cast<int>(static_cast<int64_t>(extent) * k / parts); }
}  // namespace

CellRect Decomposition::owned(int rank) const {
  const int c = columnOf(rank), r = rowOf(rank);
  if (!columnStarts.empty()) return CellRect{columnStarts[c], rowStarts[r], columnStarts[c + 1], rowStarts[r + 1]};
  return CellRect{cut(width, columns, c), cut(height, rows, r), cut(width, columns, c + 1), cut(height, rows, r + 1)};
}

CellRect Decomposition::local(int rank) const {
  const CellRect o = owned(rank);
  return CellRect{std::max(0, o.x0 - halo), std::max(0, o.y0 - halo), std::min(width, o.x1 + halo), std::min(height, o.y1 + halo)};
}

Decomposition Decomposition::choose(int ranks, int width, int height, int halo) {
  if (ranks < 1) throw std::invalid_argument("a decomposition needs at least one rank, not " + std::to_string(ranks));
  const int side = std::max(1, halo);
  Decomposition best;
  int64_t bestCut = std::numeric_limits<int64_t>::max();
  for (int columns = 1; columns <= ranks; ++columns) {
    if (ranks % columns) continue;
    const int rows = ranks / columns;
    // The smallest subdomain of a balanced split is floor(extent / parts) a side.
    if (width / columns < side || height / rows < side) continue;
    const int64_t cutCells = static_cast<int64_t>(columns - 1) * height + static_cast<int64_t>(rows - 1) * width;
    if (cutCells < bestCut) bestCut = cutCells, best = Decomposition{width, height, columns, rows, halo, {}, {}};
  }
  if (bestCut == std::numeric_limits<int64_t>::max())
    throw std::invalid_argument(std::to_string(ranks) + " ranks cannot split a " + std::to_string(width) + " x " +
                                std::to_string(height) + " grid into subdomains of at least " + std::to_string(side) +
                                " cells a side (the halo); run fewer ranks");
  return best;
}

std::optional<Decomposition> Decomposition::chooseOnTiles(int ranks, int width, int height, int halo, int step, int tileColumns,
                                                        int tileRows) {
  if (ranks < 1 || step < 1) return std::nullopt;
  const int side = std::max(1, halo);
  // `parts` bands of whole tiles, as even in tiles as the balanced split; empty where one is thinner than `side`.
  auto starts = [&](int extent, int tiles, int parts) {
    std::vector<int> s;
    if (parts > tiles) return s;
    for (int k = 0; k < parts; ++k) s.push_back(step * cut(tiles, parts, k));
    s.push_back(extent);
    for (size_t k = 0; k + 1 < s.size(); ++k)
      if (s[k + 1] - s[k] < side) return std::vector<int>();
    return s;
  };
  std::optional<Decomposition> best;
  int64_t bestCut = std::numeric_limits<int64_t>::max();
  for (int columns = 1; columns <= ranks; ++columns) {
    if (ranks % columns) continue;
    const int rows = ranks / columns;
    std::vector<int> xs = starts(width, tileColumns, columns), ys = starts(height, tileRows, rows);
    if (xs.empty() || ys.empty()) continue;
    const int64_t cutCells = static_cast<int64_t>(columns - 1) * height + static_cast<int64_t>(rows - 1) * width;
    if (cutCells >= bestCut) continue;
    bestCut = cutCells;
    best = Decomposition{width, height, columns, rows, halo, std::move(xs), std::move(ys)};
  }
  return best;
}

void copyCells(const CellRect& cells, const CellRect& fromGrid, const void* from, const CellRect& toGrid, void* to, size_t elementBytes) {
  const size_t rowBytes = static_cast<size_t>(cells.width()) * elementBytes;
  for (int y = cells.y0; y < cells.y1; ++y)
    std::memcpy(static_cast<char*>(to) + toGrid.offsetOf(cells.x0, y) * elementBytes,
                static_cast<const char*>(from) + fromGrid.offsetOf(cells.x0, y) * elementBytes, rowBytes);
}

HaloPlan haloPlan(const Decomposition& d, int self) {
  HaloPlan plan;
  const CellRect mine = d.owned(self), myLocal = d.local(self);
  for (int peer = 0; peer < d.ranks(); ++peer) {
    if (peer == self) continue;
    const CellRect send = mine.intersect(d.local(peer));
    if (!send.empty()) plan.sends.push_back({peer, send});
    const CellRect receive = d.owned(peer).intersect(myLocal);
    if (!receive.empty()) plan.receives.push_back({peer, receive});
  }
  return plan;
}

}  // namespace snow::dist
