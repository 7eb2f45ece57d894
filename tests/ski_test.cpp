// Skiers (core/ski_runs.h): the route map (automaton against the one-pass sort, an analytic plane),
// refined tracks (effective slope, continuity, straight running), dead ends, fading, the snow
// interaction and the avalanche a skier sets off.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <numeric>

#include "core/cpu_backend.h"
#include "core/season.h"
#include "core/ski_runs.h"
#include "core/reference_scenario.h"
#include "core/util.h"
#include "host_like_a_device.h"
#include "test_support.h"
#include "bake_support.h"
#include "bakers/grid_writer.h"

#include <fstream>
#include <nlohmann/json.hpp>

namespace snow {
namespace {

TEST(Ski, RouteMapIsTheLongestDescentOnAPlaneAndTheAutomatonAgrees) {
  // A plane falling east: every step must move one column east, diagonally when it can.
  SnowState s = test::terrainFrom(40, 12, 10.0, -5.f, [](double x, double) { return 1000.0 - 0.5 * x; });
  const Grid<float> d = routeMap(s.bedrockM, s.validCell, s.spec);
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 40; ++x) ASSERT_NEAR(d(x, y), (39 - x) * std::sqrt(200.0), 1e-3 * (40 - x)) << x << "," << y;
  // A rough terrain with NODATA holes: the cellular automaton gives the same bytes.
  SnowState r = test::makeRoughState(64, 48, 7);
  // The route map's device code path (ExecBackend::routeMapOnDevice: the paper's automaton,
  // iterated until it stops changing), run on a host executor dressed as a device.
  auto automaton = test::createHostLikeADeviceBackend();
  automaton->upload(r);
  Grid<float> a;
  ASSERT_TRUE(automaton->routeMapOnDevice(a));
  const Grid<float> b = routeMap(r.bedrockM, r.validCell, r.spec);
  EXPECT_EQ(a.values(), b.values());
  // Routes longer than a couple of cells: the automaton had to carry them over many iterations.
  EXPECT_GT(*std::max_element(b.values().begin(), b.values().end()), 2 * std::hypot(r.spec.cellSizeXM, r.spec.cellSizeYM));
  for (size_t i = 0; i < b.size(); ++i)
    if (!r.validCell.values()[i]) {
      ASSERT_EQ(b.values()[i], 0.f);
    }
}

double alongCurveSlopeDeg(const Path2& t, const std::function<double(double, double)>& z) {
  double length = 0.0;
  for (size_t i = 1; i < t.size(); ++i) {
    const double dz = z(t[i][0], t[i][1]) - z(t[i - 1][0], t[i - 1][1]);
    length += std::sqrt(std::pow(t[i][0] - t[i - 1][0], 2) + std::pow(t[i][1] - t[i - 1][1], 2) + dz * dz);
  }
  const double drop = z(t.front()[0], t.front()[1]) - z(t.back()[0], t.back()[1]);
  return std::asin(drop / length) * 180.0 / kPi;
}

TEST(Ski, RefinedTrackKeepsTheTargetSlopeOnSteepGroundAndRunsStraightOnGentle) {
  const ModelParameters p;  // s_t = 30 deg, a = 5 m
  const double texel = 10.0 / 8;
  for (double slopeDeg : {35.0, 45.0, 60.0}) {
    const double G = std::tan(slopeDeg * kPi / 180.0);
    auto z = [&](double, double y) { return 2000.0 - G * y; };  // falls to the south (+y)
    Path2 path;
    for (int k = 0; k <= 60; ++k) path.push_back({300.0, 10.0 * k});
    const Path2 t = refineTrack(path, z, p, 0.5 * texel);
    const double se = alongCurveSlopeDeg(t, z);
    // Within 0.1 deg (measured 30.02, 29.99, 30.02; the paper's closed form gives 29.0 at 45 deg).
    EXPECT_NEAR(se, p.skierTargetSlopeDeg, 0.1) << "terrain " << slopeDeg << " deg";
    double maxGap = 0.0, maxRise = -1e9, lateral = 0.0;
    for (size_t i = 1; i < t.size(); ++i) {
      maxGap = std::max(maxGap, std::hypot(t[i][0] - t[i - 1][0], t[i][1] - t[i - 1][1]));
      maxRise = std::max(maxRise, z(t[i][0], t[i][1]) - z(t[i - 1][0], t[i - 1][1]));
      lateral = std::max(lateral, std::abs(t[i][0] - 300.0));
    }
    EXPECT_LE(maxGap, texel);
    EXPECT_LE(maxRise, 1e-9);  // never uphill on a plane
    EXPECT_NEAR(lateral, p.trackAmplitudeM, 0.05);  // the sine's full amplitude
    std::cout << "terrain " << slopeDeg << " deg: slope along the track " << se << " deg, turn frequency "
              << turnFrequency(slopeDeg * kPi / 180.0, 30.0 * kPi / 180.0, 5.0, p.trackFrequencyPerM) << " 1/m\n";
  }
  // Gentler than s_t: straight down the fall line.
  auto gentle = [](double, double y) { return 2000.0 - std::tan(20.0 * kPi / 180.0) * y; };
  Path2 path;
  for (int k = 0; k <= 30; ++k) path.push_back({300.0, 10.0 * k});
  const Path2 t = refineTrack(path, gentle, p, 0.5 * texel);
  for (const auto& q : t) ASSERT_NEAR(q[0], 300.0, 1e-9);
  EXPECT_NEAR(alongCurveSlopeDeg(t, gentle), 20.0, 1e-6);
}

TEST(Ski, RefinedTrackIsOneContinuousCurveThroughTurns) {
  const ModelParameters p;
  auto z = [](double x, double y) { return 3000.0 - 0.9 * y - 0.3 * x; };
  Path2 path{{100, 0}};
  double heading = 0.3;
  for (int k = 0; k < 80; ++k) {
    heading += (k % 20 < 10 ? 0.12 : -0.12);  // swinging left and right by up to ~70 degrees
    path.push_back({path.back()[0] + 10.0 * std::sin(heading), path.back()[1] + 10.0 * std::cos(heading)});
  }
  const double texel = 10.0 / 8;
  const Path2 t = refineTrack(path, z, p, 0.5 * texel);
  for (size_t i = 1; i < t.size(); ++i) ASSERT_LE(std::hypot(t[i][0] - t[i - 1][0], t[i][1] - t[i - 1][1]), texel);
}

// A slope falling east at 35 degrees with a closed bowl on the fall line of the start: its
// routes end in the bowl, those around it reach the far edge.
struct BowlTerrain {
  SnowState state;
  std::unique_ptr<SnowBackend> backend;
  static constexpr int cx = 40, cy = 30, radius = 4;
};

BowlTerrain bowl() {
  BowlTerrain b;
  const double t = std::tan(35.0 * kPi / 180.0);
  b.state = test::terrainFrom(90, 60, 10.0, -5.f, [&](double x, double) { return 2000.0 - t * x; });
  // The bowl: its floor rises from its centre, 40 m below the slope at its east rim, so it is a
  // closed depression whose routes all end at its centre.
  const double rimZ = 2000.0 - t * 10.0 * (BowlTerrain::cx + BowlTerrain::radius);
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 90; ++x) {
      const double r = std::hypot(x - BowlTerrain::cx, y - BowlTerrain::cy);
      if (r < BowlTerrain::radius) b.state.bedrockM(x, y) = static_cast<float>(rimZ - 40.0 + 4.0 * r);
      b.state.stableM(x, y) = 1.0f;
    }
  b.backend = createCpuBackend();
  b.backend->upload(b.state);
  return b;
}

