#include "cpu_backend.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>

#include "exec_backend.h"
#include "kernels/powder_diffusion_rows.h"
#include "serial_exec.h"

namespace snow {
namespace {

// Rows per task: large enough to amortise scheduling, small enough to balance 2..64 threads.
constexpr int kRowGrain = 8;

class TbbExec : public HostStorage {
 public:
  std::string name() const { return "cpu"; }

  // A kernel with a row fast path (rowSpan, found by argument-dependent lookup) runs it per row.
  template <class K>
  void forEachCell(int width, int height, const K& kernel) {
    tbb::parallel_for(tbb::blocked_range<int>(0, height, kRowGrain), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y) {
        if constexpr (HasRowSpan<K>) rowSpan(kernel, y, 0, width);
        else
          for (int x = 0; x < width; ++x) kernel(x, y);
      }
    });
  }
  // kernel(i) for i in [0, n) (agents, not cells): a few per task, they are few and costly.
  template <class K>
  void forEachIndex(int n, const K& kernel) {
    if (n <= 1) {
      if (n == 1) kernel(0);
      return;
    }
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 2), [&](const tbb::blocked_range<int>& r) {
      for (int i = r.begin(); i < r.end(); ++i) kernel(i);
    });
  }
  template <class K>
  void forEachCellOfColour(int width, int height, int colour, const K& kernel) {
    tbb::parallel_for(tbb::blocked_range<int>(0, height, kRowGrain), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = firstColumnOfColour(y, colour); x < width; x += 5) kernel(x, y);
    });
  }
  // Row sums in parallel, each row in order; then the rows in order: the same bytes as SerialExec.
  double sum(const float* values, const uint8_t* valid, int width, int height) {
    rowSums_.assign(static_cast<size_t>(height), 0.0);
    tbb::parallel_for(tbb::blocked_range<int>(0, height, kRowGrain), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y) rowSums_[y] = rowSum(values, valid, width, y);
    });
    double s = 0.0;
    for (double r : rowSums_) s += r;
    return s;
  }
  float maxValue(const float* values, const uint8_t* valid, int width, int height) {
    rowMax_.assign(static_cast<size_t>(height), -std::numeric_limits<float>::infinity());
    tbb::parallel_for(tbb::blocked_range<int>(0, height, kRowGrain), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y) rowMax_[y] = rowMax(values, valid, width, y);
    });
    return rowMax_.empty() ? -std::numeric_limits<float>::infinity() : *std::max_element(rowMax_.begin(), rowMax_.end());
  }

 private:
  std::vector<double> rowSums_;
  std::vector<float> rowMax_;
};

}  // namespace

std::unique_ptr<SnowBackend> createCpuBackend() { return std::make_unique<ExecBackend<TbbExec>>(); }
std::unique_ptr<SnowBackend> createSerialBackend() { return std::make_unique<ExecBackend<SerialExec>>(); }

}  // namespace snow
