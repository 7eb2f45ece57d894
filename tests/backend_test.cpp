// The CPU backend gives the same bytes as the serial reference, for every registered step and
// whatever the thread count.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <functional>
#include <set>
#include <string>

#include "core/cpu_backend.h"
#include "core/season.h"
#include "core/kernel_registry.h"
#include "core/phenomena/powder_diffusion_rows.h"
#include "gpu/backend_parity.h"
#include "host_like_a_device.h"
#include "test_support.h"

using namespace snow;

namespace {

WeatherState warmWeather() {
  WeatherState w;
  w.seaLevelTemperatureC = 14.0;  // warm enough that low cells melt: every kernel has work
  return w;
}

ModelParameters testParameters() {
  ModelParameters p;
  p.rainSnowLimitM = 1500.0;
  return p;
}

SnowState runAll(SnowBackend& backend, const SnowState& initial, std::vector<double>* ledger) {
  SnowState s = initial;
  backend.upload(s);
  for (int round = 0; round < 3; ++round)
    for (const auto& step : registeredSteps(testParameters(), warmWeather())) ledger->push_back(step.run(backend));
  backend.download(s);
  const LayerTotals t = backend.totals();
  ledger->push_back(t.totalM3());
  return s;
}


}  // namespace

// Every step the backend runs (tests/gpu/backend_parity.h, the table the GPU binary checks CUDA
// with) gives the serial reference's bytes.
TEST(CpuBackend, EveryBackendStepMatchesSerialBitForBit) {
  for (const test::ParityCase& c : test::backendParityCases()) {
    auto serial = createSerialBackend();
    auto cpu = createCpuBackend();
    test::expectSameRun(c, *serial, *cpu);
  }
}

// Upload then download (snow_fields.h's roles) brings back exactly the downloaded fields, bytes
// intact, and leaves every other field of the destination as it was.
TEST(CpuBackend, DownloadFillsExactlyTheDownloadedFields) {
  SnowState s = test::makeRoughState(23, 17, 5);
  std::vector<std::string> names;
  forEachSnowField(s, [&](const SnowFieldInfo& f, auto& grid) {  // every field, optional ones too
    names.push_back(f.name);
    grid.resize(s.spec.width, s.spec.height);
    for (size_t i = 0; i < grid.size(); ++i) grid.values()[i] = static_cast<uint8_t>((i + names.size()) % 2);
  });
  s.compactedM.values()[5] = 0.625f;  // and a value that is no byte
  ASSERT_EQ(names.front(), "bedrockM");
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size());
  auto backend = createCpuBackend();
  backend->upload(s);
  SnowState d = s;
  forEachSnowField(d, [](const SnowFieldInfo&, auto& grid) { grid.fill(7); });
  backend->download(d);
#define SNOW_EXPECT_DOWNLOADED(member, view, Element, role, access, fill)                                 \
  if (downloadedWithState(FieldRole::role)) {                                                            \
    EXPECT_EQ(d.member.values(), s.member.values()) << #member;                                          \
  } else {                                                                                               \
    EXPECT_EQ(d.member.values(), std::vector<Element>(s.member.size(), static_cast<Element>(7))) << #member; \
  }
  SNOW_STATE_FIELDS(SNOW_EXPECT_DOWNLOADED)
#undef SNOW_EXPECT_DOWNLOADED
  EXPECT_EQ(d.compactedM.values()[5], 0.625f);
}

TEST(CpuBackend, OneAndTwoThreadsGiveTheSameBytes) {
  const SnowState initial = test::makeRoughState(130, 77, 9);
  std::vector<double> l1, l2, lSerial;
  SnowState one, two, serial;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    auto b = createCpuBackend();
    one = runAll(*b, initial, &l1);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    auto b = createCpuBackend();
    two = runAll(*b, initial, &l2);
  }
  auto s = createSerialBackend();
  serial = runAll(*s, initial, &lSerial);
  test::expectSameBytes(one, two);
  test::expectSameBytes(one, serial);
  EXPECT_EQ(l1, l2);
  EXPECT_EQ(l1, lSerial);
}

