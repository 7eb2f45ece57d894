#include "season.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <utility>

#include "rng.h"
#include "scheduler.h"
#include "step_args.h"

namespace snow {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

double SeasonReport::massBalanceRelativeError() const {
  const double expected = initial.totalM3() + snowfallAddedM3 - meltRemovedM3 + editsNetM3;
  const double scale = std::max({initial.totalM3() + snowfallAddedM3 + std::max(0.0, editsNetM3), final.totalM3(), 1e-30});
  return std::abs(final.totalM3() - expected) / scale;
}

void computeTemperatureBase(SnowState& s, const ModelParameters& p) {
  s.temperatureBaseC.resize(s.spec.width, s.spec.height);
  for (size_t i = 0; i < s.bedrockM.size(); ++i)
    s.temperatureBaseC.values()[i] = temperatureBaseC(p, s.bedrockM.values()[i], s.exposureHours.values()[i]);
}

namespace {

// One season's run: the phenomena registered with the scheduler (each add* below, in the order
// that fixes their slots and so the random draws), then the events fired until the last day.
// The scheduler's events call back into this object: it stays where it is while they run.
class SeasonRun {
 public:
  SeasonRun(SnowBackend& backend, SnowState& state, const SeasonConfig& cfg, const ProgressCallback& progress,
            const FrameCallback& onFrame)
      : backend_(backend), state_(state), cfg_(cfg), p_(cfg.params), progress_(progress), onFrame_(onFrame),
        scheduler_(cfg.seed) {}
  SeasonRun(const SeasonRun&) = delete;
  SeasonRun& operator=(const SeasonRun&) = delete;

  SeasonReport run() {
    const auto t0 = Clock::now();
    if (cfg_.updateStaticFields) cfg_.updateStaticFields(0, state_);
    leaveNoSnowCells();
    backend_.upload(state_);
    report_.initial = backend_.totals();
    maxTemperatureBase_ = backend_.maxTemperatureBaseC();
    addSnowfall();
    addStateChanges();
    addBedforms();
    addTransport();
    addEdits();
    addAvalanches();
    addSkiers();
    addStaticFieldRefresh();
    addFrames();
    runEvents();
    finish();
    report_.seconds = secondsSince(t0);
    return std::move(report_);
  }

 private:
  // A body run at a step of phenomenon `slot`, over `dt` days since its previous step.
  using ContinuousBody = std::function<void(int slot, double day, double dt)>;

  void leaveNoSnowCells();
  int addPhenomenon(PhenomenonSpec spec);
  template <class Body>
  void timed(int slot, Body&& body);
  double sinceLast(int slot, double day);
  void snowfallOver(int slot, double day);
  void addSnowfallPhenomenon(PhenomenonSpec s);
  void addSnowfall();
  void addContinuous(const char* name, double stepsPerDay, ContinuousBody body);
  void addStateChanges();
  void bedformStep(int slot, double day, double dt);
  void addBedforms();
  void addTransport();
  void addEdits();
  void releaseUser(const UserAvalanche& u, double day, double seaLevelTemperatureC);
  void startAvalanche(int slot, const EventContext& e);
  void stopAvalanche(int slot);
  void addAvalanches();
  void runSkiers(std::vector<SkierStart> starts, double day);
  std::vector<SkierStart> automaticSkierStarts(const EventContext& e);
  void addUserSkiers();
  void addSkiers();
  void addStaticFieldRefresh();
  void addFrames();
  void runEvents();
  void finish();

