// What the benchmark suite relies on, asserted: the season converges as its step rates are
// refined (the accuracy table's premise), and the plots it writes hold what they are given.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/cpu_backend.h"
#include "core/reference_scenario.h"
#include "bench/bench_suite.h"
#include "bench/plot.h"

namespace snow {
namespace {

std::vector<float> seasonDepth(double factor) {
  SnowState s = referenceRangeState(96);
  SeasonConfig c = referenceWinter(40.0);
  c.params.avalancheRatePerKm2PerDay = 0.0;
  c.params.skiersPerHour = 0.0;
  for (double start = 3; start + 3 <= 40.0; start += 10) c.weather.snowfallPeriods.push_back({start, start + 3});
  c.params.snowfallStepsPerDay *= factor;
  c.params.stateChangeStepsPerDay *= factor;
  c.params.diffusionStepsPerDay *= factor;
  computeTemperatureBase(s, c.params);
  auto backend = createCpuBackend();
  runSeason(*backend, s, c);
  return s.depthGrid().values();
}

// Refining every step rate brings the season toward the finely stepped one: the error against
// 8x the default rate falls from a quarter of it to the default to twice it.
TEST(BenchPremises, SeasonConvergesAsItsStepRatesAreRefined) {
  const std::vector<float> ref = seasonDepth(8.0);
  const double coarse = relativeL1(seasonDepth(0.25), ref);
  const double normal = relativeL1(seasonDepth(1.0), ref);
  const double fine = relativeL1(seasonDepth(2.0), ref);
  std::printf("[ measure ] season depth error against 8x the step rates: 0.25x %.3e, 1x %.3e, 2x %.3e\n", coarse, normal, fine);
  EXPECT_GT(coarse, normal);
  EXPECT_GT(normal, fine);
  EXPECT_GT(coarse, 0.0);
}

TEST(BenchPremises, LogLogPlotHoldsEveryPositivePoint) {
  const std::string svg = logLogSvg("t", "x label", "y label",
                                    {PlotSeries{"one", {{0.1, 0.5, "a"}, {1.0, 0.05, "b"}, {10.0, 0.0, "zero"}}},
                                     PlotSeries{"two <&>", {{0.2, 0.2, ""}}}});
  size_t circles = 0;
  for (size_t at = svg.find("<circle"); at != std::string::npos; at = svg.find("<circle", at + 1)) ++circles;
  EXPECT_EQ(circles, 3u);  // the point at y = 0 cannot sit on a log axis
  EXPECT_NE(svg.find("1 point(s) at 0 not shown"), std::string::npos);
  EXPECT_NE(svg.find("two &lt;&amp;&gt;"), std::string::npos);
  EXPECT_NE(svg.find("x label"), std::string::npos);
  EXPECT_EQ(svg.rfind("</svg>\n"), svg.size() - 7);
}

}  // namespace
}  // namespace snow
