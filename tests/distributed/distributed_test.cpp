// The decomposition of a distributed bake (distributed/, docs/distributed.md). The plain tests
// check the process grid and halo plan for every rank in one process; the Ranks tests run on as
// many ranks as the launcher started (ctest runs this binary alone and under mpirun with 2, 3
// and 4 ranks) and assert the same bytes as one process.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <vector>

#include "core/cpu_backend.h"
#include "core/default_terrain.h"
#include "core/parameters.h"
#include "core/season.h"
#include "core/ski_runs.h"
#include "core/snow_state.h"
#include "distributed/communicator.h"
#include "distributed/continuous_step.h"
#include "distributed/distributed_backend.h"
#include "distributed/decomposition.h"
#include "distributed/exact_sum.h"
#include "distributed/halo_exchange.h"
#include "distributed/local_state.h"
#include "distributed/wind_across_ranks.h"
#include "distributed/window_gather.h"
#include "precompute/wind_timeline.h"

namespace snow::dist {
namespace {

uint32_t mix(uint32_t x) {
  x ^= x >> 16, x *= 0x7feb352dU, x ^= x >> 15, x *= 0x846ca68bU, x ^= x >> 16;
  return x;
}
float unit(int x, int y, uint32_t salt) { return static_cast<float>(mix(x * 73856093U ^ y * 19349663U ^ salt) >> 8) / 16777216.f; }

// ---------------------------------------------------------------- the process grid, one process

TEST(Decomposition, ChoosesTheShortestCutsFewerColumnsOnATie) {
  EXPECT_EQ(Decomposition::choose(4, 512, 512, 8).columns, 2);
  EXPECT_EQ(Decomposition::choose(4, 512, 512, 8).rows, 2);
  EXPECT_EQ(Decomposition::choose(4, 1000, 100, 8).columns, 4);  // cut 300 cells, not 3000
  EXPECT_EQ(Decomposition::choose(4, 100, 1000, 8).rows, 4);
  EXPECT_EQ(Decomposition::choose(2, 300, 300, 8).columns, 1);  // a tie: two row strips
  EXPECT_EQ(Decomposition::choose(6, 600, 400, 8).columns, 3);  // 3 x 2: cut 1400 cells (2 x 3: 1600)
  EXPECT_EQ(Decomposition::choose(1, 7, 5, 3).ranks(), 1);
}

TEST(Decomposition, OwnedCellsCoverTheGridOnceAndLocalGridsAreThemWidenedByTheHalo) {
  for (int ranks = 1; ranks <= 8; ++ranks)
    for (auto [w, h] : {std::pair{97, 61}, std::pair{1000, 100}, std::pair{64, 640}, std::pair{37, 23}}) {
      const int halo = 4;
      const Decomposition d = Decomposition::choose(ranks, w, h, halo);
      ASSERT_EQ(d.ranks(), ranks);
      std::vector<int> owners(static_cast<size_t>(w) * h, 0);
      for (int r = 0; r < ranks; ++r) {
        const CellRect o = d.owned(r), l = d.local(r);
        EXPECT_GE(o.width(), halo);
        EXPECT_GE(o.height(), halo);
        for (int y = o.y0; y < o.y1; ++y)
          for (int x = o.x0; x < o.x1; ++x) ++owners[static_cast<size_t>(y) * w + x];
        EXPECT_EQ(l.intersect(o), o);
        EXPECT_EQ(l.x0, std::max(0, o.x0 - halo));
        EXPECT_EQ(l.y0, std::max(0, o.y0 - halo));
        EXPECT_EQ(l.x1, std::min(w, o.x1 + halo));
        EXPECT_EQ(l.y1, std::min(h, o.y1 + halo));
      }
      for (int c : owners) ASSERT_EQ(c, 1) << ranks << " ranks on " << w << " x " << h;
    }
}

TEST(Decomposition, RefusesSubdomainsNarrowerThanTheHaloSayingWhy) {
  try {
    Decomposition::choose(16, 20, 20, 8);
    FAIL() << "16 ranks split a 20 x 20 grid with an 8-cell halo";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("run fewer ranks"), std::string::npos) << e.what();
  }
}

TEST(Decomposition, OnTilesEveryCutFallsOnATileStartAndEachTileLiesInTheLocalGridOfTheRankItStartsIn) {
  struct Case {
    int width, height, size, step;  // tiles of `size` starting every `step` cells (overlap size - step)
  };
  const int halo = 7;
  for (const Case c : {Case{253, 253, 127, 126}, Case{129, 129, 33, 32}, Case{500, 300, 127, 126}, Case{2048, 2048, 505, 504},
                       Case{97, 61, 20, 17}}) {
    auto count = [&](int extent) { return extent <= c.size ? 1 : 1 + (extent - c.size + c.step - 1) / c.step; };
    const int columns = count(c.width), rows = count(c.height);
    for (int ranks = 1; ranks <= 6; ++ranks) {
      const std::optional<Decomposition> d = Decomposition::chooseOnTiles(ranks, c.width, c.height, halo, c.step, columns, rows);
      // These grids' last tiles leave bands wider than the halo: a split exists where a process
      // grid has no more columns and rows than there are tiles.
      bool fits = false;
      for (int pc = 1; pc <= ranks; ++pc) fits |= ranks % pc == 0 && pc <= columns && ranks / pc <= rows;
      ASSERT_EQ(d.has_value(), fits) << ranks << " ranks, " << columns << " x " << rows << " tiles";
      if (!d) continue;
      ASSERT_EQ(d->ranks(), ranks);
      std::vector<int> owners(static_cast<size_t>(c.width) * c.height, 0);
      for (int r = 0; r < ranks; ++r) {
        const CellRect o = d->owned(r), l = d->local(r);
        EXPECT_TRUE(l.x0 <= o.x0 && l.y0 <= o.y0 && l.x1 >= o.x1 && l.y1 >= o.y1) << "rank " << r << "'s local grid holds its own cells";
        EXPECT_GE(o.width(), halo);
        EXPECT_GE(o.height(), halo);
        EXPECT_EQ(o.x0 % c.step, 0) << "a cut between tile starts";
        EXPECT_EQ(o.y0 % c.step, 0);
        for (int y = o.y0; y < o.y1; ++y)
          for (int x = o.x0; x < o.x1; ++x) ++owners[static_cast<size_t>(y) * c.width + x];
      }
      for (int n : owners) ASSERT_EQ(n, 1) << ranks << " ranks on " << c.width << " x " << c.height;
      // Every tile's pixels within the image lie in the local grid of the rank owning its first pixel.
      for (int ty = 0; ty < rows; ++ty)
        for (int tx = 0; tx < columns; ++tx) {
          int owner = -1;
          for (int r = 0; r < ranks; ++r) owner = d->owned(r).contains(tx * c.step, ty * c.step) ? r : owner;
          ASSERT_GE(owner, 0);
          const CellRect shown = CellRect{tx * c.step, ty * c.step, tx * c.step + c.size, ty * c.step + c.size}.intersect({0, 0, c.width, c.height});
          EXPECT_EQ(shown.intersect(d->local(owner)), shown) << "tile " << tx << ", " << ty << " on " << ranks << " ranks";
        }
    }
  }
  // More ranks than tiles a side allows, or a band thinner than the halo: none.
  EXPECT_FALSE(Decomposition::chooseOnTiles(4, 127, 127, halo, 126, 1, 1));
  EXPECT_FALSE(Decomposition::chooseOnTiles(2, 130, 130, halo, 126, 2, 2)) << "the second band 4 cells wide";
  EXPECT_TRUE(Decomposition::chooseOnTiles(2, 140, 130, halo, 126, 2, 2)) << "the second band 14 cells wide";
}

TEST(HaloPlan, EveryHaloCellComesFromItsOwnerOnceAndEachSendIsItsPeersReceive) {
  for (int ranks = 2; ranks <= 6; ++ranks) {
    const Decomposition d = Decomposition::choose(ranks, 83, 71, 6);
    std::vector<HaloPlan> plans;
    for (int r = 0; r < ranks; ++r) plans.push_back(haloPlan(d, r));
    for (int r = 0; r < ranks; ++r) {
      const CellRect l = d.local(r), o = d.owned(r);
      std::vector<int> got(l.cells(), 0);
      for (const HaloTransfer& t : plans[r].receives) {
        EXPECT_EQ(t.cells.intersect(d.owned(t.peer)), t.cells);
        for (int y = t.cells.y0; y < t.cells.y1; ++y)
          for (int x = t.cells.x0; x < t.cells.x1; ++x) ++got[l.offsetOf(x, y)];
        bool matched = false;
        for (const HaloTransfer& s : plans[t.peer].sends) matched |= s.peer == r && s.cells == t.cells;
        EXPECT_TRUE(matched) << "rank " << t.peer << " sends rank " << r << " no such block";
      }
      for (int y = l.y0; y < l.y1; ++y)
        for (int x = l.x0; x < l.x1; ++x)
          EXPECT_EQ(got[l.offsetOf(x, y)], o.contains(x, y) ? 0 : 1) << x << ", " << y;
    }
  }
}

// ---------------------------------------------------------------- on the launched ranks

// A state on `w` x `h` cells of 10 m: the default range's relief made rough, snow in every layer,
// varied static fields, winds of every direction and a NODATA disc across the subdomains' borders.
SnowState testState(int w, int h) {
  DefaultTerrainOptions o;
  o.size = std::max(w, h);
  o.cellSizeM = 10.0;
  const Grid<float> relief = generateDefaultTerrain(o);
  SnowState s;
  GridSpec spec;
  spec.width = w, spec.height = h, spec.cellSizeXM = 10.0, spec.cellSizeYM = 10.0;
  s.allocate(spec);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      s.bedrockM.values()[i] = relief(x, y) + 6.f * unit(x, y, 11);  // rough: slopes above rest everywhere
      s.compactedM.values()[i] = 0.5f * unit(x, y, 1);
      s.stableM.values()[i] = 0.3f * unit(x, y, 2);
      s.unstableM.values()[i] = 0.4f * unit(x, y, 3);
      s.powderM.values()[i] = 0.6f * unit(x, y, 4);
      s.exposureHours.values()[i] = 2.f + 6.f * unit(x, y, 5);
      s.temperatureBaseC.values()[i] = -8.f + 6.f * unit(x, y, 6) - 0.004f * (relief(x, y) - 2000.f);
      // Gusts of every direction, so errors could travel upwind from any edge.
      s.windXMps.values()[i] = 8.f * std::sin(0.11f * y + 0.05f * x) + 2.f * (unit(x, y, 12) - 0.5f);
      s.windYMps.values()[i] = 8.f * std::cos(0.09f * x - 0.04f * y) + 2.f * (unit(x, y, 13) - 0.5f);
      s.windEffectZM.values()[i] = s.bedrockM.values()[i] + 2.f * unit(x, y, 7) - 0.5f;
      s.windLoadingMps2.values()[i] = 0.02f * unit(x, y, 8);
      const float dx = x - 0.5f * w, dy = y - 0.45f * h;
      s.validCell.values()[i] = dx * dx + dy * dy < 0.01f * w * h ? 0 : 1;
    }
  return s;
}