  SnowBackend& backend_;
  SnowState& state_;
  const SeasonConfig& cfg_;
  const ModelParameters& p_;
  const ProgressCallback& progress_;
  const FrameCallback& onFrame_;
  SeasonReport report_;
  PoissonScheduler scheduler_;
  std::vector<PhenomenonReport> reports_;  // by scheduler slot
  std::vector<double> lastStep_;           // by slot: the day of its previous step
  std::vector<std::function<void(double day)>> catchUp_;  // continuous phenomena, run at the end
  float maxTemperatureBase_ = 0.f;
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
  bool skiing_ = false;
  std::optional<SkiRun> ski_;
  uint64_t skierId_ = 0;
};

// No-snow cells leave the snow domain for the season: their snow goes, and the backend (and the
// avalanche and skier runners, built from the state later) see them as outside the terrain.
void SeasonRun::leaveNoSnowCells() {
  noSnow_ = state_.noSnow.size() == state_.spec.cellCount() && state_.noSnow.size() > 0;
  if (!noSnow_) return;
  terrainValid_ = state_.validCell;
  const double area = state_.spec.cellAreaM2();
  for (size_t i = 0; i < state_.noSnow.size(); ++i) {
    if (!state_.noSnow.values()[i]) continue;
    if (state_.validCell.values()[i])
      for (int l = 0; l < kSnowLayerCount; ++l) {
        float& d = state_.layer(static_cast<SnowLayer>(l)).values()[i];
        report_.noSnowRemovedM3 += static_cast<double>(d) * area;
        d = 0.f;
      }
    state_.validCell.values()[i] = 0;
  }
}

int SeasonRun::addPhenomenon(PhenomenonSpec spec) {
  reports_.push_back(PhenomenonReport{spec.name});
  lastStep_.push_back(0.0);
  return scheduler_.add(std::move(spec));
}

template <class Body>
void SeasonRun::timed(int slot, Body&& body) {
  const auto start = Clock::now();
  body();
  reports_[slot].seconds += secondsSince(start);
}

// Each step acts over the time since the phenomenon's previous step (or its start), not over
// the nominal 1 / stepsPerDay: the Poisson clock decides when steps happen, but a storm of
// three days adds three days of snow however many steps it drew, and a season melts for as
// long as it is warm. (With nominal steps, a fixed 4-day storm drew 9 steps in one run and 14
// in another: 30 % of the season's snow was the luck of the draw.) Continuous phenomena
// catch up at the season's end; episodic ones at their stop.
double SeasonRun::sinceLast(int slot, double day) {
  const double dt = std::max(0.0, day - lastStep_[slot]);
  lastStep_[slot] = day;
  return dt;
}

void SeasonRun::snowfallOver(int slot, double day) {
  const double dt = sinceLast(slot, day);
  if (dt > 0.0)
    timed(slot, [&] { report_.snowfallAddedM3 += backend_.snowfall(makeSnowfallArgs(p_, dt, cfg_.weather.at(day))); });
}

// A snowfall phenomenon: snow over the time since its start or previous step, and the rest at
// its stop or at the season's end.
void SeasonRun::addSnowfallPhenomenon(PhenomenonSpec s) {
  const int slot = static_cast<int>(reports_.size());
  s.onStart = [this, slot](const EventContext& e) { lastStep_[slot] = e.day; };
  s.onStep = [this, slot](const EventContext& e) { snowfallOver(slot, e.day); };
  s.onStop = [this, slot](const EventContext& e) { snowfallOver(slot, e.day); };
  catchUp_.push_back([this, slot](double day) {
    if (scheduler_.isActive(slot)) snowfallOver(slot, day);
  });
  addPhenomenon(std::move(s));
}

// Snowfall (§5.1): Poisson starts once a week, three days on average; or the fixed periods of
// the weather timeline. Storms asked for as user events run as their own fixed windows.
void SeasonRun::addSnowfall() {
  PhenomenonSpec s;
  s.name = "snowfall";
  s.stepsPerDay = p_.snowfallStepsPerDay;
  if (cfg_.weather.snowfallPeriods.empty()) {
    s.startsPerDay = p_.snowfallStartsPerDay;
    s.stopsPerDay = 1.0 / p_.snowfallMeanDurationDays;
  } else {
    for (const auto& w : cfg_.weather.snowfallPeriods) s.windows.push_back({w.startDay, w.endDay});
  }
  addSnowfallPhenomenon(std::move(s));
  if (cfg_.userSnowfalls.empty()) return;
  PhenomenonSpec user;
  user.name = "snowfall (user events)";
  user.stepsPerDay = p_.snowfallStepsPerDay;
  for (const auto& w : cfg_.userSnowfalls) user.windows.push_back({w.startDay, w.endDay});
  addSnowfallPhenomenon(std::move(user));
}

// Continuous phenomena, always active: `body(slot, day, dt)` runs at each step over the time
// since the previous one, and once more at the season's end.
void SeasonRun::addContinuous(const char* name, double stepsPerDay, ContinuousBody body) {
  PhenomenonSpec s;
  s.name = name;
  s.alwaysActive = true;
  s.stepsPerDay = stepsPerDay;
  const int slot = static_cast<int>(reports_.size());
  auto over = [this, slot, body = std::move(body)](double day) { body(slot, day, sinceLast(slot, day)); };
  s.onStep = [over](const EventContext& e) { over(e.day); };
  catchUp_.push_back(over);
  addPhenomenon(std::move(s));
}

// State changes (§5.2): melt, skipped on days when even the warmest cell is below T_0melt, and
// stability changes, skipped when it is below T_freeze and there is no wind loading.
void SeasonRun::addStateChanges() {
  addContinuous("melt", p_.stateChangeStepsPerDay, [this](int slot, double day, double dt) {
    const WeatherState w = cfg_.weather.at(day);
    if (w.seaLevelTemperatureC + maxTemperatureBase_ <= p_.meltThresholdC) {
      ++reports_[slot].skippedSteps;
      return;
    }
    timed(slot, [&] { report_.meltRemovedM3 -= backend_.melt(makeMeltArgs(p_, dt, w)); });
  });
  addContinuous("stability", p_.stateChangeStepsPerDay, [this](int slot, double day, double dt) {
    const WeatherState w = cfg_.weather.at(day);
    if (w.seaLevelTemperatureC + maxTemperatureBase_ <= p_.freezeTemperatureC &&
        !(cfg_.windTransport && p_.windInstabilityPerMps2 > 0)) {
      ++reports_[slot].skippedSteps;
      return;
    }
    timed(slot, [&] { backend_.stabilityChange(makeStabilityArgs(p_, dt, w)); });
  });
}

// One hourly bedform step: its polling rounds while some domain cell has wind above the
// threshold (else only the cohesion grows).
void SeasonRun::bedformStep(int slot, double day, double dt) {
  const BedformParameters& bp = *cfg_.bedforms;
  if (bedformWindiest_ < 0.0) {
    double maxSpeed = 0.0;
    for (size_t i = 0; i < state_.windXMps.size(); ++i) {
      if (!state_.validCell.values()[i] || (bedformsMasked_ && !state_.bedformMask.values()[i])) continue;
      const double wx = state_.windXMps.values()[i], wy = state_.windYMps.values()[i];
      maxSpeed = std::max(maxSpeed, wx * wx + wy * wy);
    }
    bedformWindiest_ = maxSpeed;
  }
  const bool windy = cfg_.windTransport && std::sqrt(bedformWindiest_) >= bp.thresholdWindMps;
  int rounds = 0;
  if (windy) {
    const double want = bedformRoundCarry_ + dt * 24.0 * bp.roundsPerHour;
    rounds = static_cast<int>(std::floor(want));
    bedformRoundCarry_ = want - rounds;
  } else {
    ++reports_[slot].skippedSteps;
    ++report_.bedforms.calmSteps;
  }
  const BedformStepReport r = backend_.bedformStep(
      makeBedformArgs(bp, dt, rounds, bedformRoundBase_, cfg_.seed, cfg_.weather.at(day).seaLevelTemperatureC));
  bedformRoundBase_ += static_cast<uint64_t>(rounds);
  report_.bedforms.rounds += rounds;
  report_.bedforms.slabsEroded += r.slabsEroded;
  report_.bedforms.slabsAvalanched += r.slabsAvalanched;
  report_.bedforms.domainCells = r.domainCells;
  report_.bedforms.atRest = report_.bedforms.atRest && r.reposeConverged;
}

// Wind bedforms (kernels/bedform.h), hourly steps of rounds_per_hour polling rounds each.
void SeasonRun::addBedforms() {
  bedformsMasked_ = state_.bedformMask.size() == state_.spec.cellCount() && state_.bedformMask.size() > 0;
  if (!cfg_.bedforms) return;
  addContinuous("wind bedforms", 24.0, [this](int slot, double day, double dt) {
    if (dt > 0.0) timed(slot, [&] { bedformStep(slot, day, dt); });
  });
}

// Wind transport (§5.4), only while the season has wind (the kernel leaves the bedforms' cells),
// and powder diffusion (§5.3).
void SeasonRun::addTransport() {
  if (cfg_.windTransport)
    addContinuous("wind transport", p_.windTransportStepsPerDay, [this](int slot, double, double dt) {
      if (dt > 0.0) timed(slot, [&] { backend_.windTransport(makeWindTransportArgs(p_, dt)); });
    });
  addContinuous("powder diffusion", p_.diffusionStepsPerDay, [this](int slot, double, double dt) {
    if (dt > 0.0) timed(slot, [&] { backend_.powderDiffusion(makePowderDiffusionArgs(p_, dt)); });
  });
}

// Timeline edits (art direction), before the avalanches and skiers of the same day.
void SeasonRun::addEdits() {
  for (const SeasonEdit& edit : cfg_.edits) {
    if (edit.day < 0.0 || edit.day > cfg_.days) continue;
    scheduler_.addAction(edit.day, [this, &edit](double now) {
      const double added = backend_.applyEdit(edit.args, edit.weights ? *edit.weights : std::vector<float>());
      report_.editsNetM3 += added;
      report_.edits.push_back({now, edit.label, added});
    });
  }
}

void SeasonRun::releaseUser(const UserAvalanche& u, double day, double seaLevelTemperatureC) {
  if (u.zone) avalanche_->releaseZone(*u.zone, day, seaLevelTemperatureC, !u.bySkier);
  else avalanche_->release(u.x, u.y, day, seaLevelTemperatureC, !u.bySkier);
}

// An avalanche's start: the first pending user (or skier) release, else a spontaneous try.
void SeasonRun::startAvalanche(int slot, const EventContext& e) {
  timed(slot, [&] {
    const double t0 = cfg_.weather.at(e.day).seaLevelTemperatureC;
    if (!pendingAvalanches_.empty()) {
      const UserAvalanche u = pendingAvalanches_.front();
      pendingAvalanches_.pop_front();
      releaseUser(u, e.day, t0);
      if (!avalanche_->active()) report_.avalanches.push_back(avalanche_->record());
    } else {
      const RandomKey key{cfg_.seed};
      const Philox4x32 r = key.draw(e.eventIndex, 0, RngStream::Avalanche);
      ++report_.avalancheTries;
      avalanche_->trySpontaneous(uniformOpenDouble(r.v[0], r.v[1]), uniformOpenDouble(r.v[2], r.v[3]), e.day, t0);
    }
  });
}

// An avalanche's stop: it settles, then the user releases that came while it ran, one after the
// other.
void SeasonRun::stopAvalanche(int slot) {
  if (avalanche_->active()) timed(slot, [&] { report_.avalanches.push_back(avalanche_->settle()); });
  while (!pendingAvalanches_.empty()) {
    const UserAvalanche u = pendingAvalanches_.front();
    pendingAvalanches_.pop_front();
    timed(slot, [&] {
      releaseUser(u, u.day, cfg_.weather.at(u.day).seaLevelTemperatureC);
      report_.avalanches.push_back(avalanche_->runToRest());
    });
  }
}

// Avalanches (§6.1): spontaneous release tries at about one a week per km^2 (each at a random
// cell, released with a probability from its unstable depth and slope above the rest angle),
// and the scene's user releases. A zoomed phenomenon: while one runs, its steps of 0.1 s are
// the only events (§3.1's temporal zoom). The runner (which keeps host copies of the state)
// exists only when the season can have avalanches.
void SeasonRun::addAvalanches() {
  skiing_ = (p_.skiersPerHour > 0.0 && p_.skiHoursPerDay > 0.0) || !cfg_.userSkiers.empty();
  double validCells = 0;
  for (uint8_t v : state_.validCell.values()) validCells += v;
  const double areaKm2 = validCells * state_.spec.cellAreaM2() * 1e-6;
  const double startsPerDay = p_.avalancheRatePerKm2PerDay * areaKm2;
  if (startsPerDay > 0.0 || !cfg_.userAvalanches.empty() || (skiing_ && p_.skiTriggerFactor > 0.0)) {
    avalanche_.emplace(backend_, p_, state_);
    avalanche_->keepMaps(cfg_.avalancheMaps, cfg_.avalancheFrameIntervalS);
    PhenomenonSpec s;
    s.name = "avalanche";
    s.zoomed = true;
    s.startsPerDay = startsPerDay;
    s.stepsPerDay = 86400.0 / p_.avalancheStepS;
    const int slot = static_cast<int>(reports_.size());
    s.onStart = [this, slot](const EventContext& e) { startAvalanche(slot, e); };
    s.onStep = [this, slot](const EventContext&) {
      if (avalanche_->active()) timed(slot, [&] { avalanche_->step(); });
    };
    s.finished = [this] { return !avalanche_->active() || avalanche_->atRest(); };
    s.onStop = [this, slot](const EventContext&) { stopAvalanche(slot); };
    avalancheId_ = addPhenomenon(std::move(s));
  }
  for (const UserAvalanche& u : cfg_.userAvalanches) {
    if (u.day < 0.0 || u.day > cfg_.days) continue;
    scheduler_.addAction(u.day, [this, u](double) {
      pendingAvalanches_.push_back(u);
      scheduler_.start(avalancheId_);
    });
  }
}

// A batch of skiers moved together to the end of their descents; the avalanches they trigger
// start after the batch, in skier order.
void SeasonRun::runSkiers(std::vector<SkierStart> starts, double day) {
  if (starts.empty()) return;
  for (SkierStart& st : starts) st.id = skierId_++;
  std::vector<SkierRecord> records = ski_->descendTogether(starts, day, cfg_.seed);
  for (SkierRecord& r : records) {
    if (r.triggered && avalancheId_ >= 0) {
      pendingAvalanches_.push_back({day, r.triggerX, r.triggerY, true, nullptr});
      scheduler_.start(avalancheId_);
    }
    if (!r.user) r.path.clear();  // keep the records small; user skiers keep their paths
    report_.skiers.push_back(std::move(r));
  }
}

// An hour's automatic skiers: a Poisson number, each skier's cell drawn by the route map until
// one has snow enough to ski (at most 16 draws).
std::vector<SkierStart> SeasonRun::automaticSkierStarts(const EventContext& e) {
  const RandomKey key{cfg_.seed};
  const int count = poissonCount(p_.skiersPerHour, [&](uint32_t k) {
    const Philox4x32 r = key.draw(e.eventIndex, k, RngStream::SkierCount);
    return uniformOpenDouble(r.v[0], r.v[1]);
  });
  std::vector<SkierStart> starts;
  for (int k = 0; k < count; ++k)
    for (uint32_t attempt = 0; attempt < 16; ++attempt) {
      const Philox4x32 r = key.draw(e.eventIndex, static_cast<uint32_t>(k) * 16u + attempt, RngStream::Skier);
      int x = 0, y = 0;
      if (!ski_->pickStart(uniformOpenDouble(r.v[0], r.v[1]), x, y)) break;
      if (!ski_->canStart(x, y)) continue;
      starts.push_back({x, y, 0, false});
      break;
    }
  return starts;
}

// The scene's user skiers (a group starts together): from their cell, or from a start mask, each
// skier's start cell drawn by the mask's weights (valid cells only), redrawn (up to 16 times)
// until it has snow enough to ski.
void SeasonRun::addUserSkiers() {
  uint64_t maskedSkierDraws = 0;
  for (const UserSkier& u : cfg_.userSkiers) {
    if (u.day < 0.0 || u.day > cfg_.days) continue;
    if (!u.startWeights) {
      scheduler_.addAction(u.day, [this, u](double now) {
        runSkiers(std::vector<SkierStart>(static_cast<size_t>(u.count), SkierStart{u.x, u.y, 0, true}), now);
      });
      continue;
    }
    auto cumulative = std::make_shared<std::vector<double>>(u.startWeights->size());
    double sum = 0.0;
    for (size_t i = 0; i < cumulative->size(); ++i)
      (*cumulative)[i] = (sum += state_.validCell.values()[i] ? std::max(0.f, (*u.startWeights)[i]) : 0.f);
    const uint64_t stream = maskedSkierDraws++;
    scheduler_.addAction(u.day, [this, u, cumulative, stream](double now) {
      const RandomKey key{cfg_.seed};
      std::vector<SkierStart> starts;
      for (int k = 0; k < u.count; ++k)
        for (uint32_t attempt = 0; attempt < 16; ++attempt) {
          const Philox4x32 r = key.draw(stream, static_cast<uint32_t>(k) * 16u + attempt, RngStream::SkierStartMask);
          const long long i = pickByCumulativeWeight(*cumulative, uniformOpenDouble(r.v[0], r.v[1]));
          if (i < 0) break;
          const int x = static_cast<int>(i % state_.spec.width), y = static_cast<int>(i / state_.spec.width);
          if (!ski_->canStart(x, y)) continue;
          starts.push_back({x, y, 0, true});
          break;
        }
      runSkiers(std::move(starts), now);
    });
  }
}

// Skiers (§6.2, §7.3): automatic ones, about skiers_per_hour in each of the day's
// ski_hours_per_day hours (an hour's skiers start together from cells drawn by the route map),
// and the scene's user skiers. The skiers of a batch move together on the backend, one move of
// each at a time (kernels/ski.h); the bake has no real-time display, so a batch runs to its end
// at its event.
void SeasonRun::addSkiers() {
  if (!skiing_) return;
  ski_.emplace(backend_, p_, state_, cfg_.skiTracks);
  if (p_.skiersPerHour > 0.0 && p_.skiHoursPerDay > 0.0) {
    PhenomenonSpec s;
    s.name = "skier";
    s.alwaysActive = true;
    s.stepsPerDay = p_.skiHoursPerDay;
    const int slot = static_cast<int>(reports_.size());
    s.onStep = [this, slot](const EventContext& e) {
      timed(slot, [&] { runSkiers(automaticSkierStarts(e), e.day); });
    };
    addPhenomenon(std::move(s));
  }
  addUserSkiers();
}

// Per-day static fields: refilled at the start of every day after the first, and uploaded.
void SeasonRun::addStaticFieldRefresh() {
  if (!cfg_.updateStaticFields) return;
  for (int day = 1; day < cfg_.days; ++day)
    scheduler_.addAction(day, [this, day](double) {
      cfg_.updateStaticFields(day, state_);
      backend_.uploadStaticFields(state_);
      bedformWindiest_ = -1.0;  // the wind changed: the bedforms scan it again
      maxTemperatureBase_ = backend_.maxTemperatureBaseC();
    });
}

void SeasonRun::addFrames() {
  for (double day : cfg_.frameDays) {
    if (day < 0.0 || day > cfg_.days || !onFrame_) continue;
    scheduler_.addAction(day, [this](double now) {
      SnowState frame = state_;
      if (noSnow_) frame.validCell = terrainValid_;
      backend_.download(frame);
      if (cfg_.skiTracks) cfg_.skiTracks->fade(frame);
      onFrame_(now, frame);
    });
  }
}

// The event loop: events drawn and fired to the season's last day (progress once a day), then
// the continuous phenomena's catch-up over the time since their last step.
void SeasonRun::runEvents() {
  double lastReported = -1.0;
  scheduler_.runUntil(cfg_.days, [&](double day) {
    if (progress_ && day - lastReported >= 1.0) {
      lastReported = day;
      progress_(std::min(1.0, day / cfg_.days));
    }
  });
  for (const auto& f : catchUp_) f(cfg_.days);
  if (progress_) progress_(1.0);
}

// The final state (with the terrain's own valid cells and faded ski tracks) and the report.
void SeasonRun::finish() {
  backend_.download(state_);
  if (noSnow_) state_.validCell = std::move(terrainValid_);
  if (cfg_.skiTracks) cfg_.skiTracks->fade(state_);
  report_.final = backend_.totals();
  const auto stats = scheduler_.stats();
  for (size_t i = 0; i < stats.size(); ++i) {
    reports_[i].starts = stats[i].starts;
    reports_[i].steps = stats[i].steps;
    reports_[i].stops = stats[i].stops;
  }
  report_.phenomena = std::move(reports_);
  report_.events = scheduler_.eventsFired();
}

}  // namespace

SeasonReport runSeason(SnowBackend& backend, SnowState& state, const SeasonConfig& cfg,
                       const ProgressCallback& progress, const FrameCallback& onFrame) {
  SeasonRun run(backend, state, cfg, progress, onFrame);
  return run.run();
}

}  // namespace snow
