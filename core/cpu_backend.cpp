#include "cpu_backend.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>

#include "exec_backend.h"
#include "phenomena/avalanche_rows.h"
#include "phenomena/powder_diffusion_rows.h"
#include "phenomena/slope_pass_rows.h"
#include "phenomena/surface_slope_rows.h"
#include "phenomena/wind_transport_rows.h"
#include "serial_exec.h"

namespace snow {
namespace {

// Rows per task: large enough to amortise scheduling, small enough to balance 2..64 threads.
constexpr int kRowGrain = 8;

// An avalanche pass over a box of fewer cells than this runs on the calling thread. Its passes
// take a few microseconds each, four to a step, hundreds of thousands of steps a season: a TBB
// pass that woke a sleeping worker for each took twice as long on two threads as on one, and a
// team of helpers spinning between passes gained under 10 % (bench/RESULTS.md).
constexpr long long kAvalancheTaskCells = 1 << 17;
inline long long boxCells(const AvalancheArgs& a) { return static_cast<long long>(a.x1 - a.x0) * (a.y1 - a.y0); }
// The cells of an avalanche pass's box; -1 for any other pass.
template <class K>
long long avalancheBoxCells(const K&, int, int) { return -1; }
template <class K>
long long avalancheBoxCells(const InBox<K>&, int width, int height) { return static_cast<long long>(width) * height; }
template <class K>
long long avalancheBoxCells(const InRowSpans<K>& k, int, int) { return boxCells(k.a); }
inline long long avalancheBoxCells(const AvalancheRowStatsKernel& k, int, int) { return boxCells(k.a); }

class TbbExec : public HostStorage {
 public:
  std::string name() const { return "cpu"; }
  // Powder diffusion's shares live in row buffers here (forEachCellThen below), not in the view.
  static constexpr bool kPowderSharesInRows = true;

