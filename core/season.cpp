#include "season.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "scheduler.h"
#include "step_args.h"

namespace snow {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

double SeasonReport::massBalanceRelativeError() const {
  const double expected = initial.totalM3() + snowfallAddedM3 - meltRemovedM3;
  const double scale = std::max({initial.totalM3() + snowfallAddedM3, final.totalM3(), 1e-30});
  return std::abs(final.totalM3() - expected) / scale;
}

void computeTemperatureBase(SnowState& s, const ModelParameters& p) {
  s.temperatureBaseC.resize(s.spec.width, s.spec.height);
  for (size_t i = 0; i < s.bedrockM.size(); ++i)
    s.temperatureBaseC.values()[i] = temperatureBaseC(p, s.bedrockM.values()[i], s.exposureHours.values()[i]);
}

SeasonReport runSeason(SnowBackend& backend, SnowState& state, const SeasonConfig& cfg,
                       const ProgressCallback& progress, const FrameCallback& onFrame) {
  const auto t0 = Clock::now();
  const ModelParameters& p = cfg.params;
  SeasonReport report;
  if (cfg.updateStaticFields) cfg.updateStaticFields(0, state);
  backend.upload(state);
  report.initial = backend.totals();
  float maxTemperatureBase = backend.maxTemperatureBaseC();

  PoissonScheduler scheduler(cfg.seed);
  std::vector<PhenomenonReport> reports;
  auto timed = [&reports](int slot, auto&& body) {
    const auto start = Clock::now();
    body();
    reports[slot].seconds += secondsSince(start);
  };


  auto addPhenomenon = [&](PhenomenonSpec spec) {
    reports.push_back(PhenomenonReport{spec.name});
    return scheduler.add(std::move(spec));
  };
  auto makeSnowfallStep = [&](int slot) {
    return [&, slot](const EventContext& e) {
      timed(slot, [&] {
        report.snowfallAddedM3 += backend.snowfall(makeSnowfallArgs(p, e.stepDays, cfg.weather.at(e.day)));
      });
    };
  };

  // Snowfall (§5.1): Poisson starts once a week, three days on average; or the fixed periods of
  // the weather timeline. Storms asked for as user events run as their own fixed windows.
  {
    PhenomenonSpec s;
    s.name = "snowfall";
    s.stepsPerDay = p.snowfallStepsPerDay;
    if (cfg.weather.snowfallPeriods.empty()) {
      s.startsPerDay = p.snowfallStartsPerDay;
      s.stopsPerDay = 1.0 / p.snowfallMeanDurationDays;
    } else {
      for (const auto& w : cfg.weather.snowfallPeriods) s.windows.push_back({w.startDay, w.endDay});
    }
    s.onStep = makeSnowfallStep(static_cast<int>(reports.size()));
    addPhenomenon(std::move(s));
  }
  if (!cfg.userSnowfalls.empty()) {
    PhenomenonSpec s;
    s.name = "snowfall (user events)";
    s.stepsPerDay = p.snowfallStepsPerDay;
    for (const auto& w : cfg.userSnowfalls) s.windows.push_back({w.startDay, w.endDay});
    s.onStep = makeSnowfallStep(static_cast<int>(reports.size()));
    addPhenomenon(std::move(s));
  }
  {
    // State changes (§5.2), always active: melt, skipped on days when even the warmest cell is
    // below T_0melt, and stability changes, skipped when it is below T_freeze and there is no
    // wind loading.
    PhenomenonSpec s;
    s.name = "melt";
    s.alwaysActive = true;
    s.stepsPerDay = p.stateChangeStepsPerDay;
    const int slot = static_cast<int>(reports.size());
    s.onStep = [&, slot](const EventContext& e) {
      const WeatherState w = cfg.weather.at(e.day);
      if (w.seaLevelTemperatureC + maxTemperatureBase <= p.meltThresholdC) {
        ++reports[slot].skippedSteps;
        return;
      }
      timed(slot, [&] {
        report.meltRemovedM3 -= backend.melt(makeMeltArgs(p, e.stepDays, w));
      });
    };
    addPhenomenon(std::move(s));
  }
  {
    PhenomenonSpec s;
    s.name = "stability";
    s.alwaysActive = true;
    s.stepsPerDay = p.stateChangeStepsPerDay;
    const int slot = static_cast<int>(reports.size());
    s.onStep = [&, slot](const EventContext& e) {
      const WeatherState w = cfg.weather.at(e.day);
      if (w.seaLevelTemperatureC + maxTemperatureBase <= p.freezeTemperatureC && !(cfg.windTransport && p.windInstabilityPerMps2 > 0)) {
        ++reports[slot].skippedSteps;
        return;
      }
      timed(slot, [&] { backend.stabilityChange(makeStabilityArgs(p, e.stepDays, w)); });
    };
    addPhenomenon(std::move(s));
  }
  if (cfg.windTransport) {
    // Wind transport (§5.4), always active while the season has wind.
    PhenomenonSpec s;
    s.name = "wind transport";
    s.alwaysActive = true;
    s.stepsPerDay = p.windTransportStepsPerDay;
    const int slot = static_cast<int>(reports.size());
    s.onStep = [&, slot](const EventContext& e) {
      timed(slot, [&] { backend.windTransport(makeWindTransportArgs(p, e.stepDays)); });
    };
    addPhenomenon(std::move(s));
  }
  {
    // Powder diffusion (§5.3), always active.
    PhenomenonSpec s;
    s.name = "powder diffusion";
    s.alwaysActive = true;
    s.stepsPerDay = p.diffusionStepsPerDay;
    const int slot = static_cast<int>(reports.size());
    s.onStep = [&, slot](const EventContext& e) {
      timed(slot, [&] {
        backend.powderDiffusion(makePowderDiffusionArgs(p, e.stepDays));
      });
    };
    addPhenomenon(std::move(s));
  }

  if (cfg.updateStaticFields) {
    for (int day = 1; day < cfg.days; ++day)
      scheduler.addAction(day, [&, day](double) {
        cfg.updateStaticFields(day, state);
        backend.uploadStaticFields(state);
        maxTemperatureBase = backend.maxTemperatureBaseC();
      });
  }
  for (double day : cfg.frameDays) {
    if (day < 0.0 || day > cfg.days || !onFrame) continue;
    scheduler.addAction(day, [&](double now) {
      SnowState frame = state;
      backend.download(frame);
      onFrame(now, frame);
    });
  }

  double lastReported = -1.0;
  scheduler.runUntil(cfg.days, [&](double day) {
    if (progress && day - lastReported >= 1.0) {
      lastReported = day;
      progress(std::min(1.0, day / cfg.days));
    }
  });
  if (progress) progress(1.0);

  backend.download(state);
  report.final = backend.totals();
  const auto stats = scheduler.stats();
  for (size_t i = 0; i < stats.size(); ++i) {
    reports[i].starts = stats[i].starts;
    reports[i].steps = stats[i].steps;
    reports[i].stops = stats[i].stops;
  }
  report.phenomena = std::move(reports);
  report.events = scheduler.eventsFired();
  report.seconds = secondsSince(t0);
  return report;
}

}  // namespace snow
