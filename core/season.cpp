#include "season.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <utility>

#include "release_memory.h"
#include "season_run.h"

namespace snow {

double SeasonReport::massBalanceRelativeError() const {
  const double expected = initial.totalM3() + snowfallAddedM3 - meltRemovedM3 + editsNetM3;
  const double scale = std::max({initial.totalM3() + snowfallAddedM3 + std::max(0.0, editsNetM3), final.totalM3(), 1e-30});
  return std::abs(final.totalM3() - expected) / scale;
}

SnowFieldSet recordFieldsToKeep(SnowFieldSet read, bool avalancheMaps) {
  const SnowFieldSet seasonPeaks = fieldBit(SnowField::avalancheSeasonPeakThicknessM) | fieldBit(SnowField::avalancheSeasonPeakSpeedMps);
  const SnowFieldSet peaks = fieldBit(SnowField::avalanchePeakThicknessM) | fieldBit(SnowField::avalanchePeakSpeedMps);
  SnowFieldSet kept = read & kAllRecordFields;
  if ((kept & (seasonPeaks | peaks)) || avalancheMaps) kept |= peaks;
  return kept;
}

void computeTemperatureBase(SnowState& s, const ModelParameters& p) {
  s.temperatureBaseC.resize(s.spec.width, s.spec.height);
  for (size_t i = 0; i < s.bedrockM.size(); ++i)
    s.temperatureBaseC.values()[i] = temperatureBaseC(p, s.bedrockM.values()[i], s.exposureHours.values()[i]);
}

SeasonReport SeasonRun::run() {
  const auto t0 = WallClock::now();
  if (cfg_.updateStaticFields) cfg_.updateStaticFields(0, state_);
  leaveNoSnowCells();
  // The record fields the season keeps, zero where the state has none yet; the others freed.
  state_.restoreFields([](FieldRole r) { return r == FieldRole::Record; }, cfg_.recordFields);
  state_.keepRecordFields(cfg_.recordFields);
  backend_.uploadTaking(state_);  // the host's copies of what the backend evolves handed over
  releaseHostCopies();
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
  report_.seconds = elapsedSeconds(t0);
  return std::move(report_);
}

// No-snow cells leave the snow domain for the season: their snow goes, and the backend (and the
// avalanche and skier runners, built from the state later) see them as outside the terrain.
void SeasonRun::leaveNoSnowCells() {
  noSnow_ = state_.noSnow.size() == state_.spec.cellCount() && state_.noSnow.size() > 0;
  if (!noSnow_) return;
  terrainValid_ = state_.validCell;
  report_.noSnowRemovedM3 += removeSnowOfNoSnowCells(state_);
  leaveNoSnowCellsOutside(state_);
}

void leaveNoSnowCellsOutside(SnowState& s) {
  for (size_t i = 0; i < s.noSnow.size(); ++i)
    if (s.noSnow.values()[i]) s.validCell.values()[i] = 0;
}

double removeSnowOfNoSnowCells(SnowState& s) {
  double removed = 0.0;
  const double area = s.spec.cellAreaM2();
  for (size_t i = 0; i < s.noSnow.size(); ++i) {
    if (!s.noSnow.values()[i] || !s.validCell.values()[i]) continue;
    for (int l = 0; l < kSnowLayerCount; ++l) {
      float& d = s.layer(static_cast<SnowLayer>(l)).values()[i];
      removed += static_cast<double>(d) * area;
      d = 0.f;
    }
  }
  return removed;
}

// While the backend holds the snow, the host's copies of the fields it downloads are freed (the
// frames and the season's end download them again), and so are the static fields when they are
// refilled each day (and the bedforms do not scan the host's wind): the host keeps the terrain.
void SeasonRun::releaseHostCopies() {
  state_.releaseFields(downloadedWithState);
  staticReleased_ = cfg_.updateStaticFields && !cfg_.bedforms;
  if (staticReleased_) state_.releaseFields([](FieldRole r) { return r == FieldRole::Static; });
}

int SeasonRun::addPhenomenon(PhenomenonSpec spec) {
  reports_.push_back(PhenomenonReport{spec.name});
  lastStep_.push_back(0.0);
  return scheduler_.add(std::move(spec));
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
  if (!(dt > 0.0)) return;
  const WeatherState w = cfg_.weather.at(day);
  // No snow falls anywhere (the kernel would add nothing): the step is skipped.
  if (!(p_.snowfallRatePerDay > 0.0)) return skipStep(slot, "snowfall_rate_per_day = 0");
  if (!(w.snowfallIntensity > 0.0)) return skipStep(slot, "weather.keyframe.snowfall_intensity = 0");
  timed(slot, [&] { report_.snowfallAddedM3 += backend_.snowfall(makeSnowfallArgs(p_, dt, w)); });
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
// stability changes, skipped when it is below T_freeze and there is no wind loading. A rate of
// zero changes nothing: its steps are skipped too (the kernels would leave every byte as it is).
void SeasonRun::addStateChanges() {
  const bool melts = p_.meltRateMPerDayPerC > 0.0;
  addContinuous("melt", p_.stateChangeStepsPerDay, [this, melts](int slot, double day, double dt) {
    const WeatherState w = cfg_.weather.at(day);
    if (!melts) return skipStep(slot, "melt_rate_m_per_day_per_c = 0");
    if (w.seaLevelTemperatureC + maxTemperatureBase_ <= p_.meltThresholdC) return skipStep(slot, "colder than T_0melt everywhere");
    timed(slot, [&] { report_.meltRemovedM3 -= backend_.melt(makeMeltArgs(p_, dt, w)); });
  });
  const bool windLoads = cfg_.windTransport && p_.windInstabilityPerMps2 > 0;
  const bool changes = p_.instabilityByWarmthMPerDay > 0.0 || p_.stabilityByColdMPerDay > 0.0 || windLoads;
  addContinuous("stability", p_.stateChangeStepsPerDay, [this, changes, windLoads](int slot, double day, double dt) {
    const WeatherState w = cfg_.weather.at(day);
    if (!changes) return skipStep(slot, "instability_by_warmth_m_per_day = stability_by_cold_m_per_day = 0, no wind loading");
    if (w.seaLevelTemperatureC + maxTemperatureBase_ <= p_.freezeTemperatureC && !windLoads)
      return skipStep(slot, "colder than T_freeze everywhere, no wind loading");
    timed(slot, [&] { backend_.stabilityChange(makeStabilityArgs(p_, dt, w)); });
  });
}

void SeasonRun::skipStep(int slot, const char* why) {
  ++reports_[slot].skippedSteps;
  reports_[slot].skippedWhy = why;
}

// One hourly bedform step: its polling rounds while some domain cell has wind above the
// threshold (else only the cohesion grows).
void SeasonRun::bedformStep(int slot, double day, double dt) {
  const BedformParameters& bp = *cfg_.bedforms;
  if (bedformWindiest_ < 0.0) {
    const SnowState& t = terrain();
    double maxSpeed = 0.0;
    for (size_t i = 0; i < t.windXMps.size(); ++i) {
      if (!t.validCell.values()[i] || (bedformsMasked_ && !t.bedformMask.values()[i])) continue;
      const double wx = t.windXMps.values()[i], wy = t.windYMps.values()[i];
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
    skipStep(slot, "no wind above the bedforms' threshold");
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

// Wind bedforms (phenomena/bedforms.h), hourly steps of rounds_per_hour polling rounds each.
void SeasonRun::addBedforms() {
  const SnowState& t = terrain();
  bedformsMasked_ = t.bedformMask.size() == t.spec.cellCount() && t.bedformMask.size() > 0;
  if (!cfg_.bedforms) return;
  addContinuous("wind bedforms", 24.0, [this](int slot, double day, double dt) {
    if (dt > 0.0) timed(slot, [&] { bedformStep(slot, day, dt); });
  });
}

// Wind transport (§5.4), only while the season has wind (the kernel leaves the bedforms' cells),
// and powder diffusion (§5.3); each skipped where its rate is zero (no share is ever given).
void SeasonRun::addTransport() {
  const bool erodes = p_.windErosionRateMPerSPerDay > 0.0;
  if (cfg_.windTransport)
    addContinuous("wind transport", p_.windTransportStepsPerDay, [this, erodes](int slot, double, double dt) {
      if (!erodes) return skipStep(slot, "wind_erosion_rate_m_per_s_per_day = 0");
      if (dt > 0.0) timed(slot, [&] { backend_.windTransport(makeWindTransportArgs(p_, dt)); });
    });
  const bool creeps = p_.diffusionRatePerDay > 0.0;
  addContinuous("powder diffusion", p_.diffusionStepsPerDay, [this, creeps](int slot, double, double dt) {
    if (!creeps) return skipStep(slot, "diffusion_rate_per_day = 0");
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

// Per-day static fields: refilled at the start of every day after the first, and uploaded.
void SeasonRun::addStaticFieldRefresh() {
  if (!cfg_.updateStaticFields) return;
  for (int day = 1; day < cfg_.days; ++day)
    scheduler_.addAction(day, [this, day](double) {
      cfg_.updateStaticFields(day, state_);
      backend_.uploadStaticFields(state_);
      staticDay_ = day;
      releaseHostCopies();
      bedformWindiest_ = -1.0;  // the wind changed: the bedforms scan it again
      maxTemperatureBase_ = backend_.maxTemperatureBaseC();
    });
}

void SeasonRun::addFrames() {
  for (double day : cfg_.frameDays) {
    if (!frameDayInSeason(day, cfg_.days) || !onFrame_) continue;
    scheduler_.addAction(day, [this](double now) {
      if (!cfg_.lendFrames) {
        SnowState frame = frameCopy();
        return onFrame_(now, frame);
      }
      if (avalanche_ && avalanche_->active()) return setFrameAside(now);
      writeLentFrame(now);
    });
  }
}

namespace {
// The fields a frame set aside keeps on disk: what a frame downloads.
bool setAside(FieldRole r) { return downloadedWithState(r) || r == FieldRole::BedformResult; }
}  // namespace

// The host's own fields of a frame: terrain and host-only (its copies of the backend's were
// released), with the terrain's own valid cells.
SnowState SeasonRun::hostFrame() const {
  SnowState frame = state_;
  if (noSnow_) frame.validCell = terrainValid_;
  return frame;
}

// The state now, on the host: hostFrame and a download of the rest, with the record fields the
// season keeps only; the ski-track texture faded to it.
SnowState SeasonRun::frameCopy() {
  SnowState frame = hostFrame();
  frame.restoreFields(downloadedWithState, cfg_.recordFields);
  backend_.download(frame);
  fadeSkiTracks(frame);
  return frame;
}

// The ski-track texture faded to `frame`'s snow surface, or, across ranks, to the backend's whole
// grid (the texture's).
void SeasonRun::fadeSkiTracks(const SnowState& frame) {
  if (!cfg_.skiTracks) return;
  if (!cfg_.eventTerrain) return cfg_.skiTracks->fade(frame);
  const float* layers[4];
  if (!backend_.hostSnowLayers(layers)) throw std::logic_error("the ski-track texture of a rank's season needs the whole grid's layers in host memory");
  cfg_.skiTracks->fade(cfg_.eventTerrain->bedrockM, layers);
}

// Between events no step holds the backend's scratch, the avalanche runner's snapshot (none in
// motion) or the skiers' storage: freed for a frame, made again as the season goes on.
void SeasonRun::releaseScratch() {
  backend_.releaseScratch(true);
  if (avalanche_) avalanche_->releaseScratch();
  releaseFreedMemory();  // back to the system, not kept in this thread's arena for the writers' threads to miss
}

// A frame from the backend's own fields, lent to the host's state and taken back as they were.
void SeasonRun::writeLentFrame(double day) {
  releaseScratch();
  const Grid<float> hostCohesion = state_.bedformCohesion;  // a download replaces it once bedforms ran
  if (noSnow_) std::swap(state_.validCell, terrainValid_);
  backend_.downloadGiving(state_);
  fadeSkiTracks(state_);
  onFrame_(day, state_);
  backend_.returnState(state_);
  if (noSnow_) std::swap(state_.validCell, terrainValid_);
  state_.bedformCohesion = hostCohesion;
  if (ski_) ski_->uploadRouteMap();
}

// A frame whose instant falls inside an avalanche (whose fields the backend holds until it
// settles): its copy set aside on disk, written by writeFramesSetAside.
void SeasonRun::setFrameAside(double day) {
  SnowState frame = frameCopy();
  if (!spill_) spill_ = std::make_unique<SpillFile>(cfg_.spillFolder);
  FrameSetAside f;
  f.day = day;
  forEachSnowField(frame, [&](const SnowFieldInfo& info, auto& grid) {
    if (setAside(info.role)) f.fields.push_back(spill_->put(grid.values()));
  });
  if (cfg_.skiTracks) f.skiDepth = spill_->put(cfg_.skiTracks->depth().values());
  framesSetAside_.push_back(std::move(f));
  ++report_.framesSetAside;
}

// The frames set aside, in order, once no avalanche is in motion (or at the season's end, beside
// one still in motion).
void SeasonRun::writeFramesSetAside(bool seasonEnd) {
  const bool moving = avalanche_ && avalanche_->active();
  if (framesSetAside_.empty() || (moving && !seasonEnd)) return;
  if (!moving) releaseScratch();
  for (const FrameSetAside& f : framesSetAside_) {
    SnowState frame = hostFrame();
    size_t k = 0;
    forEachSnowField(frame, [&](const SnowFieldInfo& info, auto& grid) {
      if (!setAside(info.role)) return;
      using Element = typename std::decay_t<decltype(grid)>::value_type;
      const SpillFile::Extent& e = f.fields[k++];
      if (e.bytes == 0) grid = std::decay_t<decltype(grid)>();
      else grid.adopt(state_.spec.width, state_.spec.height, spill_->get<Element>(e));
    });
    Grid<float> skiDepth;
    if (cfg_.skiTracks) {
      skiDepth.adopt(cfg_.skiTracks->depth().width(), cfg_.skiTracks->depth().height(), spill_->get<float>(f.skiDepth));
      cfg_.skiTracks->swapDepth(skiDepth);
    }
    onFrame_(f.day, frame);
    if (cfg_.skiTracks) cfg_.skiTracks->swapDepth(skiDepth);
  }
  framesSetAside_.clear();
  spill_.reset();
  if (ski_) ski_->uploadRouteMap();
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
  writeFramesSetAside(true);
  report_.final = backend_.totals();  // before the download hands the backend's fields over
  backend_.downloadGiving(state_);
  if (staticReleased_) cfg_.updateStaticFields(staticDay_, state_);  // the last day's, as they were
  if (noSnow_) state_.validCell = std::move(terrainValid_);
  fadeSkiTracks(state_);
  const auto stats = scheduler_.stats();
  for (size_t i = 0; i < stats.size(); ++i) {
    reports_[i].starts = stats[i].starts;
    reports_[i].steps = stats[i].steps;
    reports_[i].stops = stats[i].stops;
  }
  report_.phenomena = std::move(reports_);
  report_.events = scheduler_.eventsFired();
}

SeasonReport runSeason(SnowBackend& backend, SnowState& state, const SeasonConfig& cfg,
                       const ProgressCallback& progress, const FrameCallback& onFrame, const AvalancheCallback& onAvalanche) {
  SeasonRun run(backend, state, cfg, progress, onFrame, onAvalanche);
  return run.run();
}

}  // namespace snow
