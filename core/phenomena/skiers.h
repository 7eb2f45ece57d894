// Skiers (paper §6.2, §7.3): agents that descend the terrain, each move aimed at a cell ahead
// with probability proportional to Eq. 4, 1[snow_n >= ski_min_snow_m] f(|s_n - s_t|) w_d(n)
// (w_d from the route map, D(c) = max over lower neighbours n of D(n) + |cn|), compacting the
// snow of every cell they enter and possibly triggering an avalanche. The host runner
// core/ski_runs.h describes the model in full (route map, paths, refined tracks, track texture).
//
// The kernels for every executor: the route map's cellular automaton, and
// the agents of a batch of skiers moved together, one step of every skier at a time.
//
// A step of a batch (runSkierBatch) is three kernels:
//   SkierMoveKernel, one thread per skier: Eq. 4 over the cells ahead, the smooth turn, the move;
//     it reads the snow and writes only its own agent (skiers change no cell's surface, the only
//     thing a move reads, so every skier of the batch moves at once and in any order);
//   SkierClaimKernel and SkierEnterKernel, in rounds: each skier that entered a new cell claims
//     it (an integer atomic minimum of the skiers' indices) and the claim's winner applies its
//     entry (the snow check, the avalanche trigger, the compaction), so a cell is written by one
//     thread at a time, in skier order, whatever the schedule: the transport tiling's guarantee
//     (no cell written by two threads at once) for cells entered by any number of skiers. Rounds
//     repeat while a cell has skiers left to enter (one round when no two skiers share a cell).
// Only + - * / and sqrt on doubles (FMA contraction is off in the build) and integer atomics:
// the same bytes on the serial, TBB and CUDA executors. The weighting f uses atanPositive and
// expNonPositive (skier_kernels.h) instead of the libraries' atan2 and exp, which differ in the last bits
// between glibc and CUDA.
//
// Preconditions: the route map uploaded (uploadSkierRoute) before the first batch; the skiers'
// own buffers (SkierStorage below); no scratch field of the view.
// Mass: conserved (a compaction moves snow from U to S, or S to C).
// Backend: SnowBackend::routeMapOnDevice, uploadRouteMap and skierBatch (ExecBackend runs the
// functions below). Host runner: SkiRun (core/ski_runs.h). Season: SeasonRun::addSkiers
// (core/season_skiers.cpp). Parameters: the §6.2 blocks of ModelParameters (core/parameters.h;
// scene keys in parameterTable, parameters.cpp).
#pragma once
#include <algorithm>
#include <climits>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "../grid.h"
#include "../parameters.h"
#include "../util.h"
#include "skier_kernels.h"

namespace snow {

// The kernels' arguments for the parameters and the grid; `seed` seeds the batch's choices.
inline SkierArgs makeSkierArgs(const ModelParameters& p, const GridSpec& spec, uint64_t seed) {
  SkierArgs a;
  a.dx = spec.cellSizeXM;
  a.dy = spec.cellSizeYM;
  a.stepM = std::min(a.dx, a.dy);
  a.reach = std::max(1, static_cast<int>(std::lround(p.skiLookaheadM / a.stepM)));
  a.reachM = a.reach * a.stepM;
  a.targetRad = p.skierTargetSlopeDeg * kPi / 180.0;
  a.sigmaRad = p.skiSlopeToleranceDeg * kPi / 180.0;
  a.cosHalfCone = std::cos(100.0 * kPi / 180.0);
  a.tanRest = std::tan(p.avalancheRestAngleDeg * kPi / 180.0);
  a.minSnowM = p.skiMinSnowM;
  a.steering = p.skiSteering;
  a.triggerFactor = p.skiTriggerFactor;
  a.minUnstableM = p.avalancheMinUnstableM;
  a.compactionM = static_cast<float>(p.skiCompactionM);
  a.maxSteps = 4 * (spec.width + spec.height);
  a.seed = seed;
  return a;
}

// The skiers' buffers on an Exec's storage.
template <class Exec>
struct SkierStorage {
  template <class T>
  using Buffer = typename Exec::template Buffer<T>;
  Buffer<SkierAgent> agents;
  Buffer<double> path;
  Buffer<float> route;
  const float* hostRoute = nullptr;  // host storage: the caller's route map itself, not a copy in `route`
  Buffer<int> claim, counters;
  const float* routeData() { return hostRoute ? hostRoute : route.data(); }
};

// The route map the kernels read, with the claims and counters reset, for a grid of `cells`.
// On host storage the kernels read `route` itself, which must then outlive the batches.
template <class Exec>
void uploadSkierRoute(Exec& exec, SkierStorage<Exec>& storage, const std::vector<float>& route, size_t cells) {
  if constexpr (Exec::kDevice) exec.upload(storage.route, route);
  else storage.hostRoute = route.data();
  std::vector<int> unclaimed(cells, INT_MAX);
  exec.uploadTaking(storage.claim, unclaimed);
  exec.upload(storage.counters, std::vector<int>(2, 0));
  exec.finish();
}

// The route map by RouteMapStepKernel iterated to its fixed point, on a device Exec.
template <class Exec>
std::vector<float> runRouteMap(Exec& exec, const SnowFieldsView& v) {
  const int w = v.width, h = v.height;
  const float dx = v.cellSizeXM, dy = v.cellSizeYM, diagonal = std::sqrt(dx * dx + dy * dy);
  const size_t cells = static_cast<size_t>(w) * h;
  typename Exec::template Buffer<float> a, b;
  const std::vector<float> zero(cells, 0.f);
  exec.upload(a, zero);
  exec.upload(b, zero);
  std::vector<float> previous, latest;
  // Information moves one cell an iteration; compare the last two iterations every 16.
  for (size_t it = 1;; ++it) {
    auto& in = it % 2 ? a : b;
    auto& result = it % 2 ? b : a;
    exec.forEachCell(w, h, RouteMapStepKernel{v.bedrock, v.valid, in.data(), result.data(), w, h, dx, dy, diagonal});
    if (it % 16 == 0 || it > cells) {
      exec.download(in, previous);
      exec.download(result, latest);
      if (previous == latest) break;
    }
  }
  exec.finish();
  return latest;
}

// One batch of skiers moved together (runSkierBatch): the moves, the claim rounds of each move's
// entries, and the paths taken from the device every kChunk - 1 moves.
template <class Exec>
class SkierBatch {
 public:
  // The path buffer holds kChunk points a skier; the host empties it every kChunk - 1 moves (a
  // move adds at most one point; the start adds the first).
  static constexpr int kChunk = 64;