TEST(Ski, SkiersPreferTheRouteThatContinuesOverADeadEndBowl) {
  BowlTerrain b = bowl();
  ModelParameters p;
  p.skiTriggerFactor = 0.0;
  SkiRun run(*b.backend, p, b.state, nullptr);
  const Grid<float>& d = run.routeMap();
  // The route map's intent: the bowl's cells have short routes, the slope beside it long ones.
  EXPECT_LT(d(BowlTerrain::cx, BowlTerrain::cy), 1.f);
  EXPECT_GT(d(BowlTerrain::cx, BowlTerrain::cy - BowlTerrain::radius - 3), d(BowlTerrain::cx - 3, BowlTerrain::cy) + 200.f);
  int inBowl = 0, total = 0;
  for (uint64_t id = 0; id < 60; ++id) {
    const SkierRecord r = run.descend(20, BowlTerrain::cy, 1.0, 42, id, true);
    ASSERT_GT(r.cells, 0) << r.why;
    const auto& end = r.path.back();
    const double dist = std::hypot(end[0] / 10.0 - 0.5 - BowlTerrain::cx, end[1] / 10.0 - 0.5 - BowlTerrain::cy);
    inBowl += dist < BowlTerrain::radius;
    ++total;
    // The large-scale path never climbs: each cell entered is no higher than the one before.
    float last = 1e9f;
    for (const auto& q : r.path) {
      const float z = b.state.bedrockM(static_cast<int>(q[0] / 10.0), static_cast<int>(q[1] / 10.0));
      ASSERT_LE(z, last);
      last = z;
    }
  }
  std::cout << inBowl << " of " << total << " skiers ended in the bowl\n";
  EXPECT_LE(inBowl, total / 4);
}

