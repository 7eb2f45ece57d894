// The reference executor: every kernel body called in a plain loop, in row order, on one thread.
// The TBB executor must give the same bytes (each cell is written by exactly one call per pass),
// and the GPU test binary uses this one as the CPU reference because it links no TBB.
//
// What every executor (this one, TbbExec in cpu_backend.cpp, CudaExec in cuda/cuda_exec.cuh)
// provides, and each phenomenon's runX<Exec> (core/phenomena/) uses:
//   template <class T> using Buffer = ...;  // the storage ExecBackend keeps per field
//   template <class K> void forEachCell(int width, int height, const K& kernel);
//   template <class F, class G> void forEachCellThen(int width, int height, const F& first, const G& second);
//     (first on every cell, then second)
//   template <class K> void forEachIndex(int n, const K& kernel);  // agents, not cells
//   double sum(const float* values, const uint8_t* valid, int width, int height);  // fixed order
//   float maxValue(const float* values, const uint8_t* valid, int width, int height);
//   void finish();  // waits for queued work (GPU) and reports its errors
#pragma once
#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace snow {

template <class T>
class HostBuffer {
 public:
  T* data() { return values_.data(); }
  const T* data() const { return values_.data(); }
  std::vector<T>& values() { return values_; }
  size_t size() const { return values_.size(); }

 private:
  std::vector<T> values_;
};

// Fixed-order reductions shared by the host executors: each row is summed left to right in
// double, then the row sums top to bottom. The CUDA executor computes row sums the same way.
inline double rowSum(const float* values, const uint8_t* valid, int width, int y) {
  double s = 0.0;
  const size_t base = static_cast<size_t>(y) * width;
  for (int x = 0; x < width; ++x)
    if (valid[base + x]) s += static_cast<double>(values[base + x]);
  return s;
}
inline float rowMax(const float* values, const uint8_t* valid, int width, int y) {
  float m = -std::numeric_limits<float>::infinity();
  const size_t base = static_cast<size_t>(y) * width;
  for (int x = 0; x < width; ++x)
    if (valid[base + x] && values[base + x] > m) m = values[base + x];
  return m;
}

// Storage for the executors that run on the host: buffers are vectors, "upload" is a copy.
struct HostStorage {
  static constexpr bool kDevice = false;  // buffers live in host memory
  static constexpr bool kPowderSharesInRows = false;  // powder diffusion's shares in powderFlow
  template <class T>
  using Buffer = HostBuffer<T>;
  template <class T>
  void upload(Buffer<T>& b, const std::vector<T>& host) { b.values() = host; }
  template <class T>
  void download(Buffer<T>& b, std::vector<T>& host) { host = b.values(); }
  // Handed over, not copied: the source is left empty.
  template <class T>
  void uploadTaking(Buffer<T>& b, std::vector<T>& host) {
    b.values() = std::move(host);
    host = std::vector<T>();
  }
  template <class T>
  void downloadGiving(Buffer<T>& b, std::vector<T>& host) {
    host = std::move(b.values());
    b.values() = std::vector<T>();
  }
  template <class T>
  void downloadRange(Buffer<T>& b, size_t offset, size_t count, T* out) {
    std::copy(b.values().begin() + offset, b.values().begin() + offset + count, out);
  }
  template <class T>
  void uploadRange(Buffer<T>& b, size_t offset, size_t count, const T* in) {
    std::copy(in, in + count, b.values().begin() + offset);
  }
  void finish() {}
};

class SerialExec : public HostStorage {
 public:
  std::string name() const { return "serial"; }

  template <class K>
  void forEachCell(int width, int height, const K& kernel) {
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) kernel(x, y);
  }
  // `first` on every cell, then `second` on every cell. `second` may read what `first` wrote
  // within one cell of it; `first` may read, within one cell, the fields `second` writes (as
  // they were before). The TBB executor interleaves the passes by rows where it can.
  template <class F, class G>
  void forEachCellThen(int width, int height, const F& first, const G& second) {
    forEachCell(width, height, first);
    forEachCell(width, height, second);
  }
  // kernel(i) for i in [0, n) (agents, not cells).
  template <class K>
  void forEachIndex(int n, const K& kernel) {
    for (int i = 0; i < n; ++i) kernel(i);
  }
  double sum(const float* values, const uint8_t* valid, int width, int height) {
    double s = 0.0;
    for (int y = 0; y < height; ++y) s += rowSum(values, valid, width, y);
    return s;
  }
  float maxValue(const float* values, const uint8_t* valid, int width, int height) {
    float m = -std::numeric_limits<float>::infinity();
    for (int y = 0; y < height; ++y) {
      const float r = rowMax(values, valid, width, y);
      if (r > m) m = r;
    }
    return m;
  }
};

}  // namespace snow
