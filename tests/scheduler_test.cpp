#include <gtest/gtest.h>

#include <cmath>

#include "core/scheduler.h"

using namespace snow;

namespace {
PhenomenonSpec continuous(const std::string& name, double perDay) {
  PhenomenonSpec s;
  s.name = name;
  s.alwaysActive = true;
  s.stepsPerDay = perDay;
  return s;
}
}  // namespace

// Eq. (1): each event is of type e with probability f_e / sum f. Over N events the count of e is
// binomial; we allow 4.5 standard deviations (a false failure about once in 150000 runs; the
// seed is fixed, so the test is deterministic).
TEST(PoissonScheduler, EventSharesMatchFrequencies) {
  PoissonScheduler s(12345);
  const double f[3] = {2.0, 1.0, 0.25};
  for (int i = 0; i < 3; ++i) s.add(continuous(std::string("p") + std::to_string(i), f[i]));
  s.runUntil(40000.0);
  const auto stats = s.stats();
  double n = 0;
  for (const auto& st : stats) n += static_cast<double>(st.steps);
  ASSERT_GT(n, 100000.0);
  const double total = f[0] + f[1] + f[2];
  for (int i = 0; i < 3; ++i) {
    const double p = f[i] / total;
    const double sigma = std::sqrt(n * p * (1 - p));
    EXPECT_NEAR(static_cast<double>(stats[i].steps), n * p, 4.5 * sigma) << stats[i].name;
  }
  // The event rate is sum f: n / T within 4.5 sigma of the Poisson count.
  EXPECT_NEAR(n, total * 40000.0, 4.5 * std::sqrt(total * 40000.0));
}

TEST(PoissonScheduler, EpisodicStartsAndMeanDuration) {
  PoissonScheduler s(99);
  PhenomenonSpec storm;
  storm.name = "storm";
  storm.stepsPerDay = 2.0;
  storm.startsPerDay = 1.0 / 7.0;
  storm.stopsPerDay = 1.0 / 3.0;
  double activeDays = 0.0, startedAt = 0.0;
  storm.onStart = [&](const EventContext& e) { startedAt = e.day; };
  storm.onStop = [&](const EventContext& e) { activeDays += e.day - startedAt; };
  s.add(storm);
  s.runUntil(20000.0);
  const auto st = s.stats()[0];
  ASSERT_GT(st.stops, 1000u);
  // Mean duration 3 days: standard error 3/sqrt(n).
  const double mean = activeDays / static_cast<double>(st.stops);
  EXPECT_NEAR(mean, 3.0, 4.5 * 3.0 / std::sqrt(static_cast<double>(st.stops)));
  // Alternating renewal: the share of time active is 3 / (3 + 7).
  EXPECT_NEAR(activeDays / 20000.0, 0.3, 0.03);
}

TEST(PoissonScheduler, TemporalZoomSuppressesSlowEvents) {
  PoissonScheduler s(7);
  s.add(continuous("melt", 2.0));
  s.add(continuous("diffusion", 2.0));
  PhenomenonSpec avalanche;
  avalanche.name = "avalanche";
  avalanche.zoomed = true;
  avalanche.stepsPerDay = 864000.0;  // every 0.1 s
  avalanche.startsPerDay = 0.5;
  int steps = 0;
  avalanche.onStart = [&](const EventContext&) { steps = 0; };
  avalanche.onStep = [&](const EventContext&) { ++steps; };
  avalanche.finished = [&] { return steps >= 300; };  // at rest after 30 s
  const int id = s.add(avalanche);
  s.enableTrace(true);
  s.runUntil(200.0);
  ASSERT_GT(s.stats()[id].starts, 50u);
  bool inside = false;
  size_t checked = 0;
  for (const auto& t : s.trace()) {
    if (t.phenomenon == id) {
      if (t.kind == EventKind::Start) inside = true;
      if (t.kind == EventKind::Stop) inside = false;
    } else {
      EXPECT_FALSE(inside) << "slow event at day " << t.day << " during an avalanche";
      ++checked;
    }
  }
  EXPECT_GT(checked, 500u);
  EXPECT_EQ(s.stats()[id].steps, 300u * s.stats()[id].stops);
}

TEST(PoissonScheduler, FixedWindowsAndActionsAreMetExactly) {
  PoissonScheduler s(3);
  PhenomenonSpec snow;
  snow.name = "snowfall";
  snow.stepsPerDay = 4.0;
  snow.windows = {{10.0, 13.0}, {20.5, 21.0}};
  std::vector<double> starts, stops, stepDays;
  snow.onStart = [&](const EventContext& e) { starts.push_back(e.day); };
  snow.onStop = [&](const EventContext& e) { stops.push_back(e.day); };
  snow.onStep = [&](const EventContext& e) { stepDays.push_back(e.day); };
  s.add(snow);
  std::vector<double> actions;
  s.addAction(15.25, [&](double d) { actions.push_back(d); });
  s.addAction(5.0, [&](double d) { actions.push_back(d); });
  s.runUntil(30.0);
  EXPECT_EQ(starts, (std::vector<double>{10.0, 20.5}));
  EXPECT_EQ(stops, (std::vector<double>{13.0, 21.0}));
  EXPECT_EQ(actions, (std::vector<double>{5.0, 15.25}));
  for (double d : stepDays) EXPECT_TRUE((d >= 10.0 && d < 13.0) || (d >= 20.5 && d < 21.0)) << d;
  EXPECT_GT(stepDays.size(), 5u);
  EXPECT_DOUBLE_EQ(s.now(), 30.0);
}

TEST(PoissonScheduler, SameSeedSameEventsOtherSeedOtherEvents) {
  auto runTrace = [](uint64_t seed) {
    PoissonScheduler s(seed);
    s.add(continuous("a", 2.0));
    s.add(continuous("b", 0.5));
    s.enableTrace(true);
    s.runUntil(100.0);
    std::vector<std::pair<double, int>> out;
    for (const auto& t : s.trace()) out.push_back({t.day, t.phenomenon});
    return out;
  };
  EXPECT_EQ(runTrace(1), runTrace(1));
  EXPECT_NE(runTrace(1), runTrace(2));
}

TEST(PoissonScheduler, StepContextCarriesNominalStepAndUniqueIndex) {
  PoissonScheduler s(5);
  PhenomenonSpec p = continuous("melt", 2.0);
  std::vector<uint64_t> indices;
  p.onStep = [&](const EventContext& e) {
    EXPECT_DOUBLE_EQ(e.stepDays, 0.5);
    indices.push_back(e.eventIndex);
  };
  s.add(p);
  s.runUntil(50.0);
  for (size_t i = 1; i < indices.size(); ++i) EXPECT_GT(indices[i], indices[i - 1]);
}

TEST(PoissonScheduler, RejectsBadSpecs) {
  PoissonScheduler s(1);
  PhenomenonSpec bad = continuous("bad", 0.0);
  EXPECT_THROW(s.add(bad), std::invalid_argument);
  PhenomenonSpec window;
  window.name = "w";
  window.windows = {{3.0, 3.0}};
  EXPECT_THROW(s.add(window), std::invalid_argument);
}