TEST(Ski, TracksFadeUnderNewSnow) {
  SnowState s = test::terrainFrom(20, 20, 10.0, -5.f, [](double, double y) { return 1000.0 - 0.8 * y; });
  for (float& v : s.stableM.values()) v = 1.f;
  SkiTracks tracks(s.spec, 8);
  const Path2 line{{100.625, 20.0}, {100.625, 180.0}};  // along a texel column's centre
  auto surface = [&](int c) { return s.bedrockM.values()[c] + s.depthM(c % 20, c / 20); };
  tracks.stamp(line, 0.1, 1.2, surface);
  auto maxDepth = [&] { return *std::max_element(tracks.depth().values().begin(), tracks.depth().values().end()); };
  EXPECT_NEAR(maxDepth(), 0.1, 1e-3);
  SkiTracks light = tracks;
  // A light snowfall (4 cm) softens the track; a deep one (15 cm) buries it.
  SnowState a = s;
  for (float& v : a.powderM.values()) v = 0.04f;
  light.fade(a);
  EXPECT_NEAR(maxDepth(), 0.1, 1e-3);
  EXPECT_NEAR(*std::max_element(light.depth().values().begin(), light.depth().values().end()), 0.06, 1e-3);
  SnowState deep = s;
  for (float& v : deep.powderM.values()) v = 0.15f;
  tracks.fade(deep);
  EXPECT_EQ(maxDepth(), 0.f);
  // Melt lowers the surface without deepening the groove.
  SkiTracks melt(s.spec, 8);
  melt.stamp(line, 0.1, 1.2, surface);
  SnowState thin = s;
  for (float& v : thin.stableM.values()) v = 0.5f;
  melt.fade(thin);
  EXPECT_NEAR(*std::max_element(melt.depth().values().begin(), melt.depth().values().end()), 0.1, 1e-3);
}