TEST(CpuBackend, TotalsAreLayerSumsTimesCellArea) {
  SnowState s = test::makeRoughState(20, 10, 2, 3.0, 4.0);
  auto b = createCpuBackend();
  b->upload(s);
  double expected = 0.0;
  for (int y = 0; y < 10; ++y) {
    double row = 0.0;
    for (int x = 0; x < 20; ++x)
      if (s.validCell(x, y)) row += s.powderM(x, y);
    expected += row;
  }
  EXPECT_DOUBLE_EQ(b->totals().powderM3, expected * 12.0);
}

namespace {
// AVX2 lanes allowed or not for a scope, allowed again when it ends (whatever ends it).
struct Avx2LanesAllowed {
  explicit Avx2LanesAllowed(bool allowed) { lanesAvx2Allowed() = allowed; }
  ~Avx2LanesAllowed() { lanesAvx2Allowed() = true; }
};

// Runs `steps` on the serial and the CPU backend from `initial(width, height)` on grids of any
// shape (narrower than a vector, a last strip of one row, strips that end mid-grid), with AVX2
// allowed (where the CPU has it: eight cells, then four, then one) and with SSE2 alone: the same
// bytes, and powder moved on the grids 37 cells wide or more.
void expectRowPathGivesTheSerialBytesOnAnyShape(const std::function<SnowState(int, int)>& initial,
                                                const std::function<void(SnowBackend&, const SnowState&)>& steps) {
  const int shapes[][2] = {{1, 1}, {3, 2}, {2, 40}, {5, 33}, {37, 31}, {38, 32}, {41, 65}, {64, 97}};
  for (const bool avx2 : {true, false}) {
    for (const auto& shape : shapes) {
      SCOPED_TRACE(std::to_string(shape[0]) + " x " + std::to_string(shape[1]) + (avx2 ? ", AVX2 allowed" : ", SSE2 alone"));
      const SnowState start = initial(shape[0], shape[1]);
      SnowState a = start, b = start;
      auto serial = createSerialBackend();
      auto cpu = createCpuBackend();
      serial->upload(a);
      cpu->upload(b);
      {
        const Avx2LanesAllowed lanes(avx2);
        steps(*serial, start);
        steps(*cpu, start);
      }
      serial->download(a);
      cpu->download(b);
      test::expectSameBytes(a, b);
      if (shape[0] >= 37) {
        EXPECT_NE(a.powderM.values(), start.powderM.values()) << "no powder moved";
      }
    }
  }
}
}  // namespace

// Powder diffusion's row path (its passes interleaved in strips of 32 rows, four or eight cells at
// a time) gives the per-cell bodies' bytes on any shape, with NODATA holes and cliffs.
TEST(CpuBackend, PowderDiffusionRowPathMatchesSerialOnAnyShape) {
  expectRowPathGivesTheSerialBytesOnAnyShape([](int w, int h) { return test::makeRoughState(w, h, 3, 2.0, 3.0); },
                                             [](SnowBackend& backend, const SnowState&) {
                                               PowderDiffusionArgs args;
                                               args.dtDays = 0.3f;
                                               for (int i = 0; i < 4; ++i) backend.powderDiffusion(args);
                                             });
}

// Wind transport's row paths (four or eight cells at a time on the inner cells) give the per-cell
// bodies' bytes on any shape, with winds of either sign along each axis, calm cells, wind shadows,
// NODATA holes, an erosion multiplier, the scour and deposit records, and then cells the bedform
// model holds (they give nothing).
TEST(CpuBackend, WindTransportRowPathMatchesSerialOnAnyShape) {
  auto windy = [](int w, int h) {
    SnowState s = test::makeRoughState(w, h, 4, 2.0, 3.0);
    s.windErosionFactor.resize(w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const int k = (3 * x + 5 * y) % 11;  // every sign and calm along each axis
        s.windXMps(x, y) = k < 3 ? 0.f : (k < 7 ? 9.f - x % 4 : -6.f - y % 3);
        s.windYMps(x, y) = k % 3 == 0 ? 0.f : (k % 3 == 1 ? 4.f : -7.f + x % 2);
        s.windErosionFactor(x, y) = 0.5f + 0.25f * static_cast<float>((x + y) % 4);
      }
    return s;
  };
  expectRowPathGivesTheSerialBytesOnAnyShape(windy, [](SnowBackend& backend, const SnowState& start) {
    const WindTransportArgs args{0.5f, 20.f, 0.1f};  // a strong erosion: shares cut by the powder
    for (int i = 0; i < 3; ++i) backend.windTransport(args);
    std::vector<uint8_t> bedforms(start.spec.cellCount());
    for (size_t i = 0; i < bedforms.size(); ++i) bedforms[i] = i % 5 == 2 || i % 7 == 0;
    backend.useBedformDomain(bedforms);
    for (int i = 0; i < 2; ++i) backend.windTransport(args);
  });
}

