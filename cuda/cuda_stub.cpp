// Built instead of cuda_backend.cu when no CUDA compiler was found at configure time.
#include <stdexcept>

#include "cuda_backend.h"

namespace snow::cuda {

DeviceInfo probeDevice() {
  DeviceInfo info;
  info.reason = "snowbake was built without CUDA (no nvcc at configure time)";
  return info;
}
std::unique_ptr<SnowBackend> createCudaBackend() {
  throw std::runtime_error("CUDA backend unavailable: " + probeDevice().reason);
}

double deviceCopyBandwidthGBs() { throw std::runtime_error("CUDA backend unavailable: " + probeDevice().reason); }

}  // namespace snow::cuda
