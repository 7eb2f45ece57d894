// A rank's part of the whole state and back: its local grid cut out of a whole-grid SnowState
// (every field the state holds), and the ranks' owned cells put together again on one rank.
#pragma once
#include <functional>

#include "communicator.h"
#include "core/snow_state.h"
#include "decomposition.h"

namespace snow::dist {

// The fields `whole` holds, cut to `cells`; the spec's origin moved to the local grid's
// north-west corner (north-up: y runs south).
SnowState cutLocalState(const SnowState& whole, const CellRect& cells);
// The same, each of `whole`'s fields freed once it is cut: the two are never held at once.
SnowState cutLocalState(SnowState&& whole, const CellRect& cells);
// The fields of `whole` whose role `pick` accepts, cut into `local` (the local grid at `cells`,
// sized anew): a day's static fields, filled on the whole grid, for a rank's season beside the
// whole grid's replica.
void cutFields(const SnowState& whole, const CellRect& cells, const std::function<bool(FieldRole)>& pick, SnowState& local);
// A state of the whole grid `spec` holding, zeroed, every field `local` holds: the root's
// gatherOwned target, which then has the single process's fields and no others.
SnowState wholeLike(const SnowState& local, const GridSpec& spec);

// Rank `root`'s `whole` (allocated like the local states' fields: a field absent on the ranks is
// left as it is) receives every rank's owned cells of every field the local state holds; the
// other ranks send theirs. `whole` is read only on `root`.
void gatherOwned(const Communicator& comm, const Decomposition& d, const SnowState& local, SnowState& whole, int root = 0);

// Every field `local` holds (the same on every rank) has its halo cells refreshed from their
// owners: a state the ranks' writers read beyond their own cells (tiles that overlap a neighbour's).
void refreshHalos(const Communicator& comm, const Decomposition& d, SnowState& local);

}  // namespace snow::dist