TEST(Ski, SkiersCompactTheSnowTheyCross) {
  SnowState s = test::terrainFrom(60, 40, 10.0, -5.f, [](double, double y) { return 2000.0 - std::tan(33.0 * kPi / 180.0) * y; });
  for (size_t i = 0; i < s.stableM.size(); ++i) s.stableM.values()[i] = 0.6f, s.unstableM.values()[i] = 0.02f;
  auto backend = createCpuBackend();
  backend->upload(s);
  ModelParameters p;
  p.skiTriggerFactor = 0.0;
  SkiRun run(*backend, p, s, nullptr);
  const SkierRecord r = run.descend(30, 2, 1.0, 7, 0, true);
  ASSERT_GT(r.cells, 10) << r.why;
  SnowState after = s;
  backend->download(after);
  double before = 0, now = 0;
  int crossed = 0;
  for (const auto& q : r.path) {
    const int x = static_cast<int>(q[0] / 10.0), y = static_cast<int>(q[1] / 10.0);
    ++crossed;
    EXPECT_EQ(after.unstableM(x, y), 0.f);                    // 2 cm of U: all turned to S
    EXPECT_NEAR(after.stableM(x, y), 0.6f + 0.02f - 0.03f, 1e-6);  // then 3 cm of S to C
    EXPECT_NEAR(after.compactedM(x, y), 0.03f, 1e-6);
  }
  for (size_t i = 0; i < s.stableM.size(); ++i) {
    before += s.stableM.values()[i] + s.unstableM.values()[i] + s.compactedM.values()[i];
    now += after.stableM.values()[i] + after.unstableM.values()[i] + after.compactedM.values()[i];
  }
  EXPECT_NEAR(now, before, 1e-4);
  EXPECT_GT(crossed, 10);
  // Untouched far from the path.
  EXPECT_EQ(after.unstableM(0, 39), 0.02f);
}

TEST(Ski, ASkierOnALoadedSlopeSetsOffAnAvalanche) {
  // 40 degree slope loaded with a metre of unstable snow: the season's skier triggers a release.
  SnowState s = test::terrainFrom(60, 80, 10.0, -8.f, [](double, double y) { return 2500.0 - std::tan(40.0 * kPi / 180.0) * y; });
  for (size_t i = 0; i < s.stableM.size(); ++i) s.stableM.values()[i] = 0.5f, s.unstableM.values()[i] = 1.0f;
  auto backend = createCpuBackend();
  SeasonConfig cfg;
  cfg.days = 1.0;
  cfg.seed = 3;
  cfg.params.snowfallStartsPerDay = 0.0;
  cfg.params.avalancheRatePerKm2PerDay = 0.0;  // no spontaneous ones: only the skier's
  cfg.params.skiersPerHour = 0.0;
  cfg.params.skiTriggerFactor = 10.0;  // a loaded 40 degree slope: p = 1 at the first cell
  cfg.userSkiers.push_back({0.5, 30, 3, 1, nullptr});
  const SeasonReport rep = runSeason(*backend, s, cfg);
  ASSERT_EQ(rep.skiers.size(), 1u);
  EXPECT_TRUE(rep.skiers[0].triggered) << rep.skiers[0].why;
  ASSERT_FALSE(rep.avalanches.empty());
  EXPECT_TRUE(rep.avalanches[0].released);
  EXPECT_FALSE(rep.avalanches[0].user);
  EXPECT_GT(rep.avalanches[0].releasedM3, 100.0);
  EXPECT_NEAR(rep.avalanches[0].day, 0.5, 1e-9);
}

TEST(Ski, SameDescentForTheSameSeed) {
  BowlTerrain b1 = bowl(), b2 = bowl();
  ModelParameters p;
  SkiRun r1(*b1.backend, p, b1.state, nullptr), r2(*b2.backend, p, b2.state, nullptr);
  const SkierRecord a = r1.descend(20, 30, 1.0, 9, 5, true), c = r2.descend(20, 30, 1.0, 9, 5, true);
  ASSERT_EQ(a.path.size(), c.path.size());
  for (size_t i = 0; i < a.path.size(); ++i) EXPECT_EQ(a.path[i], c.path[i]);
}

}  // namespace
}  // namespace snow

