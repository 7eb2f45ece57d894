// Every step a SnowBackend runs, as a table of cases run on two backends from the same state:
// the registered season steps, art direction with timeline edits, an avalanche to rest, the wind
// bedforms (closed with a mask, and periodic) and a batch of skiers. The GPU binary checks CUDA
// against the serial reference with it, tests/backend_test.cpp the TBB backend; a step the
// backend gains goes here to be checked on both. Header-only and free of TBB (the GPU binary
// links none).
#pragma once
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "core/avalanche_runs.h"
#include "core/bedform_runs.h"
#include "core/kernel_registry.h"
#include "core/ski_runs.h"
#include "tests/test_support.h"

namespace snow::test {

struct ParityCase {
  std::string name;
  std::function<SnowState()> fixture;
  // Runs the case on `backend`, which holds `state` (uploaded); returns what the steps reported
  // (ledgers, counts, records), to be compared exactly.
  std::function<std::vector<double>(SnowBackend& backend, const SnowState& state)> run;
};

inline ModelParameters parityParameters() {
  ModelParameters p;
  p.rainSnowLimitM = 1500.0;
  return p;
}
inline WeatherState parityWarmWeather() {
  WeatherState w;
  w.seaLevelTemperatureC = 14.0;  // warm enough that low cells melt: every kernel has work
  return w;
}

// Painted multipliers on every phenomenon that takes one, and a grey mask for the edits.
inline SnowState artDirectionFixture() {
  SnowState s = makeRoughState(167, 131, 43);
  s.snowfallFactor.resize(s.spec.width, s.spec.height, 0.f);
  s.meltFactor.resize(s.spec.width, s.spec.height, 0.f);
  s.windErosionFactor.resize(s.spec.width, s.spec.height, 0.f);
  for (int y = 0; y < s.spec.height; ++y)
    for (int x = 0; x < s.spec.width; ++x) {
      s.snowfallFactor(x, y) = static_cast<float>(x % 7) / 3.f;
      s.meltFactor(x, y) = static_cast<float>(y % 5) / 2.f;
      s.windErosionFactor(x, y) = (x + y) % 3 == 0 ? 0.f : 1.5f;
    }
  return s;
}
inline std::vector<double> artDirectionAndEdits(SnowBackend& b, const SnowState& s) {
  const ModelParameters p = parityParameters();
  std::vector<float> weights(s.spec.cellCount());
  for (int y = 0; y < s.spec.height; ++y)
    for (int x = 0; x < s.spec.width; ++x) weights[static_cast<size_t>(y) * s.spec.width + x] = static_cast<float>((x * 3 + y) % 11) / 10.f;
  std::vector<double> out;
  out.push_back(b.snowfall(makeSnowfallArgs(p, 0.5, WeatherState{})));
  out.push_back(b.melt(makeMeltArgs(p, 0.5, parityWarmWeather())));
  b.windTransport(makeWindTransportArgs(p, 0.5));
  for (EditOp op : {EditOp::Add, EditOp::Remove, EditOp::Set, EditOp::Move})
    out.push_back(b.applyEdit(EditArgs{op, static_cast<int>(SnowLayer::Unstable), static_cast<int>(SnowLayer::Stable), 0.7f, true}, weights));
  return out;
}

// Unstable snow everywhere, released near the middle and run to rest.
inline SnowState avalancheFixture() {
  SnowState s = makeRoughState(203, 157, 29);
  for (int y = 0; y < s.spec.height; ++y)
    for (int x = 0; x < s.spec.width; ++x)
      if (s.validCell(x, y)) s.unstableM(x, y) = 1.5f;
  return s;
}
inline std::vector<double> avalancheToRest(SnowBackend& b, const SnowState& s) {
  int rx = 100, ry = 80;
  while (!s.validCell(rx, ry)) ++rx;
  const ModelParameters params;
  AvalancheRun run(b, params, s);
  run.release(rx, ry, 0.0, -5.0, true);
  const AvalancheRecord r = run.runToRest();
  EXPECT_TRUE(r.released);
  EXPECT_GT(r.steps, 1);
  return {static_cast<double>(r.released), static_cast<double>(r.steps), static_cast<double>(r.substeps), r.runoutM,
          r.releasedM3, r.depositM3, static_cast<double>(r.footprintCells), r.maxSpeedMps};
}

// A closed grid with NODATA holes, a bedform mask and a wind turning with the row.
inline SnowState closedBedformFixture() {
  SnowState s = makeBedformWindow(150, 122, 0.5, 0.08, 0.05, 8.f, 0.f, -6.f, 5);
  s.bedformMask.resize(150, 122, 0);
  for (int y = 0; y < 122; ++y)
    for (int x = 0; x < 150; ++x) {
      s.windYMps(x, y) = 4.f * std::sin(0.05f * static_cast<float>(y));
      s.bedrockM(x, y) = 0.01f * static_cast<float>(x) + ((x / 20 + y / 20) % 4 == 0 ? 0.6f : 0.f);
      s.bedformMask(x, y) = x < 120 ? 1 : 0;
      if ((x - 75) * (x - 75) + (y - 40) * (y - 40) < 16) s.validCell(x, y) = 0;
    }
  return s;
}
inline void appendBedformReport(std::vector<double>& out, const BedformStepReport& r) {
  for (long long v : {r.slabsEroded, r.slabsAvalanched, r.slabsBefore, r.slabsAfter, r.domainCells}) out.push_back(static_cast<double>(v));
  out.push_back(r.reposeConverged);
  EXPECT_EQ(r.slabsBefore, r.slabsAfter);  // slabs are conserved
}
inline std::vector<double> closedBedformSteps(SnowBackend& b, const SnowState&) {
  BedformParameters p;
  p.sinteringPerDay = 0.3;
  p.speedupLinear = 1.2;
  std::vector<double> out;
  for (int step = 0; step < 3; ++step) appendBedformReport(out, b.bedformStep(makeBedformArgs(p, 0.2, 15, 15 * step, 7, -2.0)));
  return out;
}
inline std::vector<double> periodicBedformStep(SnowBackend& b, const SnowState&) {
  BedformParameters q = periodicBedformParameters();
  q.sinteringPerDay = 0.5;  // the cohesion too
  std::vector<double> out;
  appendBedformReport(out, b.bedformStep(makeBedformArgs(q, 0.5, 40, 0, 1, 0.0)));
  return out;
}

// A batch of skiers moved together, several sharing start cells, every path flattened.
inline std::vector<double> skierBatch(SnowBackend& b, const SnowState& s) {
  ModelParameters p;
  p.skiMinSnowM = 0.2;
  p.skiTriggerFactor = 0.5;
  p.skiLookaheadM = 20.0;
  SkiRun run(b, p, s, nullptr);
  std::vector<SkierStart> starts;
  for (int k = 0; k < 48; ++k) starts.push_back({20 + (k % 6) * 3, 10 + (k / 6) * 15, static_cast<uint64_t>(k), k % 2 == 0});
  for (int k = 0; k < 8; ++k) starts.push_back({40, 70, static_cast<uint64_t>(100 + k), true});  // one start cell
  std::vector<double> out;
  int moved = 0;
  for (const SkierRecord& r : run.descendTogether(starts, 1.0, 11)) {
    out.insert(out.end(), {static_cast<double>(r.cells), r.lengthM, r.dropM, static_cast<double>(r.triggered),
                           static_cast<double>(r.why.size()), static_cast<double>(r.path.size())});
    for (const auto& point : r.path) out.insert(out.end(), point.begin(), point.end());
    moved += r.cells > 0;
  }
  EXPECT_GT(moved, 10);
  return out;
}

inline std::vector<ParityCase> backendParityCases() {
  std::vector<ParityCase> cases;
  for (RegisteredStep& step : registeredSteps(parityParameters(), parityWarmWeather()))
    cases.push_back({step.name, [] { return makeRoughState(203, 157, 17); },  // odd sizes: partial blocks and rows
                     [run = step.run](SnowBackend& b, const SnowState&) { return std::vector<double>{run(b)}; }});
  cases.push_back({"art direction and edits", artDirectionFixture, artDirectionAndEdits});
  cases.push_back({"avalanche", avalancheFixture, avalancheToRest});
  cases.push_back({"bedforms, closed with a mask", closedBedformFixture, closedBedformSteps});
  cases.push_back({"bedforms, periodic", [] { return makeBarchanWindow(256); }, periodicBedformStep});
  cases.push_back({"skier batch", [] { return makeRoughState(181, 143, 31); }, skierBatch});
  return cases;
}

// Runs `c` on both backends from its fixture; the reports, the downloaded fields, the totals and
// the bedforms' cohesion must be the same bits.
inline void expectSameRun(const ParityCase& c, SnowBackend& reference, SnowBackend& other) {
  SCOPED_TRACE(c.name);
  const SnowState initial = c.fixture();
  SnowState a = initial, b = initial;
  reference.upload(a);
  other.upload(b);
  const std::vector<double> ra = c.run(reference, a), rb = c.run(other, b);
  EXPECT_EQ(ra, rb);
  reference.download(a);
  other.download(b);
  expectSameBytes(a, b);
  EXPECT_EQ(a.bedformCohesion.values(), b.bedformCohesion.values());
  EXPECT_EQ(reference.totals().totalM3(), other.totals().totalM3());
  // The case did something on its fixture.
  bool changed = false;
#define SNOW_PARITY_CHANGED(member, view, Element, role, access, fill) \
  changed = changed || (downloadedWithState(FieldRole::role) && a.member.values() != initial.member.values());
  SNOW_STATE_FIELDS(SNOW_PARITY_CHANGED)
#undef SNOW_PARITY_CHANGED
  EXPECT_TRUE(changed) << c.name << " changed nothing on its fixture";
}

}  // namespace snow::test
