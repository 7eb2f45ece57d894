// A rank's backend in a distributed season: the rank's own backend on its local grid, its halo
// refreshed after each phenomenon (continuous_step.h's reach), and every sum the season reads
// (the mass ledger, snowfall and melt volumes, the warmest cell) over the whole grid in the
// single process's order (exact_sum.h). runSeason on each rank's local state with it gives the
// single process's bytes for a season of snowfall, melt, stability, powder diffusion, wind
// transport and timeline edits; the phenomena that are not across ranks yet (avalanches, skiers,
// bedforms) throw std::logic_error, and distributedSeasonRefusal says so before a season starts.
#pragma once
#include <memory>
#include <string>

#include "communicator.h"
#include "core/backend.h"
#include "core/season.h"
#include "decomposition.h"

namespace snow::dist {

// Why `config` (its parameters and events) cannot run across ranks yet; empty when it can. A
// no-snow mask's removed snow (SeasonReport::noSnowRemovedM3) is the local grid's: remove
// it from the whole state before cutting (removeSnowOfNoSnowCells, as the bake does). The config's
// updateStaticFields, if any, must fill the rank's local grid: cutFields (local_state.h) cuts a
// day's whole-grid fields to it.
std::string distributedSeasonRefusal(const SeasonConfig& config);

class DistributedBackend final : public SnowBackend {
 public:
  // `local` holds (once uploaded) the rank's local grid of `d`, whose halo is at least
  // kContinuousHalo (continuous_step.h); the halo is refreshed after each phenomenon and each
  // of powder diffusion's substeps. With `measureWaits`, a barrier before each refresh, so that
  // exchangeSeconds is the transfer alone and waitSeconds the wait for the slowest rank.
  DistributedBackend(std::unique_ptr<SnowBackend> local, const Communicator& comm, const Decomposition& d, bool measureWaits = false);

  DistributedBackend(const DistributedBackend&) = delete;  // local_'s substep hook holds `this`
  DistributedBackend& operator=(const DistributedBackend&) = delete;

  std::string name() const override { return local_->name(); }
  void upload(const SnowState& s) override;
  void download(SnowState& s) override { local_->download(s); }
  void uploadTaking(SnowState& s) override;
  void downloadGiving(SnowState& s) override { local_->downloadGiving(s); }
  void returnState(SnowState& s) override { local_->returnState(s); }
  void* hostField(SnowField f) override { return local_->hostField(f); }
  void* hostScratch(ScratchField f) override { return local_->hostScratch(f); }
  void releaseRouteMap() override { local_->releaseRouteMap(); }
  void releaseScratch(bool avalancheFields) override { local_->releaseScratch(avalancheFields); }
  uint64_t stateVersion() const override { return local_->stateVersion(); }
  void uploadStaticFields(const SnowState& s) override { local_->uploadStaticFields(s); }

  double snowfall(const SnowfallArgs& a) override;
  double melt(const MeltArgs& a) override;
  void powderDiffusion(const PowderDiffusionArgs& a) override;
  void windTransport(const WindTransportArgs& a) override;
  void stabilityChange(const StabilityArgs& a) override;
  LayerTotals totals() override;
  float maxTemperatureBaseC() override;

  // `weights` (empty, or one a cell of the whole grid) cut to the local grid.
  double applyEdit(const EditArgs& a, const std::vector<float>& weights) override;

  // Not across ranks yet.
  void readCells(int, int, int, int, std::vector<float>&, std::vector<float>&) override { notYet("skiers and avalanches"); }
  void downloadBox(SnowBox&, bool) override { notYet("avalanches"); }
  BedformStepReport bedformStep(const BedformArgs&) override { notYet("wind bedforms"); }
  bool bedformCohesion(Grid<float>&) override { notYet("wind bedforms"); }
  void uploadRouteMap(const Grid<float>&) override { notYet("skiers"); }
  void skierBatch(const SkierArgs&, std::vector<SkierAgent>&, std::vector<std::vector<double>>&) override { notYet("skiers"); }
  void avalancheRelease(const std::vector<uint8_t>&, const AvalancheArgs&) override { notYet("avalanches"); }
  std::vector<float> avalancheSteps(const AvalancheArgs&, int) override { notYet("avalanches"); }
  void avalancheSettle(const AvalancheArgs&) override { notYet("avalanches"); }

  // Bytes this rank has sent to refresh halos, and seconds spent doing it (and waiting before).
  size_t bytesSent() const { return bytesSent_; }
  double exchangeSeconds() const { return exchangeS_; }
  double waitSeconds() const { return waitS_; }

 private:
  [[noreturn]] static void notYet(const char* what);
  void checkLocalGrid(const GridSpec& spec) const;
  void* field(SnowField f);
  void refreshHalo(bool powderOnly = false);
  // A step's `delta` over the owned cells, times the cell area in the kernels' float cell sizes:
  // what the single process's snowfall and melt return.
  double deltaVolume();
  double layerSum(SnowField layer);

  std::unique_ptr<SnowBackend> local_;
  Communicator comm_;
  Decomposition d_;
  HaloPlan plan_;
  GridSpec spec_;
  bool measureWaits_ = false;
  size_t bytesSent_ = 0;
  double exchangeS_ = 0.0, waitS_ = 0.0;
};

}  // namespace snow::dist