  // A kernel with a row path (rowSpan, found by argument-dependent lookup) runs it per row. A
  // pass of one task's rows, or an avalanche's pass on a small box, runs on the calling thread.
  template <class K>
  void forEachCell(int width, int height, const K& kernel) {
    auto rows = [&](int y0, int y1) {
      for (int y = y0; y < y1; ++y) {
        if constexpr (HasRowSpan<K>) rowSpan(kernel, y, 0, width);
        else
          for (int x = 0; x < width; ++x) kernel(x, y);
      }
    };
    const long long box = avalancheBoxCells(kernel, width, height);
    if (height <= kRowGrain || (box >= 0 && box < kAvalancheTaskCells)) return rows(0, height);
    tbb::parallel_for(tbb::blocked_range<int>(0, height, kRowGrain),
                      [&](const tbb::blocked_range<int>& r) { rows(r.begin(), r.end()); });
  }
  void forEachHostChunk(int n, int chunk, const std::function<void(int, int)>& f) {
    tbb::parallel_for(0, (n + chunk - 1) / chunk, [&](int k) { f(k * chunk, std::min(n, (k + 1) * chunk)); });
  }
  // `first` on every cell, then `second` (SerialExec::forEachCellThen).
  template <class F, class G>
  void forEachCellThen(int width, int height, const F& first, const G& second) {
    forEachCell(width, height, first);
    forEachCell(width, height, second);
  }
  // A powder-diffusion substep, its two passes interleaved by rows (powder_diffusion_rows.h) so
  // the shares stay in cache-sized row buffers. The grid is cut into strips of kStripRows rows.
  // First, pass 1 on each strip's first and last rows (into edgeRows_). Then each strip, as a
  // task of its own, runs pass 1 on its next inner row and pass 2 on the row above it, in order:
  // pass 1 on row r reads the powder of rows r - 1 .. r + 1 before pass 2 writes them (pass 2 on
  // row r comes after pass 1 on row r + 1, and the tasks of other strips only read their own
  // rows), and pass 2 on row r finds the shares of rows r - 1 .. r + 1 computed. So the result is
  // the two whole-grid passes' bytes.
  void forEachCellThen(int width, int height, const PowderFlowKernel& first, const PowderGatherKernel& second) {
    const int strips = (height + kStripRows - 1) / kStripRows;
    edgeRows_.resize(2 * strips, width);
    zeroRow_.resize(1, width);
    auto edgeSlot = [&](int r) { return 2 * (r / kStripRows) + (r % kStripRows == 0 ? 0 : 1); };
    auto isEdge = [&](int r) { return r % kStripRows == 0 || r % kStripRows == kStripRows - 1 || r == height - 1; };
    tbb::parallel_for(0, strips, [&](int k) {
      const int a = k * kStripRows, b = std::min(height, a + kStripRows);
      powderSharesRow(first, a, edgeRows_.row(edgeSlot(a)));
      if (b - 1 > a) powderSharesRow(first, b - 1, edgeRows_.row(edgeSlot(b - 1)));
    });
    tbb::parallel_for(0, strips, [&](int k) {
      const int a = k * kStripRows, b = std::min(height, a + kStripRows);
      // Each thread's three row buffers, kept from task to task (every cell of a buffer is written
      // before it is read; the zero padding is never written).
      PowderRowBuffer& ring = rings_.local();
      ring.resize(3, width);
      auto rowOf = [&](int r) {
        if (r < 0 || r >= height) return zeroRow_.row(0);
        return isEdge(r) ? edgeRows_.row(edgeSlot(r)) : ring.row(r % 3);
      };
      for (int y = a; y < b; ++y) {
        if (y + 1 < b && !isEdge(y + 1)) powderSharesRow(first, y + 1, ring.row((y + 1) % 3));
        powderGatherRow(second.v, y, rowOf(y - 1), rowOf(y), rowOf(y + 1));
      }
    });
  }
  // The slope snapshot and a pass that reads its own cell's slope only (stability, snowfall),
  // fused by rows, with powder diffusion's strips: the slopes of each strip's first and last rows
  // into edgeSlopes_ first, then each strip, as a task of its own, takes the slope of its next
  // inner row (into a ring of two row buffers) before the pass changes the row above it. A slope
  // on row r reads rows r - 1 .. r + 1, which the pass has not changed yet, so the results are
  // the two whole-grid passes' bytes, without the snapshot's write and read of 8 bytes a cell.
  template <class G>
    requires ReadsOwnSlope<G>
  void forEachCellThen(int width, int height, const SurfaceSlopeKernel& first, const G& second) {
    const int strips = (height + kStripRows - 1) / kStripRows;
    edgeSlopes_.resize(2 * static_cast<size_t>(strips) * width);
    auto edgeRow = [&](int r) { return edgeSlopes_.data() + static_cast<size_t>(2 * (r / kStripRows) + (r % kStripRows == 0 ? 0 : 1)) * width; };
    tbb::parallel_for(0, strips, [&](int k) {
      const int a = k * kStripRows, b = std::min(height, a + kStripRows);
      surfaceSlopeRow(first.v, a, 0, width, edgeRow(a));
      if (b - 1 > a) surfaceSlopeRow(first.v, b - 1, 0, width, edgeRow(b - 1));
    });
    tbb::parallel_for(0, strips, [&](int k) {
      const int a = k * kStripRows, b = std::min(height, a + kStripRows);
      std::vector<float>& ring = slopeRings_.local();
      ring.resize(2 * static_cast<size_t>(width));
      auto rowOf = [&](int r) { return r == a || r == b - 1 ? edgeRow(r) : ring.data() + static_cast<size_t>(r % 2) * width; };
      for (int y = a; y < b; ++y) {
        if (y + 1 < b - 1) surfaceSlopeRow(first.v, y + 1, 0, width, rowOf(y + 1));
        withSlopeRow(second, y, width, rowOf(y));
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
  static constexpr int kStripRows = 32;
  PowderRowBuffer edgeRows_, zeroRow_;
  tbb::enumerable_thread_specific<PowderRowBuffer> rings_;
  std::vector<float> edgeSlopes_;
  tbb::enumerable_thread_specific<std::vector<float>> slopeRings_;
};

}  // namespace

std::unique_ptr<SnowBackend> createCpuBackend() { return std::make_unique<ExecBackend<TbbExec>>(); }
std::unique_ptr<SnowBackend> createSerialBackend() { return std::make_unique<ExecBackend<SerialExec>>(); }

}  // namespace snow
