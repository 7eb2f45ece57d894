// A backend over the serial executor that behaves as CUDA's does where the host code branches on
// it: its buffers count as device memory (Exec::kDevice: the avalanche runner keeps a snapshot
// of the layers, the route map runs as the device's automaton) and an upload of nothing frees the
// buffer (CudaBuffer::resize(0)). Built once, in host_like_a_device.cpp: each instantiation of
// ExecBackend compiles every kernel, the slowest part of a test file's build.
#pragma once
#include <memory>

#include "core/backend.h"

namespace snow::test {

std::unique_ptr<SnowBackend> createHostLikeADeviceBackend();

}  // namespace snow::test
