// The grid split among ranks for a distributed bake (docs/distributed.md): a 2-D process grid of
// rectangles, each rank's subdomain; its local grid, the subdomain widened by a halo; and the
// cells each rank sends to and receives from the others to refresh its halo.
#pragma once
#include <cstddef>
#include <optional>
#include <vector>

#include "core/grid_window.h"

namespace snow::dist {

using snow::CellRect;  // core/grid_window.h

struct Decomposition {
  int width = 0, height = 0;    // the whole grid, cells
  int columns = 1, rows = 1;    // the process grid; rank = row * columns + column
  int halo = 0;                 // cells of neighbours each local grid holds at least, each side
  // Where the subdomains' columns and rows start (columns + 1 and rows + 1 values, the last the
  // grid's extent) when chosen on tiles (chooseOnTiles); empty: the balanced splits.
  std::vector<int> columnStarts, rowStarts;

  int ranks() const { return columns * rows; }
  int columnOf(int rank) const { return rank % columns; }
  int rowOf(int rank) const { return rank / columns; }
  int rankAt(int column, int row) const { return row * columns + column; }
  // The cells `rank` owns: balanced splits, the first cut at width * column / columns (or at
  // columnStarts and rowStarts).
  CellRect owned(int rank) const;
  // Its local grid: `owned` widened by `halo` within the grid.
  CellRect local(int rank) const;

  // The process grid for `ranks` processes on a width × height grid: of the factorisations
  // columns × rows, the one whose cuts are shortest (the least halo to exchange), fewer columns on
  // a tie (rows are contiguous in memory). Throws std::invalid_argument, saying why, when no
  // factorisation gives every subdomain at least `halo` cells (and one) a side.
  static Decomposition choose(int ranks, int width, int height, int halo);
  // As choose, but every cut falls on the start of a tile of `tileColumns` x `tileRows` tiles
  // starting every `step` cells (the last reaching past the grid), each rank's subdomain a band
  // of whole tiles, so that a rank's local grid holds every cell of the tiles starting in it as
  // long as the tiles overlap by no more than the halo. nullopt where no factorisation gives
  // every subdomain a tile and `halo` cells a side.
  static std::optional<Decomposition> chooseOnTiles(int ranks, int width, int height, int halo, int step, int tileColumns, int tileRows);
};

// Copies `cells` (whole-grid coordinates, inside both) from a row-major grid of `fromGrid`'s cells
// to one of `toGrid`'s, `elementBytes` a cell: cutting, gathering and packing halo blocks.
void copyCells(const CellRect& cells, const CellRect& fromGrid, const void* from, const CellRect& toGrid, void* to, size_t elementBytes);

// One block of cells (whole-grid coordinates) that `self` sends to `peer` or receives from it.
struct HaloTransfer {
  int peer = 0;
  CellRect cells;
};
// What `self` exchanges to refresh its halo: the cells it owns that another rank's local grid
// holds (sends), and the cells of its own local grid that others own (receives). Every halo cell
// is received from its one owner, corners from diagonal neighbours directly.
struct HaloPlan {
  std::vector<HaloTransfer> sends, receives;
};
HaloPlan haloPlan(const Decomposition& d, int self);

}  // namespace snow::dist
