// The season's avalanches (SeasonRun, season_run.h): the zoomed phenomenon, its spontaneous
// tries and the user and skier releases waiting for it.
#include "rng.h"
#include "season_run.h"
#include "util.h"

namespace snow {

void SeasonRun::releaseUser(const UserAvalanche& u, double day, double seaLevelTemperatureC) {
  if (u.zone) avalanche_->releaseZone(*u.zone, day, seaLevelTemperatureC, !u.bySkier);
  else avalanche_->release(u.x, u.y, day, seaLevelTemperatureC, !u.bySkier);
}

// An avalanche's start: the first pending user (or skier) release, else a spontaneous try.
void SeasonRun::startAvalanche(int slot, const EventContext& e) {
  const bool retry = retryingRelease_;
  retryingRelease_ = false;
  timed(slot, [&] {
    const double t0 = cfg_.weather.at(e.day).seaLevelTemperatureC;
    if (!pendingAvalanches_.empty()) {
      const UserAvalanche u = pendingAvalanches_.front();
      pendingAvalanches_.pop_front();
      releaseUser(u, e.day, t0);
      if (!avalanche_->active()) recordAvalanche(avalanche_->record());
      if (retry) scheduleWaitingRelease(e.day);
    } else {
      trySpontaneousRelease(e, retry);
    }
  });
}

// A spontaneous release at a cell drawn among those that can release. One that finds none waits:
// the paper's rate is of avalanches, and natural ones come when the snowpack lets them (in
// cycles during and after storms), so it is tried again at each state-change step (when
// stability changes) until it releases or the season ends; one waiting release a step.
void SeasonRun::trySpontaneousRelease(const EventContext& e, bool retry) {
  const RandomKey key{cfg_.seed};
  const Philox4x32 r = key.draw(e.eventIndex, 0, RngStream::Avalanche);
  if (!retry) ++report_.avalancheTries;
  const auto t0 = WallClock::now();
  const bool released = avalanche_->trySpontaneous(uniformOpenDouble(r.v[0], r.v[1]), e.day, cfg_.weather.at(e.day).seaLevelTemperatureC);
  report_.avalancheTrySeconds += elapsedSeconds(t0);
  ++report_.avalancheTryCalls;
  report_.avalancheSnapshotsKept = avalanche_->snapshotsKept();
  if (retry && released) --waitingReleases_;
  if (!retry && !released) ++waitingReleases_;
  if (waitingReleases_ > 0) scheduleWaitingRelease(e.day);
}

void SeasonRun::scheduleWaitingRelease(double day) {
  if (waitingRetryScheduled_) return;
  waitingRetryScheduled_ = true;
  scheduler_.addAction(day + 1.0 / p_.stateChangeStepsPerDay, [this](double d) {
    waitingRetryScheduled_ = false;
    if (waitingReleases_ <= 0) return;
    if (scheduler_.isActive(avalancheId_)) return scheduleWaitingRelease(d);
    retryingRelease_ = true;
    scheduler_.start(avalancheId_);
  });
}

void SeasonRun::recordAvalanche(AvalancheRecord record) {
  report_.avalanches.push_back(std::move(record));
  if (onAvalanche_) onAvalanche_(report_.avalanches.back());
}

// An avalanche's stop: it settles, then the user releases that came while it ran, one after the
// other.
void SeasonRun::stopAvalanche(int slot) {
  if (avalanche_->active()) timed(slot, [&] { recordAvalanche(avalanche_->settle()); });
  while (!pendingAvalanches_.empty()) {
    const UserAvalanche u = pendingAvalanches_.front();
    pendingAvalanches_.pop_front();
    timed(slot, [&] {
      releaseUser(u, u.day, cfg_.weather.at(u.day).seaLevelTemperatureC);
      recordAvalanche(avalanche_->runToRest());
    });
  }
  writeFramesSetAside(false);
}

// Avalanches (§6.1): spontaneous releases at about one a week per km^2, each at a cell drawn
// among those that can release, weighted by their unstable depth and slope above the rest angle
// (AvalancheRun::trySpontaneous; none where no cell can),
// and the scene's user releases. A zoomed phenomenon: while one runs, its steps of 0.1 s are
// the only events (§3.1's temporal zoom). The runner (which keeps host copies of the state)
// exists only when the season can have avalanches.
void SeasonRun::addAvalanches() {
  skiing_ = (p_.skiersPerHour > 0.0 && p_.skiHoursPerDay > 0.0) || !cfg_.userSkiers.empty();
  double validCells = 0;
  for (uint8_t v : terrain().validCell.values()) validCells += v;
  const double areaKm2 = validCells * terrain().spec.cellAreaM2() * 1e-6;
  const double startsPerDay = p_.avalancheRatePerKm2PerDay * areaKm2;
  if (startsPerDay > 0.0 || !cfg_.userAvalanches.empty() || (skiing_ && p_.skiTriggerFactor > 0.0)) {
    avalanche_.emplace(backend_, p_, terrain());
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

}  // namespace snow
