#include "cpu_backend.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <utility>

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
inline long long avalancheBoxCells(const AvalancheWaterRowStatsKernel& k, int, int) { return boxCells(k.a); }

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
  // the shares stay in cache-sized row buffers: pass 1 on row r reads the powder of rows
  // r - 1 .. r + 1 before pass 2 writes them (pass 2 on row r comes after pass 1 on row r + 1),
  // and pass 2 on row r finds the shares of rows r - 1 .. r + 1 computed. So the result is the
  // two whole-grid passes' bytes.
  void forEachCellThen(int width, int height, const PowderFlowKernel& first, const PowderGatherKernel& second) {
    edgeRows_.resize(2 * stripCount(height), width);
    zeroRow_.resize(1, width);
    forEachStrip(
        height, [&](int r) { powderSharesRow(first, r, edgeRows_.row(edgeSlot(r))); },
        [&] {
          // Each thread's three row buffers, kept from task to task (every cell of a buffer is
          // written before it is read; the zero padding is never written).
          PowderRowBuffer* ring = &rings_.local();
          ring->resize(3, width);
          auto rowOf = [this, ring, height](int r) {
            if (r < 0 || r >= height) return zeroRow_.row(0);
            return isEdgeRow(r, height) ? edgeRows_.row(edgeSlot(r)) : ring->row(r % 3);
          };
          auto inner = [ring, &first](int r) { powderSharesRow(first, r, ring->row(r % 3)); };
          auto pass = [&second, rowOf](int y) { powderGatherRow(second.v, y, rowOf(y - 1), rowOf(y), rowOf(y + 1)); };
          return std::pair{inner, pass};
        });
  }
  // The slope snapshot and a pass that reads its own cell's slope only (stability, snowfall),
  // fused by rows: the slope of each row is taken before the pass changes the rows it reads
  // (r - 1 .. r + 1), so the results are the two whole-grid passes' bytes, without the
  // snapshot's write and read of 8 bytes a cell.
  template <class G>
    requires ReadsOwnSlope<G>
  void forEachCellThen(int width, int height, const SurfaceSlopeKernel& first, const G& second) {
    edgeSlopes_.resize(2 * static_cast<size_t>(stripCount(height)) * width);
    auto edgeRow = [&](int r) { return edgeSlopes_.data() + static_cast<size_t>(edgeSlot(r)) * width; };
    forEachStrip(
        height, [&](int r) { surfaceSlopeRow(first.v, r, 0, width, edgeRow(r)); },
        [&] {
          std::vector<float>* ring = &slopeRings_.local();
          ring->resize(2 * static_cast<size_t>(width));
          auto rowOf = [&edgeRow, ring, width, height](int r) {
            return isEdgeRow(r, height) ? edgeRow(r) : ring->data() + static_cast<size_t>(r % 2) * width;
          };
          auto inner = [&first, width, rowOf](int r) { surfaceSlopeRow(first.v, r, 0, width, rowOf(r)); };
          auto pass = [&second, width, rowOf](int y) { withSlopeRow(second, y, width, rowOf(y)); };
          return std::pair{inner, pass};
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
  static int stripCount(int height) { return (height + kStripRows - 1) / kStripRows; }
  static bool isEdgeRow(int r, int height) { return r % kStripRows == 0 || r % kStripRows == kStripRows - 1 || r == height - 1; }
  // The slot of a strip's first (2k) or last (2k + 1) row among the strips' edge rows.
  static int edgeSlot(int r) { return 2 * (r / kStripRows) + (r % kStripRows == 0 ? 0 : 1); }
  // A pass that reads rows r - 1 .. r + 1 of a per-row product (`edge` / `inner`, written to row
  // buffers) and then changes what that product reads (`pass`), fused by strips of kStripRows
  // rows: first `edge` on each strip's first and last rows, whose neighbours other strips change;
  // then each strip as a task of its own, `inner` on its next inner row before `pass` on the row
  // above it. `strip()` gives a task's (inner, pass) pair, bound to its thread's buffers.
  template <class Edge, class Strip>
  void forEachStrip(int height, const Edge& edge, const Strip& strip) {
    const int strips = stripCount(height);
    tbb::parallel_for(0, strips, [&](int k) {
      const int a = k * kStripRows, b = std::min(height, a + kStripRows);
      for (int r = a; r < b; ++r)
        if (isEdgeRow(r, height)) edge(r);
    });
    tbb::parallel_for(0, strips, [&](int k) {
      const int a = k * kStripRows, b = std::min(height, a + kStripRows);
      const auto [inner, pass] = strip();
      for (int y = a; y < b; ++y) {
        if (y + 1 < b && !isEdgeRow(y + 1, height)) inner(y + 1);
        pass(y);
      }
    });
  }
  PowderRowBuffer edgeRows_, zeroRow_;
  tbb::enumerable_thread_specific<PowderRowBuffer> rings_;
  std::vector<float> edgeSlopes_;
  tbb::enumerable_thread_specific<std::vector<float>> slopeRings_;
};

}  // namespace

std::unique_ptr<SnowBackend> createCpuBackend() { return std::make_unique<ExecBackend<TbbExec>>(); }
std::unique_ptr<SnowBackend> createSerialBackend() { return std::make_unique<ExecBackend<SerialExec>>(); }

}  // namespace snow
