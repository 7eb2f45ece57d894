// CPU backends: the TBB-parallel one used by bakes, and the serial reference.
#pragma once
#include <memory>

#include "backend.h"

namespace snow {

// Runs kernels with tbb::parallel_for over row blocks, using however many threads the caller's
// tbb::global_control (or task arena) allows. Results are identical for any thread count.
std::unique_ptr<SnowBackend> createCpuBackend();
// Runs kernels in a plain loop on the calling thread (the reference the others must match).
std::unique_ptr<SnowBackend> createSerialBackend();

}  // namespace snow