// Snowfall and the stability change fused with their slope snapshot by rows (TbbExec::
// forEachCellThen: each strip's edge rows first, then a ring of two slope rows; each row's cells
// in lanes, snowfall_lanes.inc and stability_lanes.inc) give the two
// whole-grid passes' bytes on any shape: heavy snowfall (which changes the surface the next row's
// slope reads) under a precipitation map, stability days from cold to hot (its lanes, stability_lanes.inc, take every
// piece of the rate), NODATA holes, cliffs and wind loading.
TEST(CpuBackend, SlopeFusedWithSnowfallAndStabilityMatchesSerialOnAnyShape) {
  auto withPrecipitationMap = [](int w, int h) {
    SnowState s = test::makeRoughState(w, h, 6, 60.0, 80.0);  // slopes of about 0.3 to 1.5: the shares do not clamp
    s.snowfallFactor.resize(w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) s.snowfallFactor(x, y) = 0.25f * static_cast<float>((x + 2 * y) % 5);  // none to twice
    return s;
  };
  expectRowPathGivesTheSerialBytesOnAnyShape(withPrecipitationMap,
                                             [](SnowBackend& backend, const SnowState&) {
                                               SnowfallArgs fall;
                                               fall.snowfallRatePerDay = 2e-3f;  // about a metre a day at 1500 m
                                               fall.rainSnowLimitM = 1000.f;
                                               // Days whose cells span each piece of the rate: below T_freeze,
                                               // between T_freeze and T_cool, T_cool and T_warm, above T_warm.
                                               // The model's rates (the struct's 1e4 m a day would move whole
                                               // layers whatever the slope).
                                               StabilityArgs days[3];
                                               for (StabilityArgs& d : days) d.instabilityByWarmthMPerDay = 1.f, d.stabilityByColdMPerDay = 0.3f;
                                               days[0].seaLevelTemperatureC = 12.f;
                                               days[0].windInstabilityPerMps2 = 0.5f;
                                               days[1].seaLevelTemperatureC = -2.f;
                                               days[2].seaLevelTemperatureC = 30.f;
                                               for (int i = 0; i < 3; ++i) {
                                                 backend.snowfall(fall);
                                                 backend.stabilityChange(days[i]);
                                               }
                                             });
}

// The bake's daily refill of the temperature with a constant wind: the season releases the host's
// static fields and refills the exposure and temperature only; the wind the backend holds must stay
// (it was uploaded empty, and freed on CUDA). The same bytes as a season refilling the wind too.
TEST(Backend, StaticFieldsTheHostReleasedKeepTheBackendsValuesThroughADailyRefill) {
  const SnowState initial = test::makeRoughState(40, 32, 5);
  auto season = [&](SnowBackend& backend, bool refillWind) {
    SnowState s = initial;
    const SnowState wind = initial;
    SeasonConfig c;
    c.days = 4;
    c.seed = 3;
    c.windTransport = true;
    c.params = testParameters();
    c.updateStaticFields = [&wind, refillWind](int day, SnowState& st) {
      st.exposureHours = Grid<float>(st.spec.width, st.spec.height, 2.f + static_cast<float>(day));
      st.temperatureBaseC = wind.temperatureBaseC;
      if (refillWind) st.windXMps = wind.windXMps, st.windYMps = wind.windYMps, st.windEffectZM = wind.windEffectZM, st.windLoadingMps2 = wind.windLoadingMps2;
    };
    const SeasonReport r = runSeason(backend, s, c);
    EXPECT_GT(r.phenomena.size(), 0u);
    return s;
  };
  // Host storage whose upload of nothing frees the buffer, as CUDA's does.
  auto freeing = test::createHostLikeADeviceBackend(), reference = test::createHostLikeADeviceBackend();
  const SnowState kept = season(*freeing, false);
  const SnowState refilled = season(*reference, true);
  test::expectSameBytes(kept, refilled);
  double scour = 0;
  for (float v : kept.windScourM.values()) scour += v;
  EXPECT_GT(scour, 0.0);  // the wind moved snow after the first day
}

