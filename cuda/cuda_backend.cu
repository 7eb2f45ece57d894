#include <cuda_runtime.h>

#include "../core/exec_backend.h"
#include "cuda_backend.h"
#include "cuda_exec.cuh"

namespace snow::cuda {

bool compiledWithCuda() { return true; }

DeviceInfo probeDevice() {
  DeviceInfo info;
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess || count == 0) {
    (void)cudaGetLastError();
    info.reason = e != cudaSuccess ? std::string("cudaGetDeviceCount failed: ") + cudaGetErrorString(e) + " (error " +
                                         std::to_string(static_cast<int>(e)) + ")"
                                   : std::string("no CUDA device");
    return info;
  }
  cudaDeviceProp prop{};
  if (cudaGetDeviceProperties(&prop, 0) != cudaSuccess) {
    (void)cudaGetLastError();
    info.reason = "cudaGetDeviceProperties failed";
    return info;
  }
  info.available = true;
  info.description = std::string(prop.name) + " (sm_" + std::to_string(prop.major) + std::to_string(prop.minor) + ", " +
                     std::to_string(prop.totalGlobalMem >> 30) + " GiB)";
  return info;
}

std::unique_ptr<SnowBackend> createCudaBackend() {
  const DeviceInfo info = probeDevice();
  if (!info.available) throw std::runtime_error("CUDA backend unavailable: " + info.reason);
  return std::make_unique<ExecBackend<CudaExec>>();
}

}  // namespace snow::cuda
