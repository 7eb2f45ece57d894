// The whole grid's fixed-order reductions over the ranks' owned cells, bit for bit the single
// process's (core/serial_exec.h: each row summed left to right in double, then the row sums top
// to bottom; the CPU and CUDA executors sum the same way): so the mass ledger, and everything
// that reads it, does not depend on the rank count.
#pragma once
#include <cstdint>

#include "communicator.h"
#include "decomposition.h"

namespace snow::dist {

// Each row's partial sum passes left to right along the process row (a rank continues its left
// neighbour's double over its own columns), the rows' sums are gathered, and every rank adds them
// top to bottom. `values` and `valid` hold d.local(rank) row-major; only owned cells count.
double exactSum(const Communicator& comm, const Decomposition& d, const float* values, const uint8_t* valid);
// The largest value of a valid owned cell (order does not matter to a maximum); -inf if none.
float exactMax(const Communicator& comm, const Decomposition& d, const float* values, const uint8_t* valid);

}  // namespace snow::dist