// On a host backend the avalanche runner reads the backend's own layers in place of a 16-byte
// snapshot, and keeps the layers at release of the cells each step may reach: the same season,
// avalanche records and maps (with frames of their motion) as from a snapshot, also where a
// user's skiers compact snow while an avalanche runs.
TEST(Backend, AvalanchesReadingTheLayersInPlaceAreTheBytesOfAvalanchesFromASnapshot) {
  const SnowState initial = test::makeRoughState(48, 40, 7);
  auto season = [&](SnowBackend& backend, SeasonReport& report) {
    SnowState s = initial;
    for (auto& u : s.unstableM.values()) u += 0.6f;
    SeasonConfig c;
    c.days = 6;
    c.seed = 5;
    c.params = testParameters();
    c.params.avalancheRatePerKm2PerDay = 400.0;
    c.avalancheMaps = true;
    c.avalancheFrameIntervalS = 1.0;
    c.userAvalanches = {{1.0, 20, 10, false, nullptr}, {3.0, 0, 0, false, std::make_shared<std::vector<uint8_t>>(48 * 40, uint8_t{1})}};
    // Skiers at the instant of the day-3 release: they compact snow while the avalanche runs.
    c.userSkiers = {{3.0, 24, 4, 12, nullptr}};
    report = runSeason(backend, s, c);
    return s;
  };
  // The snapshot: host storage the avalanche runner takes for a device's (hostSnowLayers false).
  auto inPlace = createSerialBackend(), snapshot = test::createHostLikeADeviceBackend();
  SeasonReport a, b;
  const SnowState endA = season(*inPlace, a), endB = season(*snapshot, b);
  test::expectSameBytes(endA, endB);
  ASSERT_EQ(a.avalanches.size(), b.avalanches.size());
  size_t released = 0, moved = 0;
  for (size_t k = 0; k < a.avalanches.size(); ++k) {
    const AvalancheRecord &x = a.avalanches[k], &y = b.avalanches[k];
    released += x.released;
    moved += x.steps > 3;
    EXPECT_EQ(x.releaseCells, y.releaseCells) << k;
    EXPECT_EQ(x.footprintCells, y.footprintCells) << k;
    EXPECT_EQ(x.releasedM3, y.releasedM3) << k;
    EXPECT_EQ(x.depositM3, y.depositM3) << k;
    EXPECT_EQ(x.runoutM, y.runoutM) << k;
    EXPECT_EQ(x.fallHeightM, y.fallHeightM) << k;
    ASSERT_EQ(bool(x.maps), bool(y.maps)) << k;
    if (!x.maps) continue;
    EXPECT_TRUE(x.maps->scour.grid.values() == y.maps->scour.grid.values()) << k;
    EXPECT_TRUE(x.maps->deposit.grid.values() == y.maps->deposit.grid.values()) << k;
    EXPECT_TRUE(x.maps->depthAtRelease.values() == y.maps->depthAtRelease.values()) << k;
    ASSERT_EQ(x.maps->frames.size(), y.maps->frames.size()) << k;
    for (size_t f = 0; f < x.maps->frames.size(); ++f) EXPECT_TRUE(x.maps->frames[f].second.grid.values() == y.maps->frames[f].second.grid.values()) << k;
  }
  EXPECT_GT(released, 5u);
  EXPECT_GT(moved, 1u) << "no avalanche ran more than three steps";
}

