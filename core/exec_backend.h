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

  void upload(const SnowState& s) override {
    spec_ = s.spec;
    exec_.upload(bedrock_, s.bedrockM.values());
    exec_.upload(compacted_, s.compactedM.values());
    exec_.upload(stable_, s.stableM.values());
    exec_.upload(unstable_, s.unstableM.values());
    exec_.upload(powder_, s.powderM.values());
    exec_.upload(moving_, s.snowMoving.values());
    exec_.upload(windScour_, s.windScourM.values());
    exec_.upload(windDeposit_, s.windDepositM.values());
    exec_.upload(melted_, s.meltedM.values());
    exec_.upload(avalancheScour_, s.avalancheScourM.values());
    exec_.upload(avalancheDeposit_, s.avalancheDepositM.values());
    avalancheFieldsReady_ = false;
    bedformFieldsReady_ = false;
    exec_.upload(valid_, s.validCell.values());
    exec_.upload(delta_, std::vector<float>(s.spec.cellCount(), 0.f));
    exec_.upload(surfaceSlope_, std::vector<float>(s.spec.cellCount(), 0.f));
    exec_.upload(scratchSurface_, std::vector<float>(s.spec.cellCount(), 0.f));
    exec_.upload(scratchPowder_, std::vector<float>(s.spec.cellCount(), 0.f));
    // Five shares a cell, unless the executor keeps them in row buffers (the TBB one).
    if constexpr (Exec::kPowderSharesInRows)
      exec_.upload(powderFlow_, std::vector<float>());
    else
      exec_.upload(powderFlow_, std::vector<float>(5 * s.spec.cellCount(), 0.f));
    uploadStaticFields(s);
  }

  void uploadStaticFields(const SnowState& s) override {
    exec_.upload(exposure_, s.exposureHours.values());
    exec_.upload(temperatureBase_, s.temperatureBaseC.values());
    exec_.upload(windX_, s.windXMps.values());
    exec_.upload(windY_, s.windYMps.values());
    exec_.upload(windEffectZ_, s.windEffectZM.values());
    exec_.upload(windLoading_, s.windLoadingMps2.values());
    // Art-direction factors: uploaded when the scene paints them, null in the kernels otherwise.
    hasSnowfallFactor_ = uploadOptional(snowfallFactor_, s.snowfallFactor);
    hasMeltFactor_ = uploadOptional(meltFactor_, s.meltFactor);
    hasWindErosionFactor_ = uploadOptional(windErosionFactor_, s.windErosionFactor);
    hasBedformMask_ = s.bedformMask.size() == spec_.cellCount() && s.bedformMask.size() > 0;
    exec_.upload(bedformMask_, hasBedformMask_ ? s.bedformMask.values() : std::vector<uint8_t>());
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
    exec_.download(compacted_, s.compactedM.values());
    exec_.download(stable_, s.stableM.values());
    exec_.download(unstable_, s.unstableM.values());
    exec_.download(powder_, s.powderM.values());
    exec_.download(moving_, s.snowMoving.values());
    exec_.download(windScour_, s.windScourM.values());
    exec_.download(windDeposit_, s.windDepositM.values());
    exec_.download(melted_, s.meltedM.values());
    exec_.download(avalancheScour_, s.avalancheScourM.values());
    exec_.download(avalancheDeposit_, s.avalancheDepositM.values());
    if (bedformFieldsReady_) {
      s.bedformCohesion.resize(spec_.width, spec_.height, 0.f);
      exec_.download(bedCohesion_, s.bedformCohesion.values());
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
      for (auto* layer : {&compacted_, &stable_, &unstable_, &powder_}) {
        exec_.downloadRange(*layer, offset, static_cast<size_t>(cols), row.data());
        for (int c = 0; c < cols; ++c) d[c] += row[c];
        if (layer == &unstable_) std::copy(row.begin(), row.end(), unstable.begin() + static_cast<size_t>(r) * cols);
      }
    }
  }

  BedformStepReport bedformStep(const BedformArgs& args) override {
    const int w = spec_.width, h = spec_.height;
    const size_t n = spec_.cellCount();
    if (args.periodic && (w % 2 != 0 || h % 2 != 0))  // the repose edge families need even sizes to wrap
      throw std::invalid_argument("bedforms: a periodic grid needs an even width and height");
    if (!(args.slabM > 0.f) || args.batches < 1 || args.rounds < 0)
      throw std::invalid_argument("bedforms: slab thickness, batches and rounds must be positive");
    if (!bedformFieldsReady_) {  // allocated on the first bedform step only
      const std::vector<int> zeroInts(n, 0);
      const std::vector<float> zeroFloats(n, 0.f);
      const std::vector<uint8_t> zeroBytes(n, 0);
      for (auto* b : {&bedSlabs_, &bedSnapshot_, &bedExported_, &bedArrived_, &bedArrivedCohesion_, &bedInitial_}) exec_.upload(*b, zeroInts);
      for (auto* b : {&bedCohesion_, &bedBase_}) exec_.upload(*b, zeroFloats);
      for (auto* b : {&bedShadow_, &bedActive_}) exec_.upload(*b, zeroBytes);
      std::vector<float> powder;
      exec_.download(powder_, powder);
      exec_.upload(bedLastPowder_, powder);  // the snow already there is not fresh
      bedformFieldsReady_ = true;
    }
    exec_.upload(bedCounters_, std::vector<unsigned long long>(4, 0ull));
    const SnowFieldsView v = view();
    const BedformFields f = bedformFields();
    BedformArgs a = args;
    exec_.forEachCell(w, h, BedformPrepareKernel{v, f, a});
    BedformStepReport report;
    const double cells = exec_.sum(v.surfaceSlope, v.valid, w, h);
    report.domainCells = static_cast<long long>(cells);
    a.meanSlabs = cells > 0 ? static_cast<float>(exec_.sum(v.delta, v.valid, w, h) / cells) : 0.f;
    auto slabTotal = [&] {
      std::vector<int> slabs, exported;
      exec_.download(bedSlabs_, slabs);
      exec_.download(bedExported_, exported);
      long long total = 0;
      for (size_t i = 0; i < slabs.size(); ++i) total += static_cast<long long>(slabs[i]) + exported[i];
      return total;
    };
    report.slabsBefore = slabTotal();
    unsigned long long relaxed = 0;
    // Relaxation sweeps over the four edge families until no edge moves (at most maxSweeps).
    auto relax = [&](int maxSweeps) {
      for (int sweep = 0; sweep < maxSweeps; ++sweep) {
        for (int family = 0; family < 4; ++family) {
          a.family = family;
          if (family < 2) exec_.forEachCell((w + 1) / 2, h, BedformReposeKernel{v, f, a});
          else exec_.forEachCell(w, (h + 1) / 2, BedformReposeKernel{v, f, a});
        }
        unsigned long long now = 0;
        exec_.downloadRange(bedCounters_, 1, 1, &now);
        if (now == relaxed) return true;
        relaxed = now;
      }
      return false;
    };
    if (report.domainCells > 0) {
      for (int r = 0; r < args.rounds; ++r) {
        a.round = args.roundBase + static_cast<uint64_t>(r);
        for (int b = 0; b < args.batches; ++b) {
          a.batch = b;
          exec_.forEachCell(w, h, BedformSnapshotKernel{v, f, a.slabM, v.surfaceSlope});
          a.maxSurface = exec_.maxValue(v.surfaceSlope, v.valid, w, h);
          exec_.forEachCell(w, h, BedformShadowKernel{v, f, a});
          exec_.forEachCell(w, h, BedformSaltationKernel{v, f, a});
          relax(16);
        }
        BedformArgs c = a;
        c.dtDays = args.dtDays / static_cast<float>(args.rounds);
        exec_.forEachCell(w, h, BedformCohesionKernel{v, f, c});
      }
      report.reposeConverged = relax(1 << 16);
    }
    report.slabsAfter = slabTotal();
    BedformArgs c = a;
    c.dtDays = args.rounds > 0 ? 0.f : args.dtDays;  // the rest of the arrivals; sintering if no round ran
    exec_.forEachCell(w, h, BedformCohesionKernel{v, f, c});
    exec_.forEachCell(w, h, BedformFinishKernel{v, f, a});
    unsigned long long counters[2] = {0, 0};
    exec_.downloadRange(bedCounters_, 0, 2, counters);
    exec_.finish();
    report.slabsEroded = static_cast<long long>(counters[0]);
    report.slabsAvalanched = static_cast<long long>(counters[1]);
    return report;
  }

  bool bedformCohesion(Grid<float>& out) override {
    if (!bedformFieldsReady_) return false;
    out = Grid<float>(spec_.width, spec_.height, 0.f);
    exec_.download(bedCohesion_, out.values());
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
        exec_.forEachCell(w, h, RouteMapStepKernel{bedrock_.data(), valid_.data(), in.data(), result.data(), w, h, dx, dy,
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
      exec_.upload(flows_, std::vector<float>(4 * spec_.cellCount(), 0.f));
      exec_.upload(avalancheBefore_, std::vector<float>(spec_.cellCount(), 0.f));
      exec_.upload(avalancheU_, std::vector<double>(spec_.cellCount(), 0.0));
      exec_.upload(rowStats_, std::vector<float>(4 * static_cast<size_t>(spec_.height), 0.f));
      avalancheFieldsReady_ = true;
    }
    exec_.upload(moving_, moving);
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
    t.compactedM3 = exec_.sum(compacted_.data(), valid_.data(), w, h) * area;
    t.stableM3 = exec_.sum(stable_.data(), valid_.data(), w, h) * area;
    t.unstableM3 = exec_.sum(unstable_.data(), valid_.data(), w, h) * area;
    t.powderM3 = exec_.sum(powder_.data(), valid_.data(), w, h) * area;
    return t;
  }

  float maxTemperatureBaseC() override {
    return exec_.maxValue(temperatureBase_.data(), valid_.data(), spec_.width, spec_.height);
  }

  Exec& exec() { return exec_; }

 private:
  BedformFields bedformFields() {
    BedformFields f;
    f.slabs = bedSlabs_.data();
    f.snapshot = bedSnapshot_.data();
    f.exported = bedExported_.data();
    f.arrived = bedArrived_.data();
    f.arrivedCohesion = bedArrivedCohesion_.data();
    f.counters = bedCounters_.data();
    f.cohesion = bedCohesion_.data();
    f.lastPowder = bedLastPowder_.data();
    f.base = bedBase_.data();
    f.initial = bedInitial_.data();
    f.shadow = bedShadow_.data();
    f.active = bedActive_.data();
    f.mask = hasBedformMask_ ? bedformMask_.data() : nullptr;
    return f;
  }

  SnowFieldsView view() {
    SnowFieldsView v;
    v.width = spec_.width;
    v.height = spec_.height;
    v.cellSizeXM = static_cast<float>(spec_.cellSizeXM);
    v.cellSizeYM = static_cast<float>(spec_.cellSizeYM);
    v.bedrock = bedrock_.data();
    v.compacted = compacted_.data();
    v.stable = stable_.data();
    v.unstable = unstable_.data();
    v.powder = powder_.data();
    v.moving = moving_.data();
    v.valid = valid_.data();
    v.exposure = exposure_.data();
    v.temperatureBase = temperatureBase_.data();
    v.windX = windX_.data();
    v.windY = windY_.data();
    v.windEffectZ = windEffectZ_.data();
    v.windLoading = windLoading_.data();
    v.windScour = windScour_.data();
    v.windDeposit = windDeposit_.data();
    v.melted = melted_.data();
    v.snowfallFactor = hasSnowfallFactor_ ? snowfallFactor_.data() : nullptr;
    v.meltFactor = hasMeltFactor_ ? meltFactor_.data() : nullptr;
    v.windErosionFactor = hasWindErosionFactor_ ? windErosionFactor_.data() : nullptr;
    v.bedformActive = bedformFieldsReady_ ? bedActive_.data() : nullptr;
    v.delta = delta_.data();
    v.surfaceSlope = surfaceSlope_.data();
    v.scratchSurface = scratchSurface_.data();
    v.scratchPowder = scratchPowder_.data();
    v.powderFlow = powderFlow_.data();
    v.flows = flows_.data();
    v.avalancheBefore = avalancheBefore_.data();
    v.avalancheU = avalancheU_.data();
    v.avalancheScour = avalancheScour_.data();
    v.avalancheDeposit = avalancheDeposit_.data();
    v.rowStats = rowStats_.data();
    return v;
  }

  Exec exec_;
  GridSpec spec_;
  typename Exec::template Buffer<float> bedrock_, compacted_, stable_, unstable_, powder_;
  typename Exec::template Buffer<uint8_t> moving_, valid_;
  typename Exec::template Buffer<float> exposure_, temperatureBase_, windX_, windY_, windEffectZ_, delta_, surfaceSlope_, scratchSurface_, scratchPowder_;
  typename Exec::template Buffer<float> windLoading_, windScour_, windDeposit_, melted_, powderFlow_;
  typename Exec::template Buffer<float> flows_, avalancheBefore_, avalancheScour_, avalancheDeposit_, rowStats_;
  typename Exec::template Buffer<double> avalancheU_;
  typename Exec::template Buffer<float> snowfallFactor_, meltFactor_, windErosionFactor_, editWeight_;
  bool hasSnowfallFactor_ = false, hasMeltFactor_ = false, hasWindErosionFactor_ = false;
  bool avalancheFieldsReady_ = false;
  typename Exec::template Buffer<int> bedSlabs_, bedSnapshot_, bedExported_, bedArrived_, bedArrivedCohesion_, bedInitial_;
  typename Exec::template Buffer<unsigned long long> bedCounters_;
  typename Exec::template Buffer<SkierAgent> skierAgents_;
  typename Exec::template Buffer<double> skierPath_;
  typename Exec::template Buffer<float> skierRoute_;
  typename Exec::template Buffer<int> skierClaim_, skierCounters_;
  typename Exec::template Buffer<float> bedCohesion_, bedLastPowder_, bedBase_;
  typename Exec::template Buffer<uint8_t> bedShadow_, bedActive_, bedformMask_;
  bool bedformFieldsReady_ = false, hasBedformMask_ = false;

  bool uploadOptional(typename Exec::template Buffer<float>& buffer, const Grid<float>& grid) {
    const bool present = grid.size() == spec_.cellCount() && grid.size() > 0;
    exec_.upload(buffer, present ? grid.values() : std::vector<float>());
    return present;
  }
};

}  // namespace snow
