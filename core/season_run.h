// The season's run behind runSeason (season.h): one object registers every phenomenon with the
// Poisson scheduler, then fires the events. Internal to core: season.cpp (the loop, snowfall,
// state changes, wind, edits, static fields, frames), season_avalanches.cpp and
// season_skiers.cpp.
#pragma once
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "scheduler.h"
#include "season.h"
#include "spill_file.h"
#include "util.h"

namespace snow {

// The phenomena registered with the scheduler (each add* function, in the order that fixes their
// slots and so the random draws; each phenomenon's module in core/phenomena/ names its add*), then
// the events fired until the last day. The scheduler's events call back into this object: it
// stays where it is while they run.
class SeasonRun {
 public:
  SeasonRun(SnowBackend& backend, SnowState& state, const SeasonConfig& cfg, const ProgressCallback& progress,
            const FrameCallback& onFrame, const AvalancheCallback& onAvalanche)
      : backend_(backend), state_(state), cfg_(cfg), p_(cfg.params), progress_(progress), onFrame_(onFrame),
        onAvalanche_(onAvalanche), scheduler_(cfg.seed) {}
  SeasonRun(const SeasonRun&) = delete;
  SeasonRun& operator=(const SeasonRun&) = delete;

  SeasonReport run();

 private:
  // A body run at a step of phenomenon `slot`, over `dt` days since its previous step.
  using ContinuousBody = std::function<void(int slot, double day, double dt)>;

  // The grid the runners of avalanches, skiers and bedforms work on (SeasonConfig::eventTerrain).
  const SnowState& terrain() const { return cfg_.eventTerrain ? *cfg_.eventTerrain : state_; }
  void fadeSkiTracks(const SnowState& frame);
  void leaveNoSnowCells();
  void releaseHostCopies();
  int addPhenomenon(PhenomenonSpec spec);
  template <class Body>
  void timed(int slot, Body&& body);
  double sinceLast(int slot, double day);
  void snowfallOver(int slot, double day);
  void addSnowfallPhenomenon(PhenomenonSpec s);
  void addSnowfall();
  void addContinuous(const char* name, double stepsPerDay, ContinuousBody body);
  void addStateChanges();
  // Counts a step whose kernel would change nothing, with why (for the log).
  void skipStep(int slot, const char* why);
  void bedformStep(int slot, double day, double dt);
  void addBedforms();
  void addTransport();
  void addEdits();
  // season_avalanches.cpp
  void releaseUser(const UserAvalanche& u, double day, double seaLevelTemperatureC);
  void startAvalanche(int slot, const EventContext& e);
  void stopAvalanche(int slot);
  void recordAvalanche(AvalancheRecord record);  // into the report, and to onAvalanche_ at once
  void trySpontaneousRelease(const EventContext& e, bool retry);
  void scheduleWaitingRelease(double day);
  void addAvalanches();
  // season_skiers.cpp
  void runSkiers(std::vector<SkierStart> starts, double day);
  std::vector<SkierStart> automaticSkierStarts(const EventContext& e);
  void addUserSkiers();
  void addSkiers();
  // season.cpp again
  void addStaticFieldRefresh();
  void addFrames();
  SnowState hostFrame() const;
  SnowState frameCopy();
  void writeLentFrame(double day);
  void setFrameAside(double day);
  void writeFramesSetAside(bool seasonEnd);
  void releaseScratch();
  void runEvents();
  void finish();

  SnowBackend& backend_;
  SnowState& state_;
  const SeasonConfig& cfg_;
  const ModelParameters& p_;
  const ProgressCallback& progress_;
  const FrameCallback& onFrame_;
  const AvalancheCallback& onAvalanche_;
  SeasonReport report_;
  PoissonScheduler scheduler_;
  std::vector<PhenomenonReport> reports_;  // by scheduler slot
  std::vector<double> lastStep_;           // by slot: the day of its previous step
  std::vector<std::function<void(double day)>> catchUp_;  // continuous phenomena, run at the end
  float maxTemperatureBase_ = 0.f;
  bool staticReleased_ = false;  // the host's static fields freed (refilled from day staticDay_ at the end)
  int staticDay_ = 0;
  // No-snow cells: the terrain's own valid cells, given back to the frames and the final state.
  bool noSnow_ = false;
  Grid<uint8_t> terrainValid_;
  // The domain's strongest wind (squared) for the bedforms, scanned again only after the daily
  // static-field refresh changed the wind (-1: to scan), not at every hourly step.
  double bedformWindiest_ = -1.0;
  bool bedformsMasked_ = false;  // state.bedformMask is painted: the bedforms run inside it only
  double bedformRoundCarry_ = 0.0;  // the fraction of a polling round owed to the next step
  uint64_t bedformRoundBase_ = 0;
  std::optional<AvalancheRun> avalanche_;
  std::deque<UserAvalanche> pendingAvalanches_;
  int avalancheId_ = -1;
  // Spontaneous releases that found no cell able to release, waiting for one (season_avalanches.cpp).
  int waitingReleases_ = 0;
  bool waitingRetryScheduled_ = false, retryingRelease_ = false;
  bool skiing_ = false;
  std::optional<SkiRun> ski_;
  uint64_t skierId_ = 0;
  // Frames whose instant fell inside an avalanche (SeasonConfig::lendFrames): their downloaded
  // fields and ski-track texture on disk until it settles.
  struct FrameSetAside {
    double day = 0;
    std::vector<SpillFile::Extent> fields;  // the downloaded fields', in forEachSnowField's order
    SpillFile::Extent skiDepth;
  };
  std::vector<FrameSetAside> framesSetAside_;
  std::unique_ptr<SpillFile> spill_;
};

template <class Body>
void SeasonRun::timed(int slot, Body&& body) {
  const auto start = WallClock::now();
  body();
  reports_[slot].seconds += elapsedSeconds(start);
}

}  // namespace snow