namespace snow {
namespace {

TEST(Ski, BakeWritesTheTrackTextureAtItsOwnSize) {
  const std::string text =
      "[terrain]\nbuiltin = \"ridged\"\nsize = 64\ncell_size_m = 20\n[season]\ndays = 12\n[[events]]\ntype = \"snowfall\"\nday = 1\n"
      "duration_days = 4\n[[events]]\ntype = \"skier\"\nday = 8\nposition_m = [600, 200]\ncount = 2\n[parameters]\n"
      "skiers_per_hour = 2\n[outputs]\nlayers = [\"depth\", \"ski_tracks\", \"ski_route_map\"]\nencodings = [\"png16\"]\n"
      "ski_track_factor = 4\n";
  const test::Bake b = test::bakeSceneText("ski_texture", text);
  const auto manifest = nlohmann::json::parse(std::ifstream(b.out() / "manifest.json"));
  int listed = 0;
  for (const auto& f : manifest["files"]) {
    const std::string path = f["path"];
    if (path.rfind("ski_tracks", 0) != 0) continue;
    ++listed;
    EXPECT_EQ(f["width"], 256);
    EXPECT_EQ(f["height"], 256);
  }
  EXPECT_EQ(listed, 2);  // the EXR and the 16-bit PNG
  const Grid<float> t = readFloatImage((b.out() / "ski_tracks.exr").string());
  EXPECT_EQ(t.width(), 256);
  EXPECT_GT(*std::max_element(t.values().begin(), t.values().end()), 0.f);
  EXPECT_GT(manifest["run"]["skiers"].size(), 2u);
  EXPECT_TRUE(manifest["run"]["skiers"][0].contains("outcome"));
}

}  // namespace
}  // namespace snow

