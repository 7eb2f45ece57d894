// The season's backend: the CPU (TBB), or CUDA when asked or, with "auto", when a device works.
#include "core/cpu_backend.h"
#include "core/errors.h"
#include "cuda/cuda_backend.h"
#include "stages.h"

namespace snow {

std::unique_ptr<SnowBackend> chooseBackend(BackendChoice wanted, std::ostream& log) {
  if (wanted == BackendChoice::Cpu) return createCpuBackend();
  const cuda::DeviceInfo device = cuda::probeDevice();
  if (wanted == BackendChoice::Cuda) {
    if (!device.available) throw InputError("--backend cuda: no usable CUDA device: " + device.reason);
    return cuda::createCudaBackend();
  }
  if (device.available) {
    log << "backend: cuda (auto: " << device.description << ")\n";
    return cuda::createCudaBackend();
  }
  log << "backend: cpu (auto: " << device.reason << ")\n";
  return createCpuBackend();
}

}  // namespace snow
