// The counter-based generator gives the same numbers in device code as on the host.
#include <cuda_runtime.h>
#include <gtest/gtest.h>

#include <vector>

#include "core/rng.h"

namespace {

__global__ void drawKernel(snow::RandomKey key, uint64_t eventIndex, int n, float* out, uint32_t* raw) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  out[i] = key.uniform(eventIndex, static_cast<uint32_t>(i), snow::RngStream::Snowfall);
  raw[i] = key.draw(eventIndex, static_cast<uint32_t>(i), snow::RngStream::Melt).v[3];
}

}  // namespace

TEST(CudaRng, DeviceDrawsEqualHostDraws) {
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess || count == 0) {
    (void)cudaGetLastError();
    GTEST_SKIP() << "no CUDA device: " << (e != cudaSuccess ? cudaGetErrorString(e) : "none");
  }
  const int n = 1 << 16;
  const snow::RandomKey key{0x123456789abcdefull};
  const uint64_t eventIndex = (1ull << 40) + 77;  // high bits of the counter in use
  float* dOut = nullptr;
  uint32_t* dRaw = nullptr;
  ASSERT_EQ(cudaMalloc(&dOut, n * sizeof(float)), cudaSuccess);
  ASSERT_EQ(cudaMalloc(&dRaw, n * sizeof(uint32_t)), cudaSuccess);
  drawKernel<<<(n + 255) / 256, 256>>>(key, eventIndex, n, dOut, dRaw);
  ASSERT_EQ(cudaDeviceSynchronize(), cudaSuccess);
  std::vector<float> out(n);
  std::vector<uint32_t> raw(n);
  ASSERT_EQ(cudaMemcpy(out.data(), dOut, n * sizeof(float), cudaMemcpyDeviceToHost), cudaSuccess);
  ASSERT_EQ(cudaMemcpy(raw.data(), dRaw, n * sizeof(uint32_t), cudaMemcpyDeviceToHost), cudaSuccess);
  cudaFree(dOut);
  cudaFree(dRaw);
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(out[i], key.uniform(eventIndex, static_cast<uint32_t>(i), snow::RngStream::Snowfall)) << i;
    ASSERT_EQ(raw[i], key.draw(eventIndex, static_cast<uint32_t>(i), snow::RngStream::Melt).v[3]) << i;
  }
}
