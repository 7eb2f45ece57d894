// Refreshing a rank's halo: the cells of its local grid that other ranks own, copied from them.
// One field at a time (any element size), or every field of a backend that the field table
// (core/snow_fields.h) gives a role to exchange.
#pragma once
#include <cstddef>
#include <functional>

#include "communicator.h"
#include "core/backend.h"
#include "decomposition.h"

namespace snow::dist {

// `local` holds d.local(rank) row-major, `elementBytes` a cell; its halo cells are overwritten
// with their owners' values, its owned cells are left as they are. Returns the bytes this rank sent.
size_t exchangeHalo(const Communicator& comm, const Decomposition& d, const HaloPlan& plan, void* local, size_t elementBytes);

// exchangeHalo on every field the backend holds in host memory whose role `pick` accepts (absent
// fields skipped: a season that does not keep a record field has it on no rank). Returns the
// bytes sent. Throws std::logic_error on a backend without host fields (a device).
size_t exchangeBackendHalos(const Communicator& comm, const Decomposition& d, const HaloPlan& plan, SnowBackend& backend,
                            const std::function<bool(FieldRole)>& pick);

}  // namespace snow::dist