// The layers at release the avalanche runner keeps only for the cells its steps may reach give
// each avalanche's deposit and footprint as the whole grid's before and after do.
TEST(Backend, AvalancheDepositAndFootprintFromTheCellsItMayReachAreTheWholeGridsDifference) {
  SnowState s = test::makeRoughState(64, 48, 11);
  for (auto& u : s.unstableM.values()) u += 0.8f;
  const ModelParameters p = testParameters();
  auto serial = createSerialBackend();
  SnowBackend& backend = *serial;
  backend.upload(s);
  AvalancheRun run(backend, p, s);
  int ran = 0;
  for (int k = 0; k < 6; ++k) {
    SnowState before = s, after = s;
    backend.download(before);
    if (!run.release(8 + 9 * k, 5 + 3 * k, 1.0, -5.0, true)) continue;
    const AvalancheRecord r = run.runToRest();
    backend.download(after);
    double deposit = 0;
    int footprint = 0;
    for (size_t i = 0; i < s.spec.cellCount(); ++i) {
      if (!s.validCell.values()[i]) continue;
      const double change = (static_cast<double>(after.stableM.values()[i]) + after.unstableM.values()[i] + after.powderM.values()[i]) -
                            (static_cast<double>(before.stableM.values()[i]) + before.unstableM.values()[i] + before.powderM.values()[i]);
      footprint += std::abs(change) > 1e-3;
      if (change > 0) deposit += change * s.spec.cellAreaM2();
    }
    EXPECT_EQ(r.footprintCells, footprint) << k;
    EXPECT_EQ(r.depositM3, deposit) << k;
    ran += r.steps > 3;
  }
  EXPECT_GE(ran, 2) << "too few avalanches ran more than three steps";
}

// An edit (or a user's skiers) may write the layers while an avalanche runs: the runner keeps
// every cell's layers at release first (SnowBackend::beforeNextWrite), so reading them in place
// gives the records a snapshot taken at release gives.
TEST(Backend, ALayerWrittenWhileAnAvalancheRunsLeavesItsRecordsAsFromASnapshotAtRelease) {
  SnowState s = test::makeRoughState(64, 48, 11);
  for (auto& u : s.unstableM.values()) u += 0.8f;
  const ModelParameters p = testParameters();
  auto avalanche = [&](SnowBackend& backend) {
    backend.upload(s);
    AvalancheRun run(backend, p, s);
    EXPECT_TRUE(run.release(26, 14, 1.0, -5.0, true));
    for (int k = 0; k < 3; ++k) run.step();
    EditArgs add;
    add.op = EditOp::Add, add.layer = 2, add.depthM = 0.25f;  // unstable snow everywhere, mid-avalanche
    backend.applyEdit(add, {});
    return run.runToRest();
  };
  auto inPlace = createSerialBackend(), snapshot = test::createHostLikeADeviceBackend();
  const AvalancheRecord a = avalanche(*inPlace), b = avalanche(*snapshot);
  ASSERT_GT(a.steps, 6);
  EXPECT_GT(a.footprintCells, 0);
  EXPECT_EQ(a.footprintCells, b.footprintCells);
  EXPECT_EQ(a.depositM3, b.depositM3);
  EXPECT_EQ(a.runoutM, b.runoutM);
  EXPECT_EQ(a.fallHeightM, b.fallHeightM);
}

// The scratch a frame frees (SnowBackend::releaseScratch) comes back as it was: an avalanche
// after it, with a layer written while it runs, leaves the bytes it leaves without the frame.
TEST(Backend, ScratchFreedForAFrameChangesNoByteOfTheAvalanchesAfterIt) {
  SnowState s = test::makeRoughState(64, 48, 11);
  for (auto& u : s.unstableM.values()) u += 0.8f;
  const ModelParameters p = testParameters();
  auto season = [&](bool frame) {
    auto serial = createSerialBackend();
    SnowBackend& backend = *serial;
    backend.upload(s);
    AvalancheRun run(backend, p, s);
    EXPECT_TRUE(run.release(8, 5, 1.0, -5.0, true));
    run.runToRest();
    if (frame) backend.releaseScratch(true), run.releaseScratch();
    EXPECT_TRUE(run.release(26, 14, 1.0, -5.0, true));
    for (int k = 0; k < 3; ++k) run.step();
    EditArgs add;
    add.op = EditOp::Add, add.layer = 2, add.depthM = 0.25f;
    backend.applyEdit(add, {});
    const AvalancheRecord r = run.runToRest();
    EXPECT_GT(r.steps, 6);
    SnowState end = s;
    backend.download(end);
    return end;
  };
  test::expectSameBytes(season(true), season(false));
}
