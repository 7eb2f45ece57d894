#include "season.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <deque>
#include <functional>
#include <optional>

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

SeasonReport runSeason(SnowBackend& backend, SnowState& state, const SeasonConfig& cfg,
                       const ProgressCallback& progress, const FrameCallback& onFrame) {
  const auto t0 = Clock::now();
  const ModelParameters& p = cfg.params;
  SeasonReport report;
  if (cfg.updateStaticFields) cfg.updateStaticFields(0, state);
  // No-snow cells leave the snow domain for the season: their snow goes, and the backend (and the
  // avalanche and skier runners, built from `state` below) see them as outside the terrain.
  Grid<uint8_t> terrainValid;
  const bool noSnow = state.noSnow.size() == state.spec.cellCount() && state.noSnow.size() > 0;
  if (noSnow) {
    terrainValid = state.validCell;
    const double area = state.spec.cellAreaM2();
    for (size_t i = 0; i < state.noSnow.size(); ++i) {
      if (!state.noSnow.values()[i]) continue;
      if (state.validCell.values()[i])
        for (int l = 0; l < kSnowLayerCount; ++l) {
          float& d = state.layer(static_cast<SnowLayer>(l)).values()[i];
          report.noSnowRemovedM3 += static_cast<double>(d) * area;
          d = 0.f;
        }
      state.validCell.values()[i] = 0;
    }
  }
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


  // Each step acts over the time since the phenomenon's previous step (or its start), not over
  // the nominal 1 / stepsPerDay: the Poisson clock decides when steps happen, but a storm of
  // three days adds three days of snow however many steps it drew, and a season melts for as
  // long as it is warm. (With nominal steps, a fixed 4-day storm drew 9 steps in one run and 14
  // in another: 30 % of the season's snow was the luck of the draw.) Continuous phenomena
  // catch up at the season's end; episodic ones at their stop.
  std::vector<double> lastStep;
  auto sinceLast = [&lastStep](int slot, double day) {
    const double dt = std::max(0.0, day - lastStep[slot]);
    lastStep[slot] = day;
    return dt;
  };
  std::vector<std::function<void(double day)>> catchUp;  // continuous phenomena, run at the end
  auto addPhenomenon = [&](PhenomenonSpec spec) {
    reports.push_back(PhenomenonReport{spec.name});
    lastStep.push_back(0.0);
    return scheduler.add(std::move(spec));
  };
  auto snowfallOver = [&](int slot, double day) {
    const double dt = sinceLast(slot, day);
    if (dt > 0.0)
      timed(slot, [&] { report.snowfallAddedM3 += backend.snowfall(makeSnowfallArgs(p, dt, cfg.weather.at(day))); });
  };
  auto makeSnowfallEvents = [&](PhenomenonSpec& s, int slot) {
    s.onStart = [&, slot](const EventContext& e) { lastStep[slot] = e.day; };
    s.onStep = [&, slot](const EventContext& e) { snowfallOver(slot, e.day); };
    s.onStop = [&, slot](const EventContext& e) { snowfallOver(slot, e.day); };
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
    const int slot = static_cast<int>(reports.size());
    makeSnowfallEvents(s, slot);
    catchUp.push_back([&, slot](double day) {
      if (scheduler.isActive(slot)) snowfallOver(slot, day);
    });
    addPhenomenon(std::move(s));
  }
  if (!cfg.userSnowfalls.empty()) {
    PhenomenonSpec s;
    s.name = "snowfall (user events)";
    s.stepsPerDay = p.snowfallStepsPerDay;
    for (const auto& w : cfg.userSnowfalls) s.windows.push_back({w.startDay, w.endDay});
    const int slot = static_cast<int>(reports.size());
    makeSnowfallEvents(s, slot);
    catchUp.push_back([&, slot](double day) {
      if (scheduler.isActive(slot)) snowfallOver(slot, day);
    });
    addPhenomenon(std::move(s));
  }
  // Continuous phenomena, always active: `body(slot, day, dt)` runs at each step over the time
  // since the previous one, and once more at the season's end.
  auto addContinuous = [&](const char* name, double stepsPerDay, std::function<void(int, double, double)> body) {
    PhenomenonSpec s;
    s.name = name;
    s.alwaysActive = true;
    s.stepsPerDay = stepsPerDay;
    const int slot = static_cast<int>(reports.size());
    auto over = [&sinceLast, slot, body](double day) { body(slot, day, sinceLast(slot, day)); };
    s.onStep = [over](const EventContext& e) { over(e.day); };
    catchUp.push_back(over);
    addPhenomenon(std::move(s));
  };
  // State changes (§5.2): melt, skipped on days when even the warmest cell is below T_0melt, and
  // stability changes, skipped when it is below T_freeze and there is no wind loading.
  addContinuous("melt", p.stateChangeStepsPerDay, [&](int slot, double day, double dt) {
    const WeatherState w = cfg.weather.at(day);
    if (w.seaLevelTemperatureC + maxTemperatureBase <= p.meltThresholdC) {
      ++reports[slot].skippedSteps;
      return;
    }
    timed(slot, [&] { report.meltRemovedM3 -= backend.melt(makeMeltArgs(p, dt, w)); });
  });
  addContinuous("stability", p.stateChangeStepsPerDay, [&](int slot, double day, double dt) {
    const WeatherState w = cfg.weather.at(day);
    if (w.seaLevelTemperatureC + maxTemperatureBase <= p.freezeTemperatureC && !(cfg.windTransport && p.windInstabilityPerMps2 > 0)) {
      ++reports[slot].skippedSteps;
      return;
    }
    timed(slot, [&] { backend.stabilityChange(makeStabilityArgs(p, dt, w)); });
  });
  // Wind bedforms (kernels/bedform.h), hourly steps of rounds_per_hour polling rounds each, only
  // while some domain cell has wind above the threshold (else only the cohesion grows).
  const bool bedformsMasked = state.bedformMask.size() == state.spec.cellCount() && state.bedformMask.size() > 0;
  // The domain's strongest wind (squared), scanned again only after the daily static-field
  // refresh changed the wind (-1: to scan), not at every hourly step.
  double bedformWindiest = -1.0;
  if (cfg.bedforms) {
    const BedformParameters bp = *cfg.bedforms;
    auto carry = std::make_shared<double>(0.0);
    auto roundBase = std::make_shared<uint64_t>(0);
    addContinuous("wind bedforms", 24.0, [&, bp, carry, roundBase](int slot, double day, double dt) {
      if (!(dt > 0.0)) return;
      timed(slot, [&] {
        if (bedformWindiest < 0.0) {
          double maxSpeed = 0.0;
          const bool masked = bedformsMasked;
          for (size_t i = 0; i < state.windXMps.size(); ++i) {
            if (!state.validCell.values()[i] || (masked && !state.bedformMask.values()[i])) continue;
            const double wx = state.windXMps.values()[i], wy = state.windYMps.values()[i];
            maxSpeed = std::max(maxSpeed, wx * wx + wy * wy);
          }
          bedformWindiest = maxSpeed;
        }
        const bool windy = cfg.windTransport && std::sqrt(bedformWindiest) >= bp.thresholdWindMps;
        int rounds = 0;
        if (windy) {
          const double want = *carry + dt * 24.0 * bp.roundsPerHour;
          rounds = static_cast<int>(std::floor(want));
          *carry = want - rounds;
        } else {
          ++reports[slot].skippedSteps;
          ++report.bedforms.calmSteps;
        }
        const BedformStepReport r = backend.bedformStep(
            makeBedformArgs(bp, dt, rounds, *roundBase, cfg.seed, cfg.weather.at(day).seaLevelTemperatureC));
        *roundBase += static_cast<uint64_t>(rounds);
        report.bedforms.rounds += rounds;
        report.bedforms.slabsEroded += r.slabsEroded;
        report.bedforms.slabsAvalanched += r.slabsAvalanched;
        report.bedforms.domainCells = r.domainCells;
        report.bedforms.atRest = report.bedforms.atRest && r.reposeConverged;
      });
    });
  }
  // Wind transport (§5.4), only while the season has wind (the kernel leaves the bedforms' cells).
  if (cfg.windTransport)
    addContinuous("wind transport", p.windTransportStepsPerDay, [&](int slot, double, double dt) {
      if (dt > 0.0) timed(slot, [&] { backend.windTransport(makeWindTransportArgs(p, dt)); });
    });
  // Powder diffusion (§5.3).
  addContinuous("powder diffusion", p.diffusionStepsPerDay, [&](int slot, double, double dt) {
    if (dt > 0.0) timed(slot, [&] { backend.powderDiffusion(makePowderDiffusionArgs(p, dt)); });
  });

  // Timeline edits (art direction), before the avalanches and skiers of the same day.
  for (const SeasonEdit& edit : cfg.edits) {
    if (edit.day < 0.0 || edit.day > cfg.days) continue;
    scheduler.addAction(edit.day, [&, &edit = edit](double now) {
      const double added = backend.applyEdit(edit.args, edit.weights ? *edit.weights : std::vector<float>());
      report.editsNetM3 += added;
      report.edits.push_back({now, edit.label, added});
    });
  }

  // Avalanches (§6.1): spontaneous release tries at about one a week per km^2 (each at a random
  // cell, released with a probability from its unstable depth and slope above the rest angle),
  // and the scene's user releases. A zoomed phenomenon: while one runs, its steps of 0.1 s are
  // the only events (§3.1's temporal zoom). The runner (which keeps host copies of the state)
  // exists only when the season can have avalanches.
  std::optional<AvalancheRun> avalanche;
  std::deque<UserAvalanche> pendingAvalanches;
  std::function<void(const UserAvalanche&, double day, double t0)> releaseUser;
  int avalancheId = -1;
  const bool skiing = (p.skiersPerHour > 0.0 && p.skiHoursPerDay > 0.0) || !cfg.userSkiers.empty();
  {
    double validCells = 0;
    for (uint8_t v : state.validCell.values()) validCells += v;
    const double areaKm2 = validCells * state.spec.cellAreaM2() * 1e-6;
    const double startsPerDay = p.avalancheRatePerKm2PerDay * areaKm2;
    if (startsPerDay > 0.0 || !cfg.userAvalanches.empty() || (skiing && p.skiTriggerFactor > 0.0)) {
      avalanche.emplace(backend, p, state);
      avalanche->keepMaps(cfg.avalancheMaps, cfg.avalancheFrameIntervalS);
      releaseUser = [&](const UserAvalanche& u, double day, double t0) {
        if (u.zone) avalanche->releaseZone(*u.zone, day, t0, !u.bySkier);
        else avalanche->release(u.x, u.y, day, t0, !u.bySkier);
      };
      PhenomenonSpec s;
      s.name = "avalanche";
      s.zoomed = true;
      s.startsPerDay = startsPerDay;
      s.stepsPerDay = 86400.0 / p.avalancheStepS;
      const int slot = static_cast<int>(reports.size());
      s.onStart = [&, slot](const EventContext& e) {
        timed(slot, [&] {
          const double t0 = cfg.weather.at(e.day).seaLevelTemperatureC;
          if (!pendingAvalanches.empty()) {
            const UserAvalanche u = pendingAvalanches.front();
            pendingAvalanches.pop_front();
            releaseUser(u, e.day, t0);
            if (!avalanche->active()) report.avalanches.push_back(avalanche->record());
          } else {
            const RandomKey key{cfg.seed};
            const Philox4x32 r = key.draw(e.eventIndex, 0, RngStream::Avalanche);
            ++report.avalancheTries;
            avalanche->trySpontaneous(uniformOpenDouble(r.v[0], r.v[1]), uniformOpenDouble(r.v[2], r.v[3]), e.day, t0);
          }
        });
      };
      s.onStep = [&, slot](const EventContext&) {
        if (avalanche->active()) timed(slot, [&] { avalanche->step(); });
      };
      s.finished = [&] { return !avalanche->active() || avalanche->atRest(); };
      s.onStop = [&, slot](const EventContext&) {
        if (avalanche->active()) timed(slot, [&] { report.avalanches.push_back(avalanche->settle()); });
        // User releases that came while this one ran: run them now, one after the other.
        while (!pendingAvalanches.empty()) {
          const UserAvalanche u = pendingAvalanches.front();
          pendingAvalanches.pop_front();
          timed(slot, [&] {
            releaseUser(u, u.day, cfg.weather.at(u.day).seaLevelTemperatureC);
            report.avalanches.push_back(avalanche->runToRest());
          });
        }
      };
      avalancheId = addPhenomenon(std::move(s));
    }
  }
  for (const UserAvalanche& u : cfg.userAvalanches) {
    if (u.day < 0.0 || u.day > cfg.days) continue;
    scheduler.addAction(u.day, [&, u](double) {
      pendingAvalanches.push_back(u);
      scheduler.start(avalancheId);
    });
  }

  // Skiers (§6.2, §7.3): automatic ones, about skiers_per_hour in each of the day's
  // ski_hours_per_day hours (an hour's skiers, a Poisson number, start together from cells drawn
  // by the route map), and the scene's user skiers (a group starts together). The skiers of a
  // batch move together on the backend, one move of each at a time (kernels/ski.h); the bake has
  // no real-time display, so a batch runs to its end at its event. Avalanches they trigger start
  // after the batch, in skier order.
  std::optional<SkiRun> ski;
  // At function scope: the scheduler's events call runSkiers (and it counts skierId) long after
  // the block below has ended.
  uint64_t skierId = 0;
  auto runSkiers = [&](std::vector<SkierStart> starts, double day) {
    if (starts.empty()) return;
    for (SkierStart& st : starts) st.id = skierId++;
    std::vector<SkierRecord> records = ski->descendTogether(starts, day, cfg.seed);
    for (SkierRecord& r : records) {
      if (r.triggered && avalancheId >= 0) {
        pendingAvalanches.push_back({day, r.triggerX, r.triggerY, true, nullptr});
        scheduler.start(avalancheId);
      }
      if (!r.user) r.path.clear();  // keep the records small; user skiers keep their paths
      report.skiers.push_back(std::move(r));
    }
  };
  if (skiing) {
    ski.emplace(backend, p, state, cfg.skiTracks);
    if (p.skiersPerHour > 0.0 && p.skiHoursPerDay > 0.0) {
      PhenomenonSpec s;
      s.name = "skier";
      s.alwaysActive = true;
      s.stepsPerDay = p.skiHoursPerDay;
      const int slot = static_cast<int>(reports.size());
      s.onStep = [&, slot](const EventContext& e) {
        timed(slot, [&] {
          const RandomKey key{cfg.seed};
          const int count = poissonCount(p.skiersPerHour, [&](uint32_t k) {
            const Philox4x32 r = key.draw(e.eventIndex, k, RngStream::SkierCount);
            return uniformOpenDouble(r.v[0], r.v[1]);
          });
          // Each skier's cell drawn by the route map until one has snow enough to ski (at most
          // 16 draws).
          std::vector<SkierStart> starts;
          for (int k = 0; k < count; ++k)
            for (uint32_t attempt = 0; attempt < 16; ++attempt) {
              const Philox4x32 r = key.draw(e.eventIndex, static_cast<uint32_t>(k) * 16u + attempt, RngStream::Skier);
              int x = 0, y = 0;
              if (!ski->pickStart(uniformOpenDouble(r.v[0], r.v[1]), x, y)) break;
              if (!ski->canStart(x, y)) continue;
              starts.push_back({x, y, 0, false});
              break;
            }
          runSkiers(std::move(starts), e.day);
        });
      };
      addPhenomenon(std::move(s));
    }
    uint64_t maskedSkierDraws = 0;
    for (const UserSkier& u : cfg.userSkiers) {
      if (u.day < 0.0 || u.day > cfg.days) continue;
      if (!u.startWeights) {
        scheduler.addAction(u.day, [&, u](double now) {
          runSkiers(std::vector<SkierStart>(static_cast<size_t>(u.count), SkierStart{u.x, u.y, 0, true}), now);
        });
        continue;
      }
      // From a start mask: each skier's start cell drawn by the mask's weights (valid cells only),
      // redrawn (up to 16 times) until it has snow enough to ski.
      auto cumulative = std::make_shared<std::vector<double>>(u.startWeights->size());
      double sum = 0.0;
      for (size_t i = 0; i < cumulative->size(); ++i)
        (*cumulative)[i] = (sum += state.validCell.values()[i] ? std::max(0.f, (*u.startWeights)[i]) : 0.f);
      const uint64_t stream = maskedSkierDraws++;
      scheduler.addAction(u.day, [&, u, cumulative, stream](double now) {
        const RandomKey key{cfg.seed};
        std::vector<SkierStart> starts;
        for (int k = 0; k < u.count; ++k)
          for (uint32_t attempt = 0; attempt < 16; ++attempt) {
            const Philox4x32 r = key.draw(stream, static_cast<uint32_t>(k) * 16u + attempt, RngStream::SkierStartMask);
            const long long i = pickByCumulativeWeight(*cumulative, uniformOpenDouble(r.v[0], r.v[1]));
            if (i < 0) break;
            const int x = static_cast<int>(i % state.spec.width), y = static_cast<int>(i / state.spec.width);
            if (!ski->canStart(x, y)) continue;
            starts.push_back({x, y, 0, true});
            break;
          }
        runSkiers(std::move(starts), now);
      });
    }
  }

  if (cfg.updateStaticFields) {
    for (int day = 1; day < cfg.days; ++day)
      scheduler.addAction(day, [&, day](double) {
        cfg.updateStaticFields(day, state);
        backend.uploadStaticFields(state);
        bedformWindiest = -1.0;  // the wind changed: the bedforms scan it again
        maxTemperatureBase = backend.maxTemperatureBaseC();
      });
  }
  for (double day : cfg.frameDays) {
    if (day < 0.0 || day > cfg.days || !onFrame) continue;
    scheduler.addAction(day, [&](double now) {
      SnowState frame = state;
      if (noSnow) frame.validCell = terrainValid;
      backend.download(frame);
      if (cfg.skiTracks) cfg.skiTracks->fade(frame);
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
  for (const auto& f : catchUp) f(cfg.days);
  if (progress) progress(1.0);

  backend.download(state);
  if (noSnow) state.validCell = std::move(terrainValid);
  if (cfg.skiTracks) cfg.skiTracks->fade(state);
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
