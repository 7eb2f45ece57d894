#include "bench.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "bakers/atomic_file.h"
#include "core/cpu_backend.h"
#include "core/errors.h"
#include "core/reference_scenario.h"
#include "cuda/cuda_backend.h"

namespace snow {

namespace {
std::string machineDescription() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(cpuinfo, line))
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  return model + ", " + std::to_string(std::thread::hardware_concurrency()) + " hardware threads";
}

std::string format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}
}  // namespace

std::string runBench(const BenchOptions& o, std::ostream& log) {
  const int threads = o.threads > 0 ? o.threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  std::string backendName = o.backend;
  if (backendName == "auto") backendName = cuda::probeDevice().available ? "cuda" : "cpu";
  if (backendName == "cuda" && !cuda::probeDevice().available)
    throw InputError("--backend cuda: no usable CUDA device: " + cuda::probeDevice().reason);

  std::ostringstream table, csv;
  table << "Season stage, reference scenario (" << o.days << " days; snowfall, melt, powder diffusion), "
        << (backendName == "cpu" ? machineDescription() + ", " + std::to_string(threads) + " threads" : cuda::probeDevice().description)
        << "\n\n";
  table << "| grid | cell (m) | backend | season (s) | snowfall (s) | melt (s) | diffusion (s) | events | mass balance error |\n"
        << "|---|---|---|---|---|---|---|---|---|\n";
  csv << "size,cell_m,backend,threads,season_s,snowfall_s,melt_s,diffusion_s,events,mass_error\n";
  for (int size : o.sizes) {
    if (size < 8) throw InputError("--sizes: " + std::to_string(size) + " is too small");
    SnowState state = referenceRangeState(size);
    const SeasonConfig config = referenceWinter(o.days);
    computeTemperatureBase(state, config.params);
    auto backend = backendName == "cuda" ? cuda::createCudaBackend() : createCpuBackend();
    const auto t0 = std::chrono::steady_clock::now();
    const SeasonReport r = runSeason(*backend, state, config);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    double phase[3] = {0, 0, 0};
    for (const auto& p : r.phenomena) {
      if (p.name.rfind("snowfall", 0) == 0) phase[0] += p.seconds;
      if (p.name == "melt") phase[1] += p.seconds;
      if (p.name == "powder diffusion") phase[2] += p.seconds;
    }
    const double cell = state.spec.cellSizeXM;
    table << "| " << size << "² | " << format("%.2f", cell) << " | " << backend->name() << " | " << format("%.3f", seconds) << " | "
          << format("%.3f", phase[0]) << " | " << format("%.3f", phase[1]) << " | " << format("%.3f", phase[2]) << " | " << r.events
          << " | " << format("%.1e", r.massBalanceRelativeError()) << " |\n";
    csv << size << "," << cell << "," << backend->name() << "," << threads << "," << seconds << "," << phase[0] << "," << phase[1]
        << "," << phase[2] << "," << r.events << "," << r.massBalanceRelativeError() << "\n";
    log << "  " << size << "² done in " << format("%.2f", seconds) << " s\n";
  }
  if (!o.csvPath.empty()) {
    const auto parent = std::filesystem::path(o.csvPath).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent);
    writeTextAtomically(o.csvPath, csv.str());
    table << "\nCSV: " << o.csvPath << "\n";
  }
  return table.str();
}

}  // namespace snow
