// `snowbake bench --stage skiers`: skiers moved together as agents (phenomena/skiers.h) on the builtin
// range at 1024² (10 m cells, a metre of snow): the time of a batch and per move for 1 to 4096
// skiers (CPU, and CUDA when a device works), and the exact reference: the serial executor's
// paths and bytes, which the parallel backends must equal.
#include <cstring>
#include <sstream>

#include "bench_suite.h"
#include "core/cpu_backend.h"
#include "core/reference_scenario.h"
#include "core/ski_runs.h"
#include "cuda/cuda_backend.h"

namespace snow {

namespace {

struct BatchResult {
  double seconds = 0;
  int moves = 0;       // the longest descent's moves (the batch's number of steps)
  long long cells = 0;  // cells entered, all skiers
  std::vector<SkierRecord> records;
  SnowState after;
};

BatchResult runBatch(SnowBackend& b, const SnowState& s, int skiers) {
  ModelParameters p;
  p.skiTriggerFactor = 0.0;
  b.upload(s);
  SkiRun run(b, p, s, nullptr);
  std::vector<SkierStart> starts;
  for (int k = 0; k < skiers; ++k) {
    int x = 0, y = 0;
    if (run.pickStart((k + 0.5) / skiers, x, y)) starts.push_back({x, y, static_cast<uint64_t>(k), false});
  }
  BatchResult r;
  const auto t0 = WallClock::now();
  r.records = run.descendTogether(starts, 1.0, 3);
  r.seconds = elapsedSeconds(t0);
  for (const SkierRecord& rec : r.records) {
    r.moves = std::max(r.moves, static_cast<int>(rec.path.size()) - 1);
    r.cells += rec.cells;
  }
  r.after = s;
  b.download(r.after);
  return r;
}

size_t differingCells(const SnowState& a, const SnowState& b) {
  size_t d = 0;
  for (const auto& [x, y] : {std::pair{&a.unstableM, &b.unstableM}, {&a.stableM, &b.stableM}, {&a.compactedM, &b.compactedM}})
    for (size_t i = 0; i < x->size(); ++i) d += std::memcmp(&x->values()[i], &y->values()[i], sizeof(float)) != 0;
  return d;
}

bool samePaths(const BatchResult& a, const BatchResult& b) {
  if (a.records.size() != b.records.size()) return false;
  for (size_t k = 0; k < a.records.size(); ++k)
    if (a.records[k].path != b.records[k].path || a.records[k].why != b.records[k].why) return false;
  return true;
}

}  // namespace

std::string skierBench(const BenchOptions& o, std::ostream& log, int threads) {
  (void)o;
  SnowState s = referenceRangeState(1024, 10240.0);
  s.stableM.fill(0.8f);
  s.unstableM.fill(0.2f);
  const cuda::DeviceInfo info = cuda::probeDevice();
  std::ostringstream table;
  table << "Skiers moved together (one move of every skier at a time; starts drawn by the route map): the builtin range at 1024² "
           "(10 m cells, 1 m of snow); "
        << benchMachineDescription() << ", " << threads << " threads\n\n"
        << "| skiers | backend | batch (s) | moves (longest descent) | ms per move | cells entered | µs per cell entered |\n"
           "|---|---|---|---|---|---|---|\n";
  auto row = [&](int n, const std::string& backend, const BatchResult& r) {
    table << "| " << n << " | " << backend << " | " << benchFormat("%.3f", r.seconds) << " | " << r.moves << " | "
          << benchFormat("%.3f", r.moves > 0 ? r.seconds * 1e3 / r.moves : 0.0) << " | " << r.cells << " | "
          << benchFormat("%.2f", r.cells > 0 ? r.seconds * 1e6 / static_cast<double>(r.cells) : 0.0) << " |\n";
  };
  for (int n : {1, 64, 1024, 4096}) {
    auto cpu = createCpuBackend();
    const BatchResult c = runBatch(*cpu, s, n);
    row(n, "cpu", c);
    log << "  skiers " << n << " cpu: " << benchFormat("%.3f", c.seconds) << " s, " << c.moves << " moves\n";
    if (info.available) {
      auto gpu = cuda::createCudaBackend();
      row(n, info.description, runBatch(*gpu, s, n));
    }
  }
  if (!info.available) table << "\nCUDA: skipped (" << info.reason << ").\n";

  // The reference: the serial executor's paths and layers.
  const int n = 1024;
  auto serial = createSerialBackend();
  auto cpu = createCpuBackend();
  const BatchResult rs = runBatch(*serial, s, n), rc = runBatch(*cpu, s, n);
  table << "\nAgainst the serial executor, " << n << " skiers (serial " << benchFormat("%.3f", rs.seconds) << " s, cpu "
        << benchFormat("%.3f", rc.seconds) << " s):\n\n| backend | paths and stops | cells whose C, S or U differ |\n|---|---|---|\n"
        << "| cpu (" << threads << " threads) | " << (samePaths(rs, rc) ? "identical" : "DIFFER") << " | " << differingCells(rs.after, rc.after)
        << " |\n";
  if (info.available) {
    auto gpu = cuda::createCudaBackend();
    const BatchResult rg = runBatch(*gpu, s, n);
    table << "| " << info.description << " | " << (samePaths(rs, rg) ? "identical" : "DIFFER") << " | " << differingCells(rs.after, rg.after)
          << " |\n";
  }
  return table.str();
}

}  // namespace snow
