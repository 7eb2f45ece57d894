// A replica of the whole grid on every rank, kept in step with the ranks' local grids: the
// avalanches, skiers and bedforms of a distributed season run on it, alike on every rank, while
// the continuous phenomena run decomposed (DistributedBackend). Bringing it up to date gathers
// every rank's owned cells into it on every rank; bringing a local grid up to date cuts the
// local grid, halo included, out of it (no exchange: the replica is the same on every rank).
#pragma once
#include <cstddef>
#include <functional>

#include "communicator.h"
#include "core/backend.h"
#include "decomposition.h"

namespace snow::dist {

// Every rank's owned cells of `local` (d.local(rank), row-major, `elementBytes` a cell) into
// `whole` (the whole grid, row-major) on every rank. Returns the bytes this rank sent.
size_t allGatherOwned(const Communicator& comm, const Decomposition& d, const void* local, void* whole, size_t elementBytes);

// allGatherOwned of every field whose role `pick` accepts from the backend `local` into the
// backend `replica` (both in host memory; a field absent from both is skipped). Returns the bytes
// sent. Throws std::logic_error where one holds a field the other does not, or on a device.
size_t gatherIntoReplica(const Communicator& comm, const Decomposition& d, SnowBackend& local, SnowBackend& replica,
                         const std::function<bool(FieldRole)>& pick);

// The same fields of `local`'s grid (d.local(rank), halo included) copied from `replica`.
void cutFromReplica(const Decomposition& d, int rank, SnowBackend& replica, SnowBackend& local, const std::function<bool(FieldRole)>& pick);

}  // namespace snow::dist
