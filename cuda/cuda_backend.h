// The CUDA backend's host API: plain C++ (no CUDA headers), so .cpp files never need nvcc.
// When the project is built without nvcc, cuda_stub.cpp provides the same functions and says so.
#pragma once
#include <memory>
#include <string>

#include "../core/backend.h"

namespace snow::cuda {

struct DeviceInfo {
  bool available = false;
  std::string description;  // e.g. "NVIDIA H100 80GB HBM3 (sm_90, 79 GiB)"
  std::string reason;       // why not, when unavailable
};

// Never throws: any error from cudaGetDeviceCount (35 without a driver, 100 without a device)
// means "no device", with the error text in `reason`.
DeviceInfo probeDevice();
// Throws std::runtime_error naming the CUDA error when no device can be used.
std::unique_ptr<SnowBackend> createCudaBackend();
// Device-to-device copy bandwidth (read + write counted), GB/s, best of 5 copies of 512 MiB.
double deviceCopyBandwidthGBs();

}  // namespace snow::cuda
