// CudaExec: the CUDA executor for ExecBackend. Launches the same kernel structs as the CPU
// backend with a templated __global__ launcher. Includes only CUDA and core's HD headers.
#pragma once
#include <cuda_runtime.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace snow::cuda {

inline void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw std::runtime_error(std::string("CUDA error in ") + what + ": " + cudaGetErrorString(e));
}

template <class T>
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  ~DeviceBuffer() { release(); }
  void resize(size_t n) {
    if (n == size_) return;
    release();
    if (n > 0) check(cudaMalloc(&ptr_, n * sizeof(T)), "cudaMalloc");
    size_ = n;
  }
  T* data() { return ptr_; }
  size_t size() const { return size_; }

 private:
  void release() {
    if (ptr_) cudaFree(ptr_);
    ptr_ = nullptr;
    size_ = 0;
  }
  T* ptr_ = nullptr;
  size_t size_ = 0;
};

template <class K>
__global__ void forEachCellKernel(K kernel, int width, int height) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x < width && y < height) kernel(x, y);
}

template <class K>
__global__ void forEachIndexKernel(K kernel, int n) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) kernel(i);
}

// One thread per row, summing left to right in double: the same order, and so the same bytes,
// as the CPU executors' rowSum.
__global__ inline void rowSumKernel(const float* values, const uint8_t* valid, int width, int height, double* out) {
  const int y = blockIdx.x * blockDim.x + threadIdx.x;
  if (y >= height) return;
  double s = 0.0;
  const size_t base = static_cast<size_t>(y) * width;
  for (int x = 0; x < width; ++x)
    if (valid[base + x]) s += static_cast<double>(values[base + x]);
  out[y] = s;
}
__global__ inline void rowMaxKernel(const float* values, const uint8_t* valid, int width, int height, float* out) {
  const int y = blockIdx.x * blockDim.x + threadIdx.x;
  if (y >= height) return;
  float m = -INFINITY;
  const size_t base = static_cast<size_t>(y) * width;
  for (int x = 0; x < width; ++x)
    if (valid[base + x] && values[base + x] > m) m = values[base + x];
  out[y] = m;
}

class CudaExec {
 public:
  static constexpr bool kDevice = true;  // buffers live on the GPU
  static constexpr bool kPowderSharesInRows = false;  // powder diffusion's shares in powderFlow
  template <class T>
  using Buffer = DeviceBuffer<T>;

  CudaExec() {
    int device = 0;
    check(cudaGetDevice(&device), "cudaGetDevice");
    cudaDeviceProp prop{};
    check(cudaGetDeviceProperties(&prop, device), "cudaGetDeviceProperties");
    name_ = std::string("cuda (") + prop.name + ")";
  }
  std::string name() const { return name_; }

  template <class T>
  void upload(Buffer<T>& b, const std::vector<T>& host) {
    b.resize(host.size());
    if (!host.empty()) check(cudaMemcpy(b.data(), host.data(), host.size() * sizeof(T), cudaMemcpyHostToDevice), "upload");
  }
  template <class T>
  void download(Buffer<T>& b, std::vector<T>& host) {
    host.resize(b.size());
    if (!host.empty()) check(cudaMemcpy(host.data(), b.data(), host.size() * sizeof(T), cudaMemcpyDeviceToHost), "download");
  }

  // The season's first upload and last download: the source freed once copied.
  template <class T>
  void uploadTaking(Buffer<T>& b, std::vector<T>& host) {
    upload(b, host);
    host = std::vector<T>();
  }
  template <class T>
  void downloadGiving(Buffer<T>& b, std::vector<T>& host) {
    download(b, host);
    b.resize(0);
  }

  template <class T>
  void downloadRange(Buffer<T>& b, size_t offset, size_t count, T* out) {
    if (count > 0) check(cudaMemcpy(out, b.data() + offset, count * sizeof(T), cudaMemcpyDeviceToHost), "download range");
  }
  template <class T>
  void uploadRange(Buffer<T>& b, size_t offset, size_t count, const T* in) {
    if (count > 0) check(cudaMemcpy(b.data() + offset, in, count * sizeof(T), cudaMemcpyHostToDevice), "upload range");
  }

  template <class K>
  void forEachCell(int width, int height, const K& kernel) {
    const dim3 block(32, 8);
    const dim3 grid((width + block.x - 1) / block.x, (height + block.y - 1) / block.y);
    forEachCellKernel<<<grid, block>>>(kernel, width, height);
    check(cudaGetLastError(), "forEachCell launch");
  }
  // `first` on every cell, then `second` (SerialExec::forEachCellThen): two launches.
  template <class F, class G>
  void forEachCellThen(int width, int height, const F& first, const G& second) {
    forEachCell(width, height, first);
    forEachCell(width, height, second);
  }
  template <class K>
  void forEachIndex(int n, const K& kernel) {
    if (n <= 0) return;
    forEachIndexKernel<<<(n + 127) / 128, 128>>>(kernel, n);
    check(cudaGetLastError(), "forEachIndex launch");
  }
  double sum(const float* values, const uint8_t* valid, int width, int height) {
    rowSums_.resize(static_cast<size_t>(height));
    rowSumKernel<<<(height + 127) / 128, 128>>>(values, valid, width, height, rowSums_.data());
    check(cudaGetLastError(), "rowSum launch");
    std::vector<double> host;
    download(rowSums_, host);
    double s = 0.0;
    for (double r : host) s += r;
    return s;
  }
  float maxValue(const float* values, const uint8_t* valid, int width, int height) {
    rowMax_.resize(static_cast<size_t>(height));
    rowMaxKernel<<<(height + 127) / 128, 128>>>(values, valid, width, height, rowMax_.data());
    check(cudaGetLastError(), "rowMax launch");
    std::vector<float> host;
    download(rowMax_, host);
    float m = -INFINITY;
    for (float r : host) m = r > m ? r : m;
    return m;
  }
  void finish() { check(cudaDeviceSynchronize(), "kernel execution"); }

 private:
  std::string name_;
  DeviceBuffer<double> rowSums_;
  DeviceBuffer<float> rowMax_;
};

}  // namespace snow::cuda
