// `snowbake bench`: the benchmark suite. Per stage, run time against error at several quality
// levels (tables, CSV and SVG plots), scaling with the grid size (time per stage and peak
// memory), the machine limit (copy bandwidth against the season kernels' achieved bandwidth) and
// CPU against CUDA agreement. Every table says the machine and thread count.
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace snow {

struct BenchOptions {
  std::string stage = "all";  // sun | wind | season | avalanche | avalanche-reference | stability | occlusion | mesh | bedforms | skiers | meshsnow | scaling | bandwidth | agreement | bake | all
  int sunSize = 1024;          // grid of the sun-exposure timing table
  int sunAccuracySize = 256;   // grid of the sun-exposure accuracy table (the Embree reference is costly)
  std::vector<int> scalingSizes{256, 512, 1024, 2048, 4096};
  double scalingBudgetS = 420.0;  // sizes predicted to pass this (from the growth so far) are skipped
  int seasonAccuracySize = 256;   // grid of the season's step-rate refinement
  int bandwidthSize = 2048;
  int bandwidthReps = 10;
  int agreementSize = 1024;
  std::vector<int> avalancheSizes{512, 4096};  // the same avalanche on a small and a large terrain
  int avalancheSeasonSize = 512;  // the grid of the season whose avalanches' cost per box is tabled
  double days = 120.0;
  std::string backend = "cpu";  // cpu | cuda | auto
  int threads = 0;              // 0 = all cores
  std::string csvDir = "snowbake-bench";  // one CSV per stage; empty: none
  bool avalancheFit = false;     // avalanche-reference: also the grid search of the flow's friction
  std::string sharedDataDir = "../shared/data";  // real DEMs for the wind table (skipped when absent)
};

// Returns the table as printed.
std::string runBench(const BenchOptions& options, std::ostream& log);

}  // namespace snow
