#include <cuda_runtime.h>

#include "../core/exec_backend.h"
#include "cuda_backend.h"
#include "cuda_exec.cuh"

namespace snow::cuda {

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

double deviceCopyBandwidthGBs() {
  const size_t bytes = size_t{512} << 20;
  void *a = nullptr, *b = nullptr;
  check(cudaMalloc(&a, bytes), "cudaMalloc");
  check(cudaMalloc(&b, bytes), "cudaMalloc");
  check(cudaMemset(a, 1, bytes), "cudaMemset");
  cudaEvent_t start, stop;
  cudaEventCreate(&start);
  cudaEventCreate(&stop);
  float best = 1e30f;
  for (int rep = 0; rep < 6; ++rep) {
    cudaEventRecord(start);
    check(cudaMemcpy(b, a, bytes, cudaMemcpyDeviceToDevice), "cudaMemcpy");
    cudaEventRecord(stop);
    cudaEventSynchronize(stop);
    float ms = 0.f;
    cudaEventElapsedTime(&ms, start, stop);
    if (rep > 0) best = ms < best ? ms : best;  // the first copy warms up
  }
  cudaEventDestroy(start);
  cudaEventDestroy(stop);
  cudaFree(a);
  cudaFree(b);
  return 2.0 * static_cast<double>(bytes) / (best * 1e-3) / 1e9;
}

}  // namespace snow::cuda