  SkierBatch(Exec& exec, const SnowFieldsView& v, SkierStorage<Exec>& storage, const SkierArgs& args,
             std::vector<SkierAgent>& agents, std::vector<std::vector<double>>& paths)
      : exec_(exec), v_(v), storage_(storage), agents_(agents), paths_(paths), n_(static_cast<int>(agents.size())) {
    a_ = args;
    a_.pathStride = kChunk;
  }

  void run() {
    exec_.upload(storage_.agents, agents_);
    exec_.upload(storage_.path, std::vector<double>(2 * static_cast<size_t>(kChunk) * n_));
    f_ = SkierFields{storage_.agents.data(), n_, storage_.path.data(), storage_.routeData(), storage_.claim.data(),
                     storage_.counters.data()};
    exec_.forEachIndex(n_, SkierStartKernel{v_, f_, a_});
    enterAll();
    for (int moves = 1;; ++moves) {
      resetCounter(0);
      exec_.forEachIndex(n_, SkierMoveKernel{v_, f_, a_});
      enterAll();
      const bool running = counter(0) > 0;
      if (!running || moves % (kChunk - 1) == 0) takePaths();
      if (!running) break;
    }
    exec_.finish();
  }

 private:
  int counter(int k) {
    int c = 0;
    exec_.downloadRange(storage_.counters, static_cast<size_t>(k), 1, &c);
    return c;
  }
  void resetCounter(int k) {
    const int zero = 0;
    exec_.uploadRange(storage_.counters, static_cast<size_t>(k), 1, &zero);
  }
  // Claim rounds until every entry of this move is applied (one when no two skiers share a cell).
  void enterAll() {
    for (int round = 0; round <= n_; ++round) {
      resetCounter(1);
      exec_.forEachIndex(n_, SkierClaimKernel{f_});
      exec_.forEachIndex(n_, SkierEnterKernel{v_, f_, a_});
      if (counter(1) == 0) return;
    }
    throw std::logic_error("skier entries: a claim round applied nothing");
  }
  // The points each skier added since the last take, appended to its path.
  void takePaths() {
    exec_.download(storage_.agents, agents_);
    for (int i = 0; i < n_; ++i) {
      SkierAgent& s = agents_[static_cast<size_t>(i)];
      if (s.pathCount == 0) continue;
      chunk_.resize(2 * static_cast<size_t>(s.pathCount));
      exec_.downloadRange(storage_.path, 2 * static_cast<size_t>(i) * kChunk, chunk_.size(), chunk_.data());
      paths_[static_cast<size_t>(i)].insert(paths_[static_cast<size_t>(i)].end(), chunk_.begin(), chunk_.end());
      s.pathCount = 0;
    }
    exec_.upload(storage_.agents, agents_);
  }

  Exec& exec_;
  const SnowFieldsView v_;
  SkierStorage<Exec>& storage_;
  std::vector<SkierAgent>& agents_;
  std::vector<std::vector<double>>& paths_;
  const int n_;
  SkierArgs a_;
  SkierFields f_;
  std::vector<double> chunk_;
};

// A batch of skiers moved together until all have stopped: in, each agent's startCell and id;
// out, their final state and each one's path as x, y pairs (metres).
template <class Exec>
void runSkierBatch(Exec& exec, const SnowFieldsView& v, SkierStorage<Exec>& storage, const SkierArgs& args,
                   std::vector<SkierAgent>& agents, std::vector<std::vector<double>>& paths) {
  paths.assign(agents.size(), {});
  if (agents.empty()) return;
  SkierBatch<Exec>(exec, v, storage, args, agents, paths).run();
}

}  // namespace snow
