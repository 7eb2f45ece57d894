// A rank's backend in a distributed season: the rank's own backend on its local grid, its halo
// refreshed after each phenomenon (continuous_step.h's reach), and every sum the season reads
// (the mass ledger, snowfall and melt volumes, the warmest cell) over the whole grid in the
// single process's order (exact_sum.h). runSeason on each rank's local state with it gives the
// single process's bytes for a season of snowfall, melt, stability, powder diffusion, wind
// transport and timeline edits. Avalanches, skiers and bedforms run on a replica of the whole
// grid that every rank holds and steps alike (replicateEvents, whole_replica.h), kept in step with
// the local grids as the season turns from one kind of phenomenon to the other; without one they
// throw std::logic_error, and distributedSeasonRefusal says so before a season starts.
#pragma once
#include <functional>
#include <memory>
#include <string>

#include "communicator.h"
#include "core/backend.h"
#include "core/season.h"
#include "decomposition.h"

namespace snow::dist {

// Whether `config` has avalanches, skiers or bedforms: its season runs them on the whole grid's
// replica (DistributedBackend::replicateEvents).
bool seasonNeedsReplica(const SeasonConfig& config);

// Why `config` (its parameters and events) cannot run across ranks on a backend without (or, with
// `replicated`, with) the whole grid's replica; empty when it can. A
// no-snow mask's removed snow (SeasonReport::noSnowRemovedM3) is the local grid's: remove
// it from the whole state before cutting (removeSnowOfNoSnowCells, as the bake does). The config's
// updateStaticFields, if any, must fill the rank's local grid: from the rank's cells of the
// precompute (the bake without a replica), or a day's whole-grid fields cut to it (cutFields,
// local_state.h).
std::string distributedSeasonRefusal(const SeasonConfig& config, bool replicated = false);

class DistributedBackend final : public SnowBackend {
 public:
  // `local` holds (once uploaded) the rank's local grid of `d`, whose halo is at least
  // kContinuousHalo (continuous_step.h); the halo is refreshed after each phenomenon and each
  // of powder diffusion's substeps. With `measureWaits`, a barrier before each refresh, so that
  // exchangeSeconds is the transfer alone and waitSeconds the wait for the slowest rank.
  DistributedBackend(std::unique_ptr<SnowBackend> local, const Communicator& comm, const Decomposition& d, bool measureWaits = false);

  DistributedBackend(const DistributedBackend&) = delete;  // local_'s substep hook holds `this`
  DistributedBackend& operator=(const DistributedBackend&) = delete;

  // Avalanches, skiers and bedforms on `replica`, a backend of the whole grid (in host memory)
  // that every rank steps alike: their runners work on the whole grid's cells
  // (SeasonConfig::eventTerrain = &whole). `whole` is the whole grid's state, holding the terrain,
  // art direction and each day's static fields (the replica's are uploaded from it whenever the
  // rank's are); the season's first upload hands its snow and record fields to the replica. Call
  // before that upload; `whole` must outlive the season.
  void replicateEvents(std::unique_ptr<SnowBackend> replica, SnowState& whole);

  std::string name() const override { return local_->name(); }
  void upload(const SnowState& s) override;
  void download(SnowState& s) override;
  void uploadTaking(SnowState& s) override;
  void downloadGiving(SnowState& s) override;
  void returnState(SnowState& s) override { local_->returnState(s); }
  void* hostField(SnowField f) override;
  void* hostScratch(ScratchField f) override;
  void releaseRouteMap() override;
  void releaseScratch(bool avalancheFields) override;
  void forEachHostChunk(int n, int chunk, const std::function<void(int, int)>& f) override { local_->forEachHostChunk(n, chunk, f); }
  uint64_t stateVersion() const override { return local_->stateVersion() + (replica_ ? replica_->stateVersion() : 0); }
  void uploadStaticFields(const SnowState& s) override;

  double snowfall(const SnowfallArgs& a) override;
  double melt(const MeltArgs& a) override;
  void powderDiffusion(const PowderDiffusionArgs& a) override;
  void windTransport(const WindTransportArgs& a) override;
  void stabilityChange(const StabilityArgs& a) override;
  LayerTotals totals() override;
  float maxTemperatureBaseC() override;

  // `weights` (empty, or one a cell of the whole grid) cut to the local grid.
  double applyEdit(const EditArgs& a, const std::vector<float>& weights) override;

  // On the whole grid's replica (whole-grid cells), brought up to date first.
  bool hostSnowLayers(const float* layers[4]) override;
  void readCells(int x0, int y0, int cols, int rows, std::vector<float>& depth, std::vector<float>& unstable) override;
  void downloadBox(SnowBox& box, bool peaks) override;
  BedformStepReport bedformStep(const BedformArgs& a) override;
  bool bedformCohesion(Grid<float>& out) override;
  void uploadRouteMap(const Grid<float>& route) override;
  void skierBatch(const SkierArgs& a, std::vector<SkierAgent>& agents, std::vector<std::vector<double>>& paths) override;
  void avalancheRelease(const std::vector<uint8_t>& moving, const AvalancheArgs& a) override;
  std::vector<float> avalancheSteps(const AvalancheArgs& a, int substeps) override;
  void avalancheSettle(const AvalancheArgs& a) override;

  // Bytes this rank has sent to refresh halos, and seconds spent doing it (and waiting before);
  // the seconds include bringing the replica up to date, whose bytes are replicaBytesSent's.
  size_t bytesSent() const { return bytesSent_; }
  double exchangeSeconds() const { return exchangeS_; }
  double waitSeconds() const { return waitS_; }
  // Times the whole grid's replica was brought up to date, and the bytes this rank sent for it.
  size_t replicaGathers() const { return replicaGathers_; }
  size_t replicaBytesSent() const { return replicaBytes_; }

 private:
  [[noreturn]] static void notYet(const char* what);
  void checkLocalGrid(const GridSpec& spec) const;
  void* field(SnowField f);
  void refreshHalo(bool powderOnly = false);
  // A step's `delta` over the owned cells, times the cell area in the kernels' float cell sizes:
  // what the single process's snowfall and melt return.
  double deltaVolume();
  double layerSum(SnowField layer);
  // Which of the local grids and the replica holds the snow as it is now: a phenomenon's step
  // on the one brings the other's changes in first (localUpToDate, replicaUpToDate).
  enum class Current { Both, Local, Replica };
  void localUpToDate();
  SnowBackend& replicaUpToDate(const char* what);
  void uploadReplica(const SnowState& local);
  void addBedformCohesion(SnowState& s);
  void wroteLocal() {
    if (replica_) current_ = Current::Local;
  }

  std::unique_ptr<SnowBackend> local_;
  Communicator comm_;
  Decomposition d_;
  HaloPlan plan_;
  GridSpec spec_;
  bool measureWaits_ = false;
  size_t bytesSent_ = 0;
  double exchangeS_ = 0.0, waitS_ = 0.0;
  std::unique_ptr<SnowBackend> replica_;
  SnowState* whole_ = nullptr;
  bool replicaUploaded_ = false;
  Current current_ = Current::Both;
  size_t replicaGathers_ = 0, replicaBytes_ = 0;
};

}  // namespace snow::dist
