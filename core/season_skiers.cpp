// The season's skiers (SeasonRun, season_run.h): the automatic skiers of each ski hour, the
// scene's user skiers, and the batches they descend in.
#include <algorithm>
#include <memory>
#include <utility>

#include "rng.h"
#include "season_run.h"

namespace snow {

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
      (*cumulative)[i] = (sum += terrain().validCell.values()[i] ? std::max(0.f, (*u.startWeights)[i]) : 0.f);
    const uint64_t stream = maskedSkierDraws++;
    scheduler_.addAction(u.day, [this, u, cumulative, stream](double now) {
      const RandomKey key{cfg_.seed};
      std::vector<SkierStart> starts;
      for (int k = 0; k < u.count; ++k)
        for (uint32_t attempt = 0; attempt < 16; ++attempt) {
          const Philox4x32 r = key.draw(stream, static_cast<uint32_t>(k) * 16u + attempt, RngStream::SkierStartMask);
          const long long i = pickByCumulativeWeight(*cumulative, uniformOpenDouble(r.v[0], r.v[1]));
          if (i < 0) break;
          const int w = terrain().spec.width, x = static_cast<int>(i % w), y = static_cast<int>(i / w);
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
// each at a time (phenomena/skiers.h); the bake has no real-time display, so a batch runs to its end
// at its event.
void SeasonRun::addSkiers() {
  if (!skiing_) return;
  ski_.emplace(backend_, p_, terrain(), cfg_.skiTracks);
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

}  // namespace snow
