// `snowbake bench`: times the season stage on the reference scenario (core/reference_scenario.h)
// for a list of grid sizes and prints a Markdown table (and writes CSV). The accuracy-against-
// time tables of the other stages join it as those stages land (the benchmark-suite issue).
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace snow {

struct BenchOptions {
  std::string stage = "all";  // sun | wind | season | avalanche | all
  int sunSize = 1024;          // grid of the sun-exposure timing table
  int sunAccuracySize = 256;   // grid of the sun-exposure accuracy table (the Embree reference is costly)
  std::vector<int> sizes{256, 512, 1024, 2048};
  std::vector<int> avalancheSizes{512, 4096};  // the same avalanche on a small and a large terrain
  double days = 120.0;
  std::string backend = "cpu";  // cpu | cuda | auto
  int threads = 0;              // 0 = all cores
  std::string csvDir = "snowbake-bench";  // one CSV per stage; empty: none
  std::string sharedDataDir = "../shared/data";  // real DEMs for the wind table (skipped when absent)
};

// Returns the table as printed.
std::string runBench(const BenchOptions& options, std::ostream& log);

}  // namespace snow
