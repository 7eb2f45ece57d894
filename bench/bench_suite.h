// The benchmark suite's newer stages (bench.cpp runs them): accuracy against time for the
// wind-effect surface, the season and the avalanche step, scaling with the grid size (time per
// stage and peak memory, each size in its own process), the machine limit (copy bandwidth and
// the season kernels' achieved bandwidth) and CPU against CUDA agreement.
#pragma once
#include <cstdio>
#include <ostream>
#include <string>
#include <vector>

#include "bench.h"
#include "core/util.h"
#include "plot.h"

namespace snow {

// printf-style formatting of one number.
inline std::string benchFormat(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// sum |a - reference| / sum |reference| (0 for an all-zero reference), summed in double.
double relativeL1(const std::vector<float>& a, const std::vector<float>& reference);

// One accuracy level of a stage: its name, run time, error, and whether it is the default.
struct AccuracyRow {
  std::string level;
  double seconds = 0;
  double error = 0;
  bool isDefault = false;
};

// Writes `text` to <csvDir>/<name> (when csvDir is set) and says where in `table`.
void writeCsvFile(const BenchOptions& o, const std::string& name, const std::string& text, std::ostream& table);
// Writes `svg` to <csvDir>/plots/<name>.svg (when csvDir is set) and says where in `table`.
void writePlot(const BenchOptions& o, const std::string& name, const std::string& svg, std::ostream& table);

std::string windAccuracyBench(const BenchOptions& o, std::ostream& log, int threads);
std::string seasonAccuracyBench(const BenchOptions& o, std::ostream& log, int threads);
std::string avalancheAccuracyBench(const BenchOptions& o, std::ostream& log, int threads);
// The AvaFrame com1DFA reference cases of <data>/avaframe/ (bench_avalanche_reference.cpp).
std::string avalancheReferenceBench(const BenchOptions& o, std::ostream& log, int threads);
// The stability rates' study (bench_stability.cpp).
std::string stabilityBench(const BenchOptions& o, std::ostream& log, int threads);
std::string scalingBench(const BenchOptions& o, std::ostream& log, int threads);
std::string bandwidthBench(const BenchOptions& o, std::ostream& log, int threads);
std::string agreementBench(const BenchOptions& o, std::ostream& log, int threads);
// Wind bedforms: time per round on 256²-1024² windows, and the exact references (bench_bedforms.cpp).
std::string bedformBench(const BenchOptions& o, std::ostream& log, int threads);
std::string skierBench(const BenchOptions& o, std::ostream& log, int threads);
std::string meshSnowBench(const BenchOptions& o, std::ostream& log, int threads);
// The default scene at 1024² with every output, as `snowbake bake` runs it.
std::string bakeBench(const BenchOptions& o, std::ostream& log, int threads);

// The child side of the scaling stage: one size, every stage, one CSV line on stdout.
std::string scalingChild(const BenchOptions& o, int size);

std::string benchMachineDescription();

}  // namespace snow
