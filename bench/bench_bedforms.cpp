// `snowbake bench --stage bedforms`: the wind-bedform model's time per polling round on windows
// of 256² to 1024² (CPU, and CUDA when a device works), and its checks against references that
// are exact: the slab ledger (every slab kept), the repose angle after avalanching, the serial
// executor's bytes (the parallel backends must equal them), and the barchan census of the documented
// parameter set against Filhol & Sturm's snow-barchan sizes.
#include <cmath>
#include <cstring>
#include <sstream>

#include "bench_suite.h"
#include "core/bedform_runs.h"
#include "core/cpu_backend.h"
#include "cuda/cuda_backend.h"

namespace snow {

namespace {

struct Timing {
  double secondsPerRound = 0;
  long long slabsLifted = 0;
  bool ledgerExact = true;
};

// Warm-up rounds (the forms start), then `rounds` timed rounds.
Timing timeRounds(SnowBackend& b, int n, int warmup, int rounds) {
  SnowState s = makeBarchanWindow(n);
  const BedformParameters p = periodicBedformParameters();
  b.upload(s);
  Timing t;
  BedformStepReport r = b.bedformStep(makeBedformArgs(p, 0.0, warmup, 0, 1, 0.0));
  t.ledgerExact = r.slabsBefore == r.slabsAfter;
  const auto t0 = WallClock::now();
  r = b.bedformStep(makeBedformArgs(p, 0.0, rounds, static_cast<uint64_t>(warmup), 1, 0.0));
  t.secondsPerRound = elapsedSeconds(t0) / rounds;
  t.slabsLifted = r.slabsEroded / rounds;
  t.ledgerExact = t.ledgerExact && r.slabsBefore == r.slabsAfter;
  return t;
}

}  // namespace

std::string bedformBench(const BenchOptions& o, std::ostream& log, int threads) {
  (void)o;
  std::ostringstream table;
  const cuda::DeviceInfo info = cuda::probeDevice();
  table << "Wind bedforms: time per polling round (every cell polled once: shadow, saltation and avalanching in 4 batches), "
           "the documented barchan set on periodic windows of 0.5 m cells, after 20 warm-up rounds; "
        << benchMachineDescription() << ", " << threads << " threads\n\n"
        << "| window | backend | ms per round | ns per cell and round | slabs lifted per round | slab ledger |\n|---|---|---|---|---|---|\n";
  for (int n : {256, 512, 1024}) {
    const int rounds = n >= 1024 ? 5 : 10;
    auto cpu = createCpuBackend();
    const Timing c = timeRounds(*cpu, n, 20, rounds);
    table << "| " << n << "² | cpu | " << benchFormat("%.1f", c.secondsPerRound * 1e3) << " | "
          << benchFormat("%.1f", c.secondsPerRound * 1e9 / (static_cast<double>(n) * n)) << " | " << c.slabsLifted << " | "
          << (c.ledgerExact ? "exact" : "BROKEN") << " |\n";
    log << "  bedforms " << n << "² cpu: " << benchFormat("%.1f", c.secondsPerRound * 1e3) << " ms a round\n";
    if (info.available) {
      auto gpu = cuda::createCudaBackend();
      const Timing g = timeRounds(*gpu, n, 20, rounds * 4);
      table << "| " << n << "² | " << info.description << " | " << benchFormat("%.2f", g.secondsPerRound * 1e3) << " | "
            << benchFormat("%.2f", g.secondsPerRound * 1e9 / (static_cast<double>(n) * n)) << " | " << g.slabsLifted << " | "
            << (g.ledgerExact ? "exact" : "BROKEN") << " |\n";
    }
  }
  if (!info.available) table << "\nCUDA: skipped (" << info.reason << ").\n";

  // References: the serial executor's bytes, the repose angle, the barchan census.
  const int n = 192, rounds = 500;
  const BedformParameters p = periodicBedformParameters();
  SnowState ref = makeBarchanWindow(n), par = ref;
  auto serial = createSerialBackend();
  auto cpu = createCpuBackend();
  serial->upload(ref);
  cpu->upload(par);
  const auto t0 = WallClock::now();
  const BedformStepReport rs = serial->bedformStep(makeBedformArgs(p, 0.0, rounds, 0, 1, 0.0));
  const double serialS = elapsedSeconds(t0);
  const auto t1 = WallClock::now();
  const BedformStepReport rp = cpu->bedformStep(makeBedformArgs(p, 0.0, rounds, 0, 1, 0.0));
  const double parallelS = elapsedSeconds(t1);
  serial->download(ref);
  cpu->download(par);
  auto differing = [&](const SnowState& a) {
    size_t d = 0;
    for (size_t i = 0; i < ref.powderM.size(); ++i) d += std::memcmp(&ref.powderM.values()[i], &a.powderM.values()[i], sizeof(float)) != 0;
    return d;
  };
  const double tanRepose = std::tan(p.reposeAngleDeg * kPi / 180.0);
  const BarchanCensus c = barchanCensus(par.powderM, 0.5, tanRepose, p.slabM);
  table << "\nAgainst exact references, " << n << "² window, " << rounds << " rounds (serial " << benchFormat("%.1f", serialS) << " s, cpu "
        << benchFormat("%.1f", parallelS) << " s):\n\n| check | reference | result |\n|---|---|---|\n"
        << "| slab ledger | slabs before = after | " << rp.slabsBefore << " = " << rp.slabsAfter << (rp.slabsBefore == rp.slabsAfter ? "" : " BROKEN") << " |\n"
        << "| repose after avalanching | steps <= tan 30° x 0.5 m | max excess " << benchFormat("%.2e", maxReposeExcessM(par, tanRepose, p.slabM, true)) << " m |\n"
        << "| cpu (" << threads << " threads) against the serial executor | same bytes, same ledger | " << differing(par)
        << " cells differ; " << rs.slabsEroded << " and " << rp.slabsEroded << " slabs lifted |\n";
  if (info.available) {
    SnowState g = makeBarchanWindow(n);
    auto gpu = cuda::createCudaBackend();
    gpu->upload(g);
    gpu->bedformStep(makeBedformArgs(p, 0.0, rounds, 0, 1, 0.0));
    gpu->download(g);
    table << "| " << info.description << " against the serial executor | same bytes | " << differing(g) << " cells differ |\n";
  }
  table << "| barchans (bodies >= 3 m wide above 0.1 m) | horns downwind, Filhol & Sturm 3-20 m long, 0.1-0.5 m tall | " << c.bodies
        << " bodies: " << c.hornsDownwind << " with a horn downwind, " << c.centreLeading << " with the centre leading; " << c.inSnowRange
        << " in the snow range; mean " << benchFormat("%.1f", c.meanLengthM) << " m long, " << benchFormat("%.2f", c.meanHeightM)
        << " m tall |\n"
        << "| slip faces (steeper than 22°) | on the lee side | " << c.faces.steepLeeCells << " lee, " << c.faces.steepWindwardCells
        << " windward |\n";
  return table.str();
}

}  // namespace snow