namespace snow {
namespace {

TEST(Ski, SameBytesOnOneAndTwoThreads) {
  const std::string base =
      "[terrain]\nbuiltin = \"ridged\"\nsize = 64\ncell_size_m = 20\n[season]\ndays = 15\n[[events]]\ntype = \"snowfall\"\nday = 1\n"
      "duration_days = 4\n[parameters]\nskiers_per_hour = 4\nski_trigger_factor = 1\n[outputs]\nlayers = [\"depth\", \"compacted\", "
      "\"ski_tracks\"]\n[run]\nbackend = \"cpu\"\n";
  const test::Bake one = test::bakeSceneText("ski_threads_1", base + "threads = 1\n");
  const test::Bake two = test::bakeSceneText("ski_threads_2", base + "threads = 2\n");
  auto bytes = [](const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  for (const char* f : {"depth.exr", "compacted.exr", "ski_tracks.exr"})
    EXPECT_TRUE(bytes(one.out() / f) == bytes(two.out() / f)) << f << " differs between 1 and 2 threads";
  // The manifests differ only in the scene (its text names the thread count).
  const auto m1 = nlohmann::json::parse(std::ifstream(one.out() / "manifest.json"));
  const auto m2 = nlohmann::json::parse(std::ifstream(two.out() / "manifest.json"));
  EXPECT_EQ(m1["run"], m2["run"]);
  EXPECT_EQ(m1["files"], m2["files"]);
  EXPECT_GT(m1["run"]["skiers"].size(), 10u);
}

}  // namespace
}  // namespace snow

namespace snow {
namespace {

TEST(Ski, DeviceRouteMapLoopGivesTheSameBytes) {
  SnowState r = test::makeRoughState(70, 51, 13);
  auto backend = test::createHostLikeADeviceBackend();
  backend->upload(r);
  Grid<float> out;
  ASSERT_TRUE(backend->routeMapOnDevice(out));
  EXPECT_EQ(out.values(), routeMap(r.bedrockM, r.validCell, r.spec).values());
  auto cpu = createCpuBackend();
  Grid<float> unused;
  EXPECT_FALSE(cpu->routeMapOnDevice(unused));  // the host backend leaves it to the sort
}

}  // namespace
}  // namespace snow

namespace snow {
namespace {

// On rough ground, a skier whose smooth turn is refused turns straight at its target in the
// same step; it used to redraw the target and turn toward the old one, and could spin in place
// until the step limit (seen in the art-direction example: "1 cells, 10 m; step limit").
TEST(Ski, NoDescentSpinsInPlaceOnRoughGround) {
  SnowState s = referenceRangeState(256, 2560.0);
  s.stableM.fill(1.0f);
  auto backend = createCpuBackend();
  backend->upload(s);
  ModelParameters p;
  p.skiTriggerFactor = 0.0;
  SkiRun run(*backend, p, s, nullptr);
  int spun = 0, moved = 0;
  for (uint64_t k = 0; k < 400; ++k) {
    int x = 0, y = 0;
    ASSERT_TRUE(run.pickStart((k + 0.5) / 400.0, x, y));
    const SkierRecord r = run.descend(x, y, 1.0, 3, k, false);
    spun += r.why == "step limit";
    moved += r.cells > 0;
  }
  std::printf("[ measure ] 400 descents on the rough range at 10 m: %d moved, %d hit the step limit\n", moved, spun);
  EXPECT_EQ(spun, 0);
  EXPECT_GT(moved, 300);
}

}  // namespace
}  // namespace snow

namespace snow {
namespace {

// The skier kernels' own atan and exp (phenomena/skiers.h: + - * / only, so every executor gives the
// same bytes) against the C library.
TEST(Ski, KernelMathMatchesTheLibrary) {
  double worstAtan = 0.0, worstExp = 0.0;
  for (int k = 0; k <= 200000; ++k) {
    const double t = k < 100000 ? k * 2e-5 : std::pow(10.0, (k - 100000) * 8e-5);  // [0, 2] then [1, 1e8]
    worstAtan = std::max(worstAtan, std::abs(skimath::atanPositive(t) - std::atan(t)));
    const double x = -699.0 * k / 200000.0;
    worstExp = std::max(worstExp, std::abs(skimath::expNonPositive(x) - std::exp(x)) / std::exp(x));
  }
  std::printf("[ measure ] largest error: atan %.2e (absolute), exp %.2e (relative)\n", worstAtan, worstExp);
  EXPECT_LT(worstAtan, 1e-15);
  EXPECT_LT(worstExp, 1e-14);
  EXPECT_EQ(skimath::expNonPositive(-800.0), 0.0);
  EXPECT_EQ(skimath::expNonPositive(std::nan("")), 0.0);
}

std::vector<SkierStart> manyStarts(const SkiRun& run, int n, uint64_t firstId) {
  std::vector<SkierStart> starts;
  for (int k = 0; k < n; ++k) {
    int x = 0, y = 0;
    EXPECT_TRUE(run.pickStart((k + 0.5) / n, x, y));
    starts.push_back({x, y, firstId + static_cast<uint64_t>(k), false});
  }
  return starts;
}

// Skiers moved together (phenomena/skiers.h) take the paths they take alone (a move reads only the
// surface, which skiers do not change), and the cells they enter are compacted exactly as if each
// entry were applied one after the other in (move, skier) order: the batch's layers equal a host
// replay of the paths, to the bit, with 16 skiers sharing one start cell among 200.
TEST(Ski, SkiersMovedTogetherKeepTheirPathsAndCompactInSkierOrder) {
  SnowState s = referenceRangeState(192, 1920.0);
  s.stableM.fill(0.6f);
  s.unstableM.fill(0.12f);
  ModelParameters p;
  p.skiTriggerFactor = 0.0;
  p.skiCompactionM = 0.05;
  auto together = createCpuBackend();
  together->upload(s);
  SkiRun run(*together, p, s, nullptr);
  std::vector<SkierStart> starts = manyStarts(run, 184, 0);
  for (int k = 0; k < 16; ++k) starts.push_back({starts[7].x, starts[7].y, 1000u + static_cast<uint64_t>(k), true});
  const std::vector<SkierRecord> batch = run.descendTogether(starts, 1.0, 5);
  SnowState after = s;
  together->download(after);

  // Alone, on the untouched snow: the same paths.
  size_t moved = 0;
  for (size_t k = 0; k < starts.size(); ++k) {  // each of the 200
    auto alone = createCpuBackend();
    alone->upload(s);
    SkiRun one(*alone, p, s, nullptr);
    const SkierRecord r = one.descend(starts[k].x, starts[k].y, 1.0, 5, starts[k].id, true);
    EXPECT_EQ(r.path, batch[k].path) << k;
    EXPECT_EQ(r.why, batch[k].why) << k;
  }
  for (const SkierRecord& r : batch) moved += r.cells > 3;
  EXPECT_GT(moved, 120u);

  // Host replay: every entry (the start cell at move 0, then each cell change along the path at
  // its move), applied in (move, skier) order with the kernel's arithmetic.
  struct Entry {
    size_t move, skier;
    int cell;
  };
  std::vector<Entry> entries;
  const int w = s.spec.width;
  for (size_t k = 0; k < batch.size(); ++k) {
    const auto& path = batch[k].path;
    if (path.empty()) continue;
    int last = -1;
    for (size_t m = 0; m < path.size(); ++m) {
      const int cell = static_cast<int>(path[m][1] / s.spec.cellSizeYM) * w + static_cast<int>(path[m][0] / s.spec.cellSizeXM);
      if (cell != last) entries.push_back({m, k, cell});
      last = cell;
    }
  }
  std::stable_sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return a.move != b.move ? a.move < b.move : a.skier < b.skier;
  });
  SnowState replay = s;
  SnowFieldsView v;
  v.width = w;
  v.height = s.spec.height;
  v.unstable = replay.unstableM.data();
  v.stable = replay.stableM.data();
  v.compacted = replay.compactedM.data();
  for (const Entry& e : entries) skier::compact(v, e.cell, static_cast<float>(p.skiCompactionM));
  EXPECT_EQ(replay.unstableM.values(), after.unstableM.values());
  EXPECT_EQ(replay.stableM.values(), after.stableM.values());
  EXPECT_EQ(replay.compactedM.values(), after.compactedM.values());
  // The shared start cell: 16 group skiers and the one drawn there took 0.12 m of U, then S.
  const int c = starts[7].y * w + starts[7].x;
  EXPECT_EQ(after.unstableM.values()[static_cast<size_t>(c)], 0.f);
  EXPECT_GT(after.compactedM.values()[static_cast<size_t>(c)], 0.5f);
  std::printf("[ measure ] %zu skiers moved together, %zu entries replayed\n", batch.size(), entries.size());
}

// The same batch (with avalanche triggers on, which read U as the batch leaves it) gives the same
// records and bytes on the serial executor and on TBB with 1 and 2 threads.
TEST(Ski, SkierBatchSameBytesOnEveryExecutor) {
  SnowState s = referenceRangeState(160, 1600.0);
  s.stableM.fill(0.5f);
  s.unstableM.fill(0.3f);
  ModelParameters p;
  p.skiTriggerFactor = 0.3;
  auto runOn = [&](SnowBackend& b, SnowState& out) {
    b.upload(s);
    SkiRun run(b, p, s, nullptr);
    std::vector<SkierStart> starts = manyStarts(run, 120, 0);
    for (int k = 0; k < 8; ++k) starts.push_back({starts[3].x, starts[3].y, 500u + static_cast<uint64_t>(k), true});
    auto records = run.descendTogether(starts, 1.0, 77);
    out = s;
    b.download(out);
    return records;
  };
  auto serial = createSerialBackend();
  SnowState a, b1, b2;
  const auto ra = runOn(*serial, a);
  std::vector<SkierRecord> rb1, rb2;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    auto cpu = createCpuBackend();
    rb1 = runOn(*cpu, b1);
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    auto cpu = createCpuBackend();
    rb2 = runOn(*cpu, b2);
  }
  int triggered = 0, moved = 0;
  for (size_t k = 0; k < ra.size(); ++k) {
    moved += ra[k].cells > 3;
    for (const auto* other : {&rb1, &rb2}) {
      EXPECT_EQ(ra[k].path, (*other)[k].path) << k;
      EXPECT_EQ(ra[k].why, (*other)[k].why) << k;
      EXPECT_EQ(ra[k].cells, (*other)[k].cells) << k;
    }
    triggered += ra[k].triggered;
  }
  std::printf("[ measure ] %zu skiers: %d moved more than 3 cells, %d triggered an avalanche\n", ra.size(), moved, triggered);
  EXPECT_GT(triggered, 0);
  EXPECT_GT(moved, 40);
  test::expectSameBytes(a, b1);
  test::expectSameBytes(a, b2);
}

}  // namespace
}  // namespace snow
