// The cost of the distributed decomposition (docs/distributed.md): the season's continuous
// phenomena (continuous_step.h) on the default range at size x size cells of 10 m, half-day steps,
// on as many ranks as the launcher started. Prints one table row: the process grid, the halo,
// each rank's share of the grid, and per step (slowest rank each) the time in the kernels and the
// exact sums (whose hand-offs along the process row wait too), waiting for the slowest rank
// before each refresh (a barrier, for this measure only) and in the halo exchange; the bytes all
// ranks send per step, the fields' memory and peak resident memory per rank.
// tools/bench-distributed.sh runs it on 1, 2 and 4 ranks.
//   distributed_bench [size=2048] [steps=4] [--header]
//   distributed_bench SIZE --plan RANKS   the exchange volume of RANKS ranks from the halo plan
//                                         alone (nothing allocated: for grids beyond this machine)
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "core/cpu_backend.h"
#include "core/default_terrain.h"
#include "core/phenomena/powder_diffusion.h"
#include "distributed/continuous_step.h"
#include "distributed/distributed_backend.h"

using namespace snow;
using namespace snow::dist;

namespace {

// The default range with a metre of mixed snow and a westerly (what a storm's season step reads),
// made on `cells` of it alone: only the relief is generated whole (4 bytes a cell, freed here).
SnowState localState(int size, const CellRect& cells) {
  DefaultTerrainOptions o;
  o.size = size;
  o.cellSizeM = 10.0;
  GridSpec whole;
  const Grid<float> relief = generateDefaultTerrain(o, &whole);
  GridSpec spec = whole;
  spec.width = cells.width(), spec.height = cells.height();
  SnowState s;
  s.allocate(spec);
  for (int y = 0; y < spec.height; ++y)
    for (int x = 0; x < spec.width; ++x) {
      const size_t i = static_cast<size_t>(y) * spec.width + x;
      const float b = relief(cells.x0 + x, cells.y0 + y);
      s.bedrockM.values()[i] = b;
      s.compactedM.values()[i] = 0.4f, s.stableM.values()[i] = 0.2f, s.unstableM.values()[i] = 0.1f, s.powderM.values()[i] = 0.3f;
      s.exposureHours.values()[i] = 5.f;
      s.temperatureBaseC.values()[i] = -0.0065f * (b - 1500.f);
      s.windXMps.values()[i] = 8.f, s.windYMps.values()[i] = 2.f;
      s.windEffectZM.values()[i] = b;
    }
  s.keepRecordFields(0);  // as the default preset's season: no output reads a record field
  return s;
}

double peakResidentMB() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;
}

// A step's refreshes: after snowfall, stability, melt and wind transport the snow layers (4
// floats) and the moving flag a cell, after each of powder diffusion's substeps the powder.
double exchangedBytesPerCell(double dt) {
  ModelParameters p;
  const int substeps = powderDiffusionSubsteps(static_cast<float>(dt), static_cast<float>(p.diffusionRatePerDay),
                                               static_cast<float>(p.diffusionLengthM), 10.f);
  return 4.0 * (4 * sizeof(float) + sizeof(uint8_t)) + substeps * sizeof(float);
}

int planRow(int size, int ranks) {
  const Decomposition d = Decomposition::choose(ranks, size, size, kContinuousHalo);
  double sent = 0, largest = 0;
  for (int r = 0; r < ranks; ++r) {
    for (const HaloTransfer& t : haloPlan(d, r).sends) sent += static_cast<double>(t.cells.cells());
    largest = std::max(largest, static_cast<double>(d.local(r).cells()));
  }
  std::printf("| %d (plan) | %d x %d | %d | %.0f cells (%.4f) | | | | %.1f | | | |\n", ranks, d.columns, d.rows, kContinuousHalo, largest,
              largest / (static_cast<double>(size) * size), sent * exchangedBytesPerCell(0.5) / 1e6);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  MpiSession mpi;
  const Communicator comm = Communicator::world();
  int size = 2048, steps = 4, planRanks = 0;
  bool header = false;
  std::vector<int> numbers;
  for (int a = 1; a < argc; ++a) {
    if (std::strcmp(argv[a], "--header") == 0) header = true;
    else if (std::strcmp(argv[a], "--plan") == 0 && a + 1 < argc) planRanks = std::atoi(argv[++a]);
    else numbers.push_back(std::atoi(argv[a]));
  }
  if (numbers.size() > 0) size = numbers[0];
  if (numbers.size() > 1) steps = numbers[1];
  if (planRanks > 0) return planRow(size, planRanks);
  // The cores shared among the ranks of this machine.
  const int threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) / comm.size());
  tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);

  ModelParameters p;
  const double dt = 0.5;
  const int halo = kContinuousHalo;
  const Decomposition d = Decomposition::choose(comm.size(), size, size, halo);
  DistributedBackend backend(createCpuBackend(), comm, d, true);
  size_t fieldBytes = 0;
  {
    SnowState local = localState(size, d.local(comm.rank()));
    fieldBytes = local.bytes([](FieldRole) { return true; });
    backend.uploadTaking(local);
  }
  const auto t0 = std::chrono::steady_clock::now();
  for (int s = 0; s < steps; ++s) {
    WeatherState w;
    w.seaLevelTemperatureC = s % 2 ? 2.0 : -4.0;
    continuousStep(backend, p, dt, w);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double kernels = wall - backend.waitSeconds() - backend.exchangeSeconds();
  const std::vector<double> all = comm.allGather({kernels / steps, backend.waitSeconds() / steps, backend.exchangeSeconds() / steps,
                                                  static_cast<double>(backend.bytesSent()) / steps, static_cast<double>(fieldBytes),
                                                  static_cast<double>(d.local(comm.rank()).cells()), peakResidentMB()});
  if (comm.rank() != 0) return 0;
  double compute = 0, fastest = 1e300, wait = 0, exchange = 0, sent = 0, fields = 0, cells = 0, rss = 0;
  for (int r = 0; r < comm.size(); ++r) {
    const double* v = &all[static_cast<size_t>(r) * 7];
    compute = std::max(compute, v[0]), fastest = std::min(fastest, v[0]);
    wait = std::max(wait, v[1]), exchange = std::max(exchange, v[2]), sent += v[3];
    fields = std::max(fields, v[4]), cells = std::max(cells, v[5]), rss = std::max(rss, v[6]);
  }
  if (header) {
    std::printf(
        "| ranks | process grid | halo (cells) | largest local grid (share of the whole) | kernels and sums s/step (fastest, slowest rank) "
        "| waiting s/step | exchange s/step | MB sent/step (all ranks) | fields MB/rank | peak RSS MB/rank | threads/rank |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  }
  std::printf("| %d | %d x %d | %d | %.0f cells (%.3f) | %.3f, %.3f | %.4f | %.4f | %.1f | %.0f | %.0f | %d |\n", comm.size(), d.columns,
              d.rows, halo, cells, cells / (static_cast<double>(size) * size), fastest, compute, wait, exchange, sent / 1e6, fields / 1e6,
              rss, threads);
  return 0;
}
