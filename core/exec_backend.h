// SnowBackend implemented once over any Exec: the Exec supplies storage (host vectors or
// device buffers), forEachCell / forEachCellOfColour and fixed-order reductions; this class
// owns the fields and runs the step functions of steps.h. Included by core/cpu_backend.cpp and
// by the CUDA backend's .cu file, so it must stay free of TBB and CUDA headers.
#pragma once
#include <algorithm>
#include <climits>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "backend.h"
#include "kernels/ski.h"
#include "steps.h"

namespace snow {

template <class Exec>
class ExecBackend final : public SnowBackend {
 public:
  template <class... ExecArgs>
  explicit ExecBackend(ExecArgs&&... args) : exec_(std::forward<ExecArgs>(args)...) {}

  std::string name() const override { return exec_.name(); }

  // The state's fields by their roles (snow_fields.h); the scratch fields made with the state
  // zeroed; the avalanche's and the bedforms' fields made again at their first step.
  void upload(const SnowState& s) override {
    spec_ = s.spec;
#define SNOW_UPLOAD_WITH_STATE(member, view, Element, role, access, fill) \
  if constexpr (uploadedWithState(FieldRole::role)) exec_.upload(member##_, s.member.values());
    SNOW_STATE_FIELDS(SNOW_UPLOAD_WITH_STATE)
#undef SNOW_UPLOAD_WITH_STATE
    avalancheFieldsReady_ = false;
    bedformFieldsReady_ = false;
    makeScratch(true);
    uploadStaticFields(s);
  }

  // Static fields, and the art-direction ones the scene paints (empty buffers otherwise: null in
  // the kernels).
  void uploadStaticFields(const SnowState& s) override {
#define SNOW_UPLOAD_STATIC(member, view, Element, role, access, fill) \
  if constexpr (uploadedWithStaticFields(FieldRole::role)) uploadField<FieldRole::role>(member##_, s.member);
    SNOW_STATE_FIELDS(SNOW_UPLOAD_STATIC)
#undef SNOW_UPLOAD_STATIC
  }

  double applyEdit(const EditArgs& a, const std::vector<float>& weights) override {
    exec_.upload(editWeight_, weights);
    SnowFieldsView v = view();
    v.editWeight = weights.empty() ? nullptr : editWeight_.data();
    const double added = runEdit(exec_, v, a);
    exec_.upload(editWeight_, std::vector<float>());
    exec_.finish();
    return added;
  }

  void download(SnowState& s) override {
#define SNOW_DOWNLOAD(member, view, Element, role, access, fill) \
  if constexpr (downloadedWithState(FieldRole::role)) exec_.download(member##_, s.member.values());
    SNOW_STATE_FIELDS(SNOW_DOWNLOAD)
#undef SNOW_DOWNLOAD
    if (bedformFieldsReady_) {
      s.bedformCohesion.resize(spec_.width, spec_.height, 0.f);
      exec_.download(bed_.cohesion, s.bedformCohesion.values());
    }
  }

  double snowfall(const SnowfallArgs& a) override { return runSnowfall(exec_, view(), a); }
  double melt(const MeltArgs& a) override { return runMelt(exec_, view(), a); }
  void stabilityChange(const StabilityArgs& a) override { runStability(exec_, view(), a); }
  void windTransport(const WindTransportArgs& a) override {
    runWindTransport(exec_, view(), a);
    exec_.finish();
  }
  void powderDiffusion(const PowderDiffusionArgs& a) override {
    runPowderDiffusion(exec_, view(), a);
    exec_.finish();
  }

  void readCells(int x0, int y0, int cols, int rows, std::vector<float>& depth, std::vector<float>& unstable) override {
    depth.assign(static_cast<size_t>(cols) * rows, 0.f);
    unstable.assign(depth.size(), 0.f);
    std::vector<float> row(static_cast<size_t>(cols));
    for (int r = 0; r < rows; ++r) {
      const size_t offset = static_cast<size_t>(y0 + r) * spec_.width + x0;
      float* d = &depth[static_cast<size_t>(r) * cols];
      for (auto* layer : {&compactedM_, &stableM_, &unstableM_, &powderM_}) {
        exec_.downloadRange(*layer, offset, static_cast<size_t>(cols), row.data());
        for (int c = 0; c < cols; ++c) d[c] += row[c];
        if (layer == &unstableM_) std::copy(row.begin(), row.end(), unstable.begin() + static_cast<size_t>(r) * cols);
      }
    }
  }

  BedformStepReport bedformStep(const BedformArgs& args) override {
    const int w = spec_.width, h = spec_.height;
    if (args.periodic && (w % 2 != 0 || h % 2 != 0))  // the repose edge families need even sizes to wrap
      throw std::invalid_argument("bedforms: a periodic grid needs an even width and height");
    if (!(args.slabM > 0.f) || args.batches < 1 || args.rounds < 0)
      throw std::invalid_argument("bedforms: slab thickness, batches and rounds must be positive");
    if (!bedformFieldsReady_) makeBedformFields();  // on the first bedform step only
    exec_.upload(bed_.counters, std::vector<unsigned long long>(4, 0ull));
    const SnowFieldsView v = view();
    const BedformFields f = bedformFields();
    BedformArgs a = args;
    exec_.forEachCell(w, h, BedformPrepareKernel{v, f, a});
    BedformStepReport report;
    const double cells = exec_.sum(v.surfaceSlope, v.valid, w, h);
    report.domainCells = static_cast<long long>(cells);
    a.meanSlabs = cells > 0 ? static_cast<float>(exec_.sum(v.delta, v.valid, w, h) / cells) : 0.f;
    report.slabsBefore = bedformSlabTotal();
    unsigned long long relaxed = 0;
    if (report.domainCells > 0) {
      for (int r = 0; r < args.rounds; ++r) bedformRound(v, f, args, r, a, relaxed);
      report.reposeConverged = relaxBedforms(v, f, a, 1 << 16, relaxed);
    }
    report.slabsAfter = bedformSlabTotal();
    BedformArgs c = a;
    c.dtDays = args.rounds > 0 ? 0.f : args.dtDays;  // the rest of the arrivals; sintering if no round ran
    exec_.forEachCell(w, h, BedformCohesionKernel{v, f, c});
    exec_.forEachCell(w, h, BedformFinishKernel{v, f, a});
    unsigned long long counters[2] = {0, 0};
    exec_.downloadRange(bed_.counters, 0, 2, counters);
    exec_.finish();
    report.slabsEroded = static_cast<long long>(counters[0]);
    report.slabsAvalanched = static_cast<long long>(counters[1]);
    return report;
  }

  bool bedformCohesion(Grid<float>& out) override {
    if (!bedformFieldsReady_) return false;
    out = Grid<float>(spec_.width, spec_.height, 0.f);
    exec_.download(bed_.cohesion, out.values());
    return true;
  }

  bool routeMapOnDevice(Grid<float>& out) override {
    if constexpr (!Exec::kDevice) {
      (void)out;
      return false;
    } else {
      const int w = spec_.width, h = spec_.height;
      const float dx = static_cast<float>(spec_.cellSizeXM), dy = static_cast<float>(spec_.cellSizeYM);
      typename Exec::template Buffer<float> a, b;
      const std::vector<float> zero(spec_.cellCount(), 0.f);
      exec_.upload(a, zero);
      exec_.upload(b, zero);
      std::vector<float> previous, latest;
      // Information moves one cell an iteration; compare the last two iterations every 16.
      for (size_t it = 1;; ++it) {
        auto& in = it % 2 ? a : b;
        auto& result = it % 2 ? b : a;
        exec_.forEachCell(w, h, RouteMapStepKernel{bedrockM_.data(), validCell_.data(), in.data(), result.data(), w, h, dx, dy,
                                                   std::sqrt(dx * dx + dy * dy)});
        if (it % 16 == 0 || it > spec_.cellCount()) {
          exec_.download(in, previous);
          exec_.download(result, latest);
          if (previous == latest) break;
        }
      }
      exec_.finish();
      out = Grid<float>(w, h, 0.f);
      out.values() = latest;
      return true;
    }
  }

  void uploadRouteMap(const Grid<float>& route) override {
    exec_.upload(skierRoute_, route.values());
    exec_.upload(skierClaim_, std::vector<int>(spec_.cellCount(), INT_MAX));
    exec_.upload(skierCounters_, std::vector<int>(2, 0));
    exec_.finish();
  }

  void skierBatch(const SkierArgs& args, std::vector<SkierAgent>& agents, std::vector<std::vector<double>>& paths) override {
    const int n = static_cast<int>(agents.size());
    paths.assign(agents.size(), {});
    if (n == 0) return;
    // The path buffer holds kSkierPathChunk points a skier; the host empties it every
    // kSkierPathChunk - 1 moves (a move adds at most one point; the start adds the first).
    constexpr int kSkierPathChunk = 64;
    SkierArgs a = args;
    a.pathStride = kSkierPathChunk;
    exec_.upload(skierAgents_, agents);
    exec_.upload(skierPath_, std::vector<double>(2 * static_cast<size_t>(kSkierPathChunk) * n));
    const SkierFields f{skierAgents_.data(), n, skierPath_.data(), skierRoute_.data(), skierClaim_.data(), skierCounters_.data()};
    const SnowFieldsView v = view();
    auto counter = [&](int k) {
      int c = 0;
      exec_.downloadRange(skierCounters_, static_cast<size_t>(k), 1, &c);
      return c;
    };
    auto resetCounter = [&](int k) {
      const int zero = 0;
      exec_.uploadRange(skierCounters_, static_cast<size_t>(k), 1, &zero);
    };
    // Claim rounds until every entry of this move is applied (one when no two skiers share a cell).
    auto enterAll = [&] {
      for (int round = 0; round <= n; ++round) {
        resetCounter(1);
        exec_.forEachIndex(n, SkierClaimKernel{f});
        exec_.forEachIndex(n, SkierEnterKernel{v, f, a});
        if (counter(1) == 0) return;
      }
      throw std::logic_error("skier entries: a claim round applied nothing");
    };
    std::vector<double> chunk;
    auto takePaths = [&] {
      exec_.download(skierAgents_, agents);
      for (int i = 0; i < n; ++i) {
        SkierAgent& s = agents[static_cast<size_t>(i)];
        if (s.pathCount == 0) continue;
        chunk.resize(2 * static_cast<size_t>(s.pathCount));
        exec_.downloadRange(skierPath_, 2 * static_cast<size_t>(i) * kSkierPathChunk, chunk.size(), chunk.data());
        paths[static_cast<size_t>(i)].insert(paths[static_cast<size_t>(i)].end(), chunk.begin(), chunk.end());
        s.pathCount = 0;
      }
      exec_.upload(skierAgents_, agents);
    };
    exec_.forEachIndex(n, SkierStartKernel{v, f, a});
    enterAll();
    for (int moves = 1;; ++moves) {
      resetCounter(0);
      exec_.forEachIndex(n, SkierMoveKernel{v, f, a});
      enterAll();
      const bool running = counter(0) > 0;
      if (!running || moves % (kSkierPathChunk - 1) == 0) takePaths();
      if (!running) break;
    }
    exec_.finish();
  }

  void avalancheRelease(const std::vector<uint8_t>& moving) override {
    if (!avalancheFieldsReady_) {  // allocated on the first avalanche only
      makeScratch(false);
      avalancheFieldsReady_ = true;
    }
    exec_.upload(snowMoving_, moving);
    exec_.forEachCell(spec_.width, spec_.height, AvalancheReleaseKernel{view()});
    exec_.finish();
  }
  std::vector<float> avalancheSteps(const AvalancheArgs& args, int substeps) override {
    AvalancheArgs a = args;
    runAvalancheSteps(exec_, view(), a, substeps);
    std::vector<float> stats;
    exec_.download(rowStats_, stats);
    std::vector<float> box(stats.begin() + 4 * static_cast<size_t>(a.y0), stats.begin() + 4 * static_cast<size_t>(a.y1));
    box.push_back(static_cast<float>(a.x0));
    box.push_back(static_cast<float>(a.y0));
    box.push_back(static_cast<float>(a.x1));
    box.push_back(static_cast<float>(a.y1));
    return box;
  }
  void avalancheSettle(const AvalancheArgs& a) override {
    if (a.x1 > a.x0 && a.y1 > a.y0)
      exec_.forEachCell(a.x1 - a.x0, a.y1 - a.y0, InBox<AvalancheSettleKernel>{AvalancheSettleKernel{view()}, a.x0, a.y0});
    exec_.finish();
  }

  LayerTotals totals() override {
    const double area = spec_.cellAreaM2();
    const int w = spec_.width, h = spec_.height;
    LayerTotals t;
    t.compactedM3 = exec_.sum(compactedM_.data(), validCell_.data(), w, h) * area;
    t.stableM3 = exec_.sum(stableM_.data(), validCell_.data(), w, h) * area;
    t.unstableM3 = exec_.sum(unstableM_.data(), validCell_.data(), w, h) * area;
    t.powderM3 = exec_.sum(powderM_.data(), validCell_.data(), w, h) * area;
    return t;
  }

  float maxTemperatureBaseC() override {
    return exec_.maxValue(temperatureBaseC_.data(), validCell_.data(), spec_.width, spec_.height);
  }

  Exec& exec() { return exec_; }

 private:
  BedformFields bedformFields() {
    BedformFields f;
#define SNOW_BEDFORM_POINTER(member, Element, start) f.member = bed_.member.data();
    SNOW_BEDFORM_FIELDS(SNOW_BEDFORM_POINTER)
#undef SNOW_BEDFORM_POINTER
    f.mask = dataIfPresent(bedformMask_);
    return f;
  }

  SnowFieldsView view() {
    SnowFieldsView v;
    v.width = spec_.width;
    v.height = spec_.height;
    v.cellSizeXM = static_cast<float>(spec_.cellSizeXM);
    v.cellSizeYM = static_cast<float>(spec_.cellSizeYM);
#define SNOW_VIEW_OF_FIELD(member, view, Element, role, access, fill) \
  SNOW_IF_VIEW(access, v.view = optionalField(FieldRole::role) ? dataIfPresent(member##_) : member##_.data();)
    SNOW_STATE_FIELDS(SNOW_VIEW_OF_FIELD)
#undef SNOW_VIEW_OF_FIELD
    v.bedformActive = bedformFieldsReady_ ? bed_.active.data() : nullptr;
#define SNOW_VIEW_OF_SCRATCH(view, Element, extent) v.view = view##_.data();
    SNOW_SCRATCH_FIELDS(SNOW_VIEW_OF_SCRATCH)
#undef SNOW_VIEW_OF_SCRATCH
    return v;
  }

  // The bedforms' storage (kernels/bedform.h), each field as its `start` says.
  void makeBedformFields() {
    const size_t n = spec_.cellCount();
    std::vector<float> powder;
    exec_.download(powderM_, powder);  // the snow already there is not fresh
#define SNOW_MAKE_BEDFORM_FIELD(member, Element, start)                                                          \
  if constexpr (BedformStart::start == BedformStart::Zero) exec_.upload(bed_.member, std::vector<Element>(n)); \
  else if constexpr (BedformStart::start == BedformStart::Powder) exec_.upload(bed_.member, powder);
    SNOW_BEDFORM_FIELDS(SNOW_MAKE_BEDFORM_FIELD)
#undef SNOW_MAKE_BEDFORM_FIELD
    bedformFieldsReady_ = true;
  }

  // Slabs in the domain and those that left it: conserved by a step.
  long long bedformSlabTotal() {
    std::vector<int> slabs, exported;
    exec_.download(bed_.slabs, slabs);
    exec_.download(bed_.exported, exported);
    long long total = 0;
    for (size_t i = 0; i < slabs.size(); ++i) total += static_cast<long long>(slabs[i]) + exported[i];
    return total;
  }

  // Relaxation sweeps over the four edge families until no edge moves (true), at most maxSweeps;
  // `relaxed` carries the relaxation's move counter from sweep to sweep.
  bool relaxBedforms(const SnowFieldsView& v, const BedformFields& f, BedformArgs& a, int maxSweeps, unsigned long long& relaxed) {
    const int w = spec_.width, h = spec_.height;
    for (int sweep = 0; sweep < maxSweeps; ++sweep) {
      for (int family = 0; family < 4; ++family) {
        a.family = family;
        if (family < 2) exec_.forEachCell((w + 1) / 2, h, BedformReposeKernel{v, f, a});
        else exec_.forEachCell(w, (h + 1) / 2, BedformReposeKernel{v, f, a});
      }
      unsigned long long now = 0;
      exec_.downloadRange(bed_.counters, 1, 1, &now);
      if (now == relaxed) return true;
      relaxed = now;
    }
    return false;
  }

  // Polling round r of a step: its batches (snapshot, shadow, saltation, relaxation), then the
  // round's share of the cohesion.
  void bedformRound(const SnowFieldsView& v, const BedformFields& f, const BedformArgs& args, int r, BedformArgs& a,
                    unsigned long long& relaxed) {
    const int w = spec_.width, h = spec_.height;
    a.round = args.roundBase + static_cast<uint64_t>(r);
    for (int b = 0; b < args.batches; ++b) {
      a.batch = b;
      exec_.forEachCell(w, h, BedformSnapshotKernel{v, f, a.slabM, v.surfaceSlope});
      a.maxSurface = exec_.maxValue(v.surfaceSlope, v.valid, w, h);
      exec_.forEachCell(w, h, BedformShadowKernel{v, f, a});
      exec_.forEachCell(w, h, BedformSaltationKernel{v, f, a});
      relaxBedforms(v, f, a, 16, relaxed);
    }
    BedformArgs c = a;
    c.dtDays = args.dtDays / static_cast<float>(args.rounds);
    exec_.forEachCell(w, h, BedformCohesionKernel{v, f, c});
  }

  // Zeroed scratch fields: those made with the state (withState), or at the first avalanche.
  void makeScratch(bool withState) {
    const size_t cells = spec_.cellCount(), rows = static_cast<size_t>(spec_.height);
#define SNOW_MAKE_SCRATCH(view, Element, extent)                                                               \
  if (madeWithState(ScratchExtent::extent) == withState)                                                       \
    exec_.upload(view##_, std::vector<Element>(                                                                \
                              scratchCount(ScratchExtent::extent, cells, rows, Exec::kPowderSharesInRows)));
    SNOW_SCRATCH_FIELDS(SNOW_MAKE_SCRATCH)
#undef SNOW_MAKE_SCRATCH
  }

  template <class T>
  using Buffer = typename Exec::template Buffer<T>;
  struct NoBuffer {};  // a field the backend does not hold (host only, or in the bedforms' storage)
  template <FieldRole role, class T>
  using StateBuffer = std::conditional_t<heldByBackend(role), Buffer<T>, NoBuffer>;

  template <class B>
  static auto dataIfPresent(B& b) -> decltype(b.data()) { return b.size() > 0 ? b.data() : nullptr; }
  // A static field as it is; an art-direction one when the scene paints it (else an empty buffer).
  template <FieldRole role, class T>
  void uploadField(Buffer<T>& buffer, const Grid<T>& grid) {
    const bool present = !optionalField(role) || (grid.size() == spec_.cellCount() && grid.size() > 0);
    if (present) exec_.upload(buffer, grid.values());
    else exec_.upload(buffer, std::vector<T>());
  }

  Exec exec_;
  GridSpec spec_;
#define SNOW_STATE_BUFFER(member, view, Element, role, access, fill) StateBuffer<FieldRole::role, Element> member##_;
  SNOW_STATE_FIELDS(SNOW_STATE_BUFFER)
#undef SNOW_STATE_BUFFER
#define SNOW_SCRATCH_BUFFER(view, Element, extent) Buffer<Element> view##_;
  SNOW_SCRATCH_FIELDS(SNOW_SCRATCH_BUFFER)
#undef SNOW_SCRATCH_BUFFER
  Buffer<float> editWeight_;
  bool avalancheFieldsReady_ = false;
  struct BedformBuffers {
#define SNOW_BEDFORM_BUFFER(member, Element, start) Buffer<Element> member;
    SNOW_BEDFORM_FIELDS(SNOW_BEDFORM_BUFFER)
#undef SNOW_BEDFORM_BUFFER
  } bed_;
  bool bedformFieldsReady_ = false;
  Buffer<SkierAgent> skierAgents_;
  Buffer<double> skierPath_;
  Buffer<float> skierRoute_;
  Buffer<int> skierClaim_, skierCounters_;
};

}  // namespace snow
