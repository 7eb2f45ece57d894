// Any rectangle of the grid on any rank, from the ranks that own its cells: what a rank needs
// beyond its halo (the cells a resampled tile's pixels read reach up to a tile's width past the
// rank's subdomain). Every rank calls at once, each naming its own rectangle.
#pragma once
#include <cstddef>

#include "communicator.h"
#include "decomposition.h"

namespace snow::dist {

// `local` holds d.local(rank) row-major, `elementBytes` a cell; `held` receives `want` (cells of
// the whole grid, row-major, want.cells() elements), each cell its owner's value. One allGather
// of the rectangles, then one exchange: each rank sends every other the cells it owns of theirs.
// Returns the bytes this rank sent.
size_t gatherWindow(const Communicator& comm, const Decomposition& d, const void* local, size_t elementBytes, const CellRect& want, void* held);

}  // namespace snow::dist