template <class T>
bool sameBytes(const Grid<T>& a, const Grid<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

TEST(Ranks, HaloExchangeFillsEveryHaloCellWithItsOwnersValue) {
  const Communicator comm = Communicator::world();
  const Decomposition d = Decomposition::choose(comm.size(), 97, 61, 6);
  const HaloPlan plan = haloPlan(d, comm.rank());
  const CellRect l = d.local(comm.rank()), o = d.owned(comm.rank());
  std::vector<float> f(l.cells());
  std::vector<double> g(l.cells());
  for (int y = l.y0; y < l.y1; ++y)
    for (int x = l.x0; x < l.x1; ++x) {
      const size_t i = l.offsetOf(x, y);
      f[i] = o.contains(x, y) ? unit(x, y, 9) : NAN;  // the halo starts wrong
      g[i] = o.contains(x, y) ? 1.0 + unit(x, y, 10) : -1.0;
    }
  const size_t sent = exchangeHalo(comm, d, plan, f.data(), sizeof(float)) + exchangeHalo(comm, d, plan, g.data(), sizeof(double));
  if (comm.size() > 1) {
    EXPECT_GT(sent, 0u);
  }
  for (int y = l.y0; y < l.y1; ++y)
    for (int x = l.x0; x < l.x1; ++x) {
      const size_t i = l.offsetOf(x, y);
      EXPECT_EQ(std::bit_cast<uint32_t>(f[i]), std::bit_cast<uint32_t>(unit(x, y, 9))) << x << ", " << y;
      EXPECT_EQ(g[i], 1.0 + unit(x, y, 10)) << x << ", " << y;
    }
}

// Each rank's rectangle, reaching across other ranks' subdomains (one empty, one the whole grid),
// holds every cell's owner's value; the halo cells are not read (they start as NaN), so a cell
// taken from a rank that does not own it fails. Floats and bytes.
TEST(Ranks, WindowGatherGivesEveryRankItsRectangleFromTheCellsOwners) {
  const Communicator comm = Communicator::world();
  const Decomposition d = Decomposition::choose(comm.size(), 97, 61, 6);
  const CellRect l = d.local(comm.rank()), o = d.owned(comm.rank());
  std::vector<float> f(l.cells());
  std::vector<uint8_t> b(l.cells());
  for (int y = l.y0; y < l.y1; ++y)
    for (int x = l.x0; x < l.x1; ++x) {
      f[l.offsetOf(x, y)] = o.contains(x, y) ? unit(x, y, 11) : NAN;
      b[l.offsetOf(x, y)] = o.contains(x, y) ? static_cast<uint8_t>(mix(x * 31 + y) & 0xfe) : 0xff;
    }
  const int r = comm.rank();
  const CellRect wants[4] = {CellRect{3, 50, 90, 58}, CellRect{0, 0, 97, 61}, CellRect{}, CellRect{40, 1, 41, 60}};
  const CellRect want = wants[r % 4];
  std::vector<float> heldF(want.cells(), -1.f);
  std::vector<uint8_t> heldB(want.cells(), 0xff);
  const size_t sent = gatherWindow(comm, d, f.data(), sizeof(float), want, heldF.data());
  gatherWindow(comm, d, b.data(), sizeof(uint8_t), want, heldB.data());
  if (comm.size() > 1 && r != 1) {
    EXPECT_GT(sent, 0u);  // rank 1 wants the whole grid: every other rank sends it its cells
  }
  for (int y = want.y0; y < want.y1; ++y)
    for (int x = want.x0; x < want.x1; ++x) {
      const size_t i = static_cast<size_t>(y - want.y0) * want.width() + (x - want.x0);
      EXPECT_EQ(std::bit_cast<uint32_t>(heldF[i]), std::bit_cast<uint32_t>(unit(x, y, 11))) << x << ", " << y;
      EXPECT_EQ(heldB[i], static_cast<uint8_t>(mix(x * 31 + y) & 0xfe)) << x << ", " << y;
    }
}

// Each wind state solved on the ranks' local grids is the whole grid's solve cut to them, bit for
// bit: the four fields, the loading (its halo from the owners), and the single process's
// iterations, last change and residual. Winds along the axes, the diagonals and between, over a
// rough relief with a NODATA disc across the subdomains' borders.
TEST(Ranks, WindSolvedOnLocalGridsIsTheWholeGridsSolveBitForBit) {
  const Communicator comm = Communicator::world();
  const SnowState s = testState(97, 61);
  const Decomposition d = Decomposition::choose(comm.size(), 97, 61, 6);
  const CellRect l = d.local(comm.rank());
  const ModelParameters p;
  for (const WindState w : {WindState{270.0, 10.0}, WindState{0.0, 6.0}, WindState{90.0, 12.0}, WindState{180.0, 8.0},
                            WindState{225.0, 15.0}, WindState{33.0, 9.0}, WindState{300.0, 12.0}}) {
    const WindField whole = computeWindField(s.bedrockM, s.validCell, s.spec, w, p);
    const Grid<float> wholeLoading = windLoading(whole, s.validCell, s.spec);
    WindField mine;
    Grid<float> loading;
    ASSERT_TRUE(solveWindOnLocalGrid(comm, d, s.bedrockM, s.validCell, s.spec, w, p, WindSolverOptions{}, mine, loading)) << w.directionDeg;
    EXPECT_TRUE(sameBytes(gridWindow(whole.windXMps, l), mine.windXMps)) << w.directionDeg;
    EXPECT_TRUE(sameBytes(gridWindow(whole.windYMps, l), mine.windYMps)) << w.directionDeg;
    EXPECT_TRUE(sameBytes(gridWindow(whole.windEffectZM, l), mine.windEffectZM)) << w.directionDeg;
    EXPECT_TRUE(sameBytes(gridWindow(whole.verticalSpeedMps, l), mine.verticalSpeedMps)) << w.directionDeg;
    EXPECT_TRUE(sameBytes(gridWindow(wholeLoading, l), loading)) << w.directionDeg;
    EXPECT_EQ(whole.stats.iterations, mine.stats.iterations) << w.directionDeg;
    EXPECT_EQ(whole.stats.lastUpdate, mine.stats.lastUpdate) << w.directionDeg;
    EXPECT_EQ(whole.stats.residual, mine.stats.residual) << w.directionDeg;
    EXPECT_EQ(whole.stats.converged, mine.stats.converged) << w.directionDeg;
  }
}

// A free stream that turns (1 + k_venturi A changes sign across the relief) may make loops: every
// rank declines alike, and the whole grid's solve is the reference.
TEST(Ranks, WindOnLocalGridsIsDeclinedOnEveryRankWhereTheFreeStreamTurns) {
  const Communicator comm = Communicator::world();
  const SnowState s = testState(97, 61);
  const Decomposition d = Decomposition::choose(comm.size(), 97, 61, 6);
  ModelParameters p;
  float lo = 1e30f, hi = -1e30f;
  for (size_t i = 0; i < s.bedrockM.size(); ++i)
    if (s.validCell.values()[i]) lo = std::min(lo, s.bedrockM.values()[i]), hi = std::max(hi, s.bedrockM.values()[i]);
  p.venturiPerM = -2.0 / (lo + hi);  // negative above the middle altitude
  WindField mine;
  Grid<float> loading;
  EXPECT_FALSE(solveWindOnLocalGrid(comm, d, s.bedrockM, s.validCell, s.spec, WindState{250.0, 10.0}, p, WindSolverOptions{}, mine, loading));
  // The red-black ordering stops short of the fixed point: declined too.
  WindSolverOptions redBlack;
  redBlack.ordering = WindOrdering::RedBlack;
  EXPECT_FALSE(solveWindOnLocalGrid(comm, d, s.bedrockM, s.validCell, s.spec, WindState{250.0, 10.0}, ModelParameters{}, redBlack, mine, loading));
}

TEST(Ranks, ExactSumsAreTheSingleProcessBackendsTotalsBitForBit) {
  const Communicator comm = Communicator::world();
  const SnowState whole = testState(131, 77);
  auto reference = createCpuBackend();
  reference->upload(whole);
  const LayerTotals t = reference->totals();
  const Decomposition d = Decomposition::choose(comm.size(), 131, 77, 3);
  const SnowState local = cutLocalState(whole, d.local(comm.rank()));
  const double area = whole.spec.cellAreaM2();
  const uint8_t* valid = local.validCell.data();
  EXPECT_EQ(std::bit_cast<uint64_t>(exactSum(comm, d, local.compactedM.data(), valid) * area), std::bit_cast<uint64_t>(t.compactedM3));
  EXPECT_EQ(std::bit_cast<uint64_t>(exactSum(comm, d, local.stableM.data(), valid) * area), std::bit_cast<uint64_t>(t.stableM3));
  EXPECT_EQ(std::bit_cast<uint64_t>(exactSum(comm, d, local.unstableM.data(), valid) * area), std::bit_cast<uint64_t>(t.unstableM3));
  EXPECT_EQ(std::bit_cast<uint64_t>(exactSum(comm, d, local.powderM.data(), valid) * area), std::bit_cast<uint64_t>(t.powderM3));
  EXPECT_EQ(exactMax(comm, d, local.temperatureBaseC.data(), valid), reference->maxTemperatureBaseC());
}

template <class T>
uint64_t bitsOf(T v) {
  if constexpr (sizeof(T) == 8) return std::bit_cast<uint64_t>(v);
  else return std::bit_cast<uint32_t>(v);
}

void expectSameTotals(const LayerTotals& a, const LayerTotals& b) {
  EXPECT_EQ(bitsOf(a.compactedM3), bitsOf(b.compactedM3));
  EXPECT_EQ(bitsOf(a.stableM3), bitsOf(b.stableM3));
  EXPECT_EQ(bitsOf(a.unstableM3), bitsOf(b.unstableM3));
  EXPECT_EQ(bitsOf(a.powderM3), bitsOf(b.powderM3));
}

// Rank 0 compares the ranks' owned cells of every evolved and record field with `expected`.
void expectGatheredFieldsAre(const Communicator& comm, const Decomposition& d, const SnowState& local, const SnowState& expected,
                             const SnowState& initial) {
  SnowState gathered = initial;
  gatherOwned(comm, d, local, gathered);
  if (comm.rank() != 0) return;
  int compared = 0;
#define SNOW_COMPARE_FIELD(member, view, Element, role, access, fill)                                         \
  if ((FieldRole::role == FieldRole::Evolved || FieldRole::role == FieldRole::Record) && local.member.size() > 0) { \
    EXPECT_TRUE(sameBytes(expected.member, gathered.member)) << #member << " on " << comm.size() << " ranks"; \
    ++compared;                                                                                               \
  }
  SNOW_STATE_FIELDS(SNOW_COMPARE_FIELD)
#undef SNOW_COMPARE_FIELD
  EXPECT_GE(compared, 5);
  EXPECT_FALSE(sameBytes(expected.powderM, initial.powderM));  // the phenomena changed the snow
}

// Snowfall, stability, melt, powder diffusion and wind transport, six steps of `dt`, on the whole
// grid and through a DistributedBackend on each rank's local grid: each step's snowfall and melt
// volumes, the totals and warmest cell, and the owned cells of every evolved and record field are
// the single process's bytes.
void expectContinuousStepsGiveTheSingleProcessBytes(double dt) {
  const Communicator comm = Communicator::world();
  const int w = 150, h = 104;
  const SnowState whole = testState(w, h);
  ModelParameters p;
  const Decomposition d = Decomposition::choose(comm.size(), w, h, kContinuousHalo);
  SnowState local = cutLocalState(whole, d.local(comm.rank()));
  auto reference = createCpuBackend();
  DistributedBackend mine(createCpuBackend(), comm, d);
  reference->upload(whole);
  mine.upload(local);
  for (int step = 0; step < 6; ++step) {
    WeatherState weather;
    weather.seaLevelTemperatureC = step < 3 ? -2.0 : 9.0;  // a storm, then a thaw
    const StepVolumes expected = continuousStep(*reference, p, dt, weather);
    const StepVolumes got = continuousStep(mine, p, dt, weather);
    EXPECT_EQ(bitsOf(got.snowfallM3), bitsOf(expected.snowfallM3)) << "step " << step;
    EXPECT_EQ(bitsOf(got.meltM3), bitsOf(expected.meltM3)) << "step " << step;
  }
  if (comm.size() > 1) {
    EXPECT_GT(mine.bytesSent(), 0u);
  }
  expectSameTotals(mine.totals(), reference->totals());
  EXPECT_EQ(mine.maxTemperatureBaseC(), reference->maxTemperatureBaseC());
  SnowState expected = whole;
  reference->download(expected);
  mine.download(local);
  expectGatheredFieldsAre(comm, d, local, expected, whole);
}

// Quarter days: five powder substeps.
TEST(Ranks, ContinuousPhenomenaOnLocalGridsGiveTheSingleProcessBytes) { expectContinuousStepsGiveTheSingleProcessBytes(0.25); }
// Two days: forty powder substeps, each refreshing the powder's halo (without, they would reach 80 cells).
TEST(Ranks, ContinuousPhenomenaInTwoDayStepsGiveTheSingleProcessBytes) { expectContinuousStepsGiveTheSingleProcessBytes(2.0); }
// An hour: one powder substep.
TEST(Ranks, ContinuousPhenomenaInHourStepsGiveTheSingleProcessBytes) { expectContinuousStepsGiveTheSingleProcessBytes(1.0 / 24.0); }

// A season without avalanches, skiers, bedforms or edits.
SeasonConfig continuousSeason() {
  SeasonConfig c;
  c.days = 24.0;
  c.seed = 7;
  c.params.avalancheRatePerKm2PerDay = 0.0;
  c.params.skiersPerHour = 0.0;
  c.windTransport = true;
  c.weather.keyframes = {{0.0, {-6.0, 270.0, 8.0, 1.0}}, {12.0, {4.0, 270.0, 8.0, 1.0}}, {24.0, {-3.0, 270.0, 8.0, 1.0}}};
  return c;
}

TEST(DistributedSeason, RefusesWhatIsNotAcrossRanksYetNamingIt) {
  SeasonConfig c = continuousSeason();
  EXPECT_EQ(distributedSeasonRefusal(c), "");
  c.params.avalancheRatePerKm2PerDay = 0.1;
  EXPECT_EQ(distributedSeasonRefusal(c), "avalanches");
  c = continuousSeason();
  c.userSkiers.push_back({});
  EXPECT_EQ(distributedSeasonRefusal(c), "skiers");
  c = continuousSeason();
  c.edits.push_back({});
  EXPECT_EQ(distributedSeasonRefusal(c), "");  // edits run across ranks
  EXPECT_NE(distributedSeasonRefusal(SeasonConfig{}), "");  // the defaults have avalanches and skiers
  c = continuousSeason();
  SkiTracks tracks(testState(20, 20).spec, 2);
  c.skiTracks = &tracks;
  EXPECT_EQ(distributedSeasonRefusal(c), "the ski-track texture");
  // With the whole grid's replica, avalanches, skiers, bedforms and the texture run; their
  // runners need the whole grid's terrain.
  c = continuousSeason();
  EXPECT_FALSE(seasonNeedsReplica(c));
  c.params.avalancheRatePerKm2PerDay = 0.1;
  c.userSkiers.push_back({});
  c.bedforms = BedformParameters{};
  c.skiTracks = &tracks;
  EXPECT_TRUE(seasonNeedsReplica(c));
  EXPECT_NE(distributedSeasonRefusal(c, true).find("eventTerrain"), std::string::npos);
  const SnowState terrain = testState(20, 20);
  c.eventTerrain = &terrain;
  EXPECT_EQ(distributedSeasonRefusal(c, true), "");
  c = continuousSeason();
  c.eventTerrain = &terrain;
  EXPECT_NE(distributedSeasonRefusal(c).find("no replica"), std::string::npos);
}

TEST(DistributedSeason, RefusesAStateThatIsNotTheRanksLocalGrid) {
  const Communicator comm = Communicator::world();
  const Decomposition d = Decomposition::choose(comm.size(), 60, 40, kContinuousHalo);
  DistributedBackend b(createCpuBackend(), comm, d);
  EXPECT_THROW(b.upload(testState(61, 40)), std::invalid_argument);
  EXPECT_THROW(DistributedBackend(createCpuBackend(), comm, Decomposition::choose(comm.size(), 60, 40, kContinuousHalo - 1)), std::invalid_argument);
}

// A season on the whole grid (one process's CPU backend) and on this rank's local grid through a
// DistributedBackend (with `localConfig`, when given, in place of `config`).
struct BothSeasons {
  Decomposition d;
  SnowState whole, local;
  SeasonReport expected, got;
};
BothSeasons runBothSeasons(const Communicator& comm, const SnowState& initial, const SeasonConfig& config,
                           const SeasonConfig* localConfig = nullptr) {
  BothSeasons b;
  b.d = Decomposition::choose(comm.size(), initial.spec.width, initial.spec.height, kContinuousHalo);
  b.whole = initial;
  b.local = cutLocalState(initial, b.d.local(comm.rank()));
  auto reference = createCpuBackend();
  DistributedBackend mine(createCpuBackend(), comm, b.d);
  b.expected = runSeason(*reference, b.whole, config);
  b.got = runSeason(mine, b.local, localConfig ? *localConfig : config);
  return b;
}

// The season itself (its Poisson scheduler, elapsed-time steps and mass ledger) on each rank's
// local state through a DistributedBackend: the report's ledger and totals and every evolved and
// record field are the single process's bytes.
TEST(Ranks, SeasonOfSnowfallMeltAndTransportGivesTheSingleProcessBytesAndLedger) {
  const Communicator comm = Communicator::world();
  const int w = 150, h = 104;
  const SnowState initial = testState(w, h);
  const SeasonConfig config = continuousSeason();
  ASSERT_EQ(distributedSeasonRefusal(config), "");
  const auto [d, whole, local, expected, got] = runBothSeasons(comm, initial, config);
  expectSameTotals(got.initial, expected.initial);
  expectSameTotals(got.final, expected.final);
  EXPECT_EQ(bitsOf(got.snowfallAddedM3), bitsOf(expected.snowfallAddedM3));
  EXPECT_EQ(bitsOf(got.meltRemovedM3), bitsOf(expected.meltRemovedM3));
  EXPECT_GT(expected.snowfallAddedM3, 0.0);
  EXPECT_GT(expected.meltRemovedM3, 0.0);
  EXPECT_EQ(got.events, expected.events);
  ASSERT_EQ(got.phenomena.size(), expected.phenomena.size());
  for (size_t i = 0; i < got.phenomena.size(); ++i) {
    EXPECT_EQ(got.phenomena[i].steps, expected.phenomena[i].steps) << got.phenomena[i].name;
    EXPECT_EQ(got.phenomena[i].skippedSteps, expected.phenomena[i].skippedSteps) << got.phenomena[i].name;
  }
  expectGatheredFieldsAre(comm, d, local, whole, initial);
}

// A season whose static fields change each day (as the bake's sun and wind timeline do), filled on
// the whole grid and cut to each rank's (cutFields, as bake/across_ranks.cpp does): the single
// process's ledger and fields; and the final state gathered into wholeLike's state on rank 0.
TEST(Ranks, DailyStaticFieldsCutFromTheWholeGridGiveTheSingleProcessBytes) {
  const Communicator comm = Communicator::world();
  const int w = 150, h = 104;
  const SnowState initial = testState(w, h);
  SeasonConfig config = continuousSeason();
  // Each day warmer and windier by a different amount a cell.
  config.updateStaticFields = [](int day, SnowState& s) {
    s.temperatureBaseC.resize(s.spec.width, s.spec.height);  // the season frees the host's static fields
    s.windXMps.resize(s.spec.width, s.spec.height);
    for (size_t i = 0; i < s.bedrockM.size(); ++i) {
      const float k = static_cast<float>((i * 7 + static_cast<size_t>(day) * 13) % 17) / 17.f;
      s.temperatureBaseC.values()[i] = -10.f + 0.9f * day * k;
      s.windXMps.values()[i] = 3.f + day * k;
    }
  };
  const CellRect cells = Decomposition::choose(comm.size(), w, h, kContinuousHalo).local(comm.rank());
  SeasonConfig localConfig = config;
  localConfig.updateStaticFields = [&](int day, SnowState& s) {
    SnowState filled;  // the terrain alone, as bake/across_ranks.cpp lends it
    filled.spec = initial.spec;
    filled.bedrockM = initial.bedrockM;
    config.updateStaticFields(day, filled);
    cutFields(filled, cells, [](FieldRole r) { return r == FieldRole::Static; }, s);
  };
  ASSERT_EQ(distributedSeasonRefusal(localConfig), "");
  const auto [d, whole, local, expected, got] = runBothSeasons(comm, initial, config, &localConfig);
  expectSameTotals(got.final, expected.final);
  EXPECT_EQ(bitsOf(got.snowfallAddedM3), bitsOf(expected.snowfallAddedM3));
  EXPECT_EQ(bitsOf(got.meltRemovedM3), bitsOf(expected.meltRemovedM3));
  expectGatheredFieldsAre(comm, d, local, whole, initial);
  // wholeLike: the local state's fields, whole-grid sized, and no others.
  SnowState gathered = comm.rank() == 0 ? wholeLike(local, initial.spec) : SnowState();
  gatherOwned(comm, d, local, gathered);
  if (comm.rank() != 0) return;
  EXPECT_EQ(gathered.spec.width, w);
  EXPECT_TRUE(sameBytes(gathered.powderM, whole.powderM));
  EXPECT_TRUE(sameBytes(gathered.temperatureBaseC, whole.temperatureBaseC));  // the last day's, cut and gathered
  EXPECT_EQ(gathered.windYMps.size(), whole.windYMps.size());  // released by the season in both, or kept in both
  EXPECT_EQ(gathered.noSnow.size(), 0u);
}

// Timeline edits of every kind, painted (weights of the whole grid, cut to each rank's) and not:
// the single process's fields, and each edit's volume in the report bit for bit.
TEST(Ranks, TimelineEditsGiveTheSingleProcessBytesAndVolumes) {
  const Communicator comm = Communicator::world();
  const int w = 150, h = 104;
  const SnowState initial = testState(w, h);
  SeasonConfig config = continuousSeason();
  auto painted = std::make_shared<std::vector<float>>(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) (*painted)[static_cast<size_t>(y) * w + x] = 1.4f * unit(x, y, 21) - 0.2f;  // clamped to [0, 1]
  auto edit = [&](double day, EditOp op, SnowLayer layer, float depth, bool masked, SnowLayer to = SnowLayer::Compacted) {
    SeasonEdit e;
    e.day = day;
    e.args.op = op, e.args.layer = static_cast<int>(layer), e.args.toLayer = static_cast<int>(to), e.args.depthM = depth;
    if (masked) e.weights = painted;
    e.label = "edit " + std::to_string(config.edits.size());
    config.edits.push_back(e);
  };
  edit(2.0, EditOp::Add, SnowLayer::Compacted, 0.4f, true);
  edit(5.0, EditOp::Remove, SnowLayer::Powder, 0.3f, false);
  edit(9.0, EditOp::Set, SnowLayer::Unstable, 1.2f, true);
  edit(14.0, EditOp::Move, SnowLayer::Unstable, 0.5f, true, SnowLayer::Stable);
  ASSERT_EQ(distributedSeasonRefusal(config), "");
  const auto [d, whole, local, expected, got] = runBothSeasons(comm, initial, config);
  ASSERT_EQ(got.edits.size(), 4u);
  ASSERT_EQ(expected.edits.size(), 4u);
  for (size_t k = 0; k < got.edits.size(); ++k) EXPECT_EQ(bitsOf(got.edits[k].volumeM3), bitsOf(expected.edits[k].volumeM3)) << k;
  EXPECT_NE(expected.edits[0].volumeM3, 0.0);
  EXPECT_EQ(bitsOf(got.editsNetM3), bitsOf(expected.editsNetM3));
  expectSameTotals(got.final, expected.final);
  expectGatheredFieldsAre(comm, d, local, whole, initial);
}

// Avalanches (spontaneous and a user's), skiers (automatic and a user's group, drawing the
// ski-track texture) and wind bedforms on the whole grid's replica every rank holds
// (DistributedBackend::replicateEvents), the continuous phenomena decomposed: the single
// process's report, fields and texture, bit for bit.
TEST(Ranks, AvalanchesSkiersAndBedformsOnTheWholeGridsReplicaGiveTheSingleProcessBytes) {
  const Communicator comm = Communicator::world();
  const int w = 150, h = 104;
  const SnowState initial = testState(w, h);
  SeasonConfig config = continuousSeason();
  config.params.avalancheRatePerKm2PerDay = 3.0;
  config.params.skiersPerHour = 3.0;
  config.userAvalanches.push_back({6.5, 40, 30, false, nullptr});
  config.userSkiers.push_back({9.25, 100, 20, 3, nullptr});
  BedformParameters bed;
  bed.hopLengthM = 20.0;
  bed.maxSlopeDeg = 40.0;
  bed.roundsPerHour = 1.0;
  config.bedforms = bed;
  SkiTracks tracksAlone(initial.spec, 2), tracksRanks(initial.spec, 2);
  config.skiTracks = &tracksAlone;
  ASSERT_TRUE(seasonNeedsReplica(config));
  SnowState whole = initial;
  auto reference = createCpuBackend();
  const SeasonReport expected = runSeason(*reference, whole, config);

  const Decomposition d = Decomposition::choose(comm.size(), w, h, kContinuousHalo);
  SnowState terrain = initial;  // the replica's whole state: terrain and static fields for the runners
  SnowState local = cutLocalState(initial, d.local(comm.rank()));
  SeasonConfig localConfig = config;
  localConfig.skiTracks = &tracksRanks;
  localConfig.eventTerrain = &terrain;
  ASSERT_EQ(distributedSeasonRefusal(localConfig, true), "");
  DistributedBackend mine(createCpuBackend(), comm, d);
  mine.replicateEvents(createCpuBackend(), terrain);
  const SeasonReport got = runSeason(mine, local, localConfig);

  ASSERT_GE(expected.avalanches.size(), 2u);
  ASSERT_EQ(got.avalanches.size(), expected.avalanches.size());
  for (size_t k = 0; k < got.avalanches.size(); ++k) {
    EXPECT_EQ(bitsOf(got.avalanches[k].releasedM3), bitsOf(expected.avalanches[k].releasedM3)) << "avalanche " << k;
    EXPECT_EQ(got.avalanches[k].footprintCells, expected.avalanches[k].footprintCells) << "avalanche " << k;
  }
  ASSERT_GT(expected.skiers.size(), 3u);
  ASSERT_EQ(got.skiers.size(), expected.skiers.size());
  for (size_t k = 0; k < got.skiers.size(); ++k) EXPECT_EQ(got.skiers[k].path, expected.skiers[k].path) << "skier " << k;
  EXPECT_GT(expected.bedforms.slabsEroded, 0);
  EXPECT_EQ(got.bedforms.slabsEroded, expected.bedforms.slabsEroded);
  EXPECT_EQ(got.bedforms.rounds, expected.bedforms.rounds);
  EXPECT_EQ(got.events, expected.events);
  EXPECT_EQ(bitsOf(got.snowfallAddedM3), bitsOf(expected.snowfallAddedM3));
  expectSameTotals(got.final, expected.final);
  SnowState gathered = initial;  // and the bedform cohesion, cut from the replica into the local grid's download
  gathered.bedformCohesion.resize(w, h, 0.f);
  expectGatheredFieldsAre(comm, d, local, whole, gathered);
  EXPECT_TRUE(sameBytes(tracksRanks.depth(), tracksAlone.depth()));
  EXPECT_GT(*std::max_element(tracksAlone.depth().values().begin(), tracksAlone.depth().values().end()), 0.f);
  SnowState cohesion = gathered;
  gatherOwned(comm, d, local, cohesion);
  if (comm.rank() == 0) {
    EXPECT_TRUE(sameBytes(cohesion.bedformCohesion, whole.bedformCohesion));
  }
  if (comm.size() > 1) {
    EXPECT_GT(mine.replicaGathers(), 0u);
  }
  // A second upload would leave the replica's avalanche, skier and bedform state behind.
  EXPECT_THROW(mine.upload(local), std::logic_error);
}

}  // namespace
}  // namespace snow::dist

int main(int argc, char** argv) {
  snow::dist::MpiSession mpi;
  ::testing::InitGoogleTest(&argc, argv);
  // One rank's report: the others print only their failures.
  if (snow::dist::Communicator::world().rank() != 0) GTEST_FLAG_SET(brief, true);
  return RUN_ALL_TESTS();
}
