#include "bench_suite.h"

#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "bakers/grid_writer.h"
#include "core/atomic_file.h"
#include "core/avalanche_runs.h"
#include "core/cpu_backend.h"
#include "core/errors.h"
#include "core/reference_scenario.h"
#include "cuda/cuda_backend.h"
#include "precompute/exposure.h"
#include "inputs/terrain_loader.h"
#include "precompute/wind.h"
#include "bake/bake.h"

extern char** environ;

namespace snow {
namespace {

namespace fs = std::filesystem;
constexpr auto fmt = benchFormat;

// The accuracy table shared by the stages: level, time, error, default marked; monotone check.
std::string accuracyTable(const std::vector<AccuracyRow>& rows, const std::string& errorName, const std::string& timeName) {
  std::ostringstream t;
  t << "| level | " << timeName << " | " << errorName << " |\n|---|---|---|\n";
  for (const auto& r : rows)
    t << "| " << r.level << (r.isDefault ? " (default)" : "") << " | " << fmt("%.3f", r.seconds) << " | " << fmt("%.3e", r.error) << " |\n";
  bool monotone = true;
  for (size_t k = 1; k < rows.size(); ++k) monotone = monotone && rows[k].error <= rows[k - 1].error;
  t << "\nError " << (monotone ? "falls monotonically" : "does NOT fall monotonically") << " from the coarsest to the finest level.\n";
  return t.str();
}

PlotSeries seriesOf(const std::string& name, const std::vector<AccuracyRow>& rows) {
  PlotSeries s;
  s.name = name;
  for (const auto& r : rows) s.points.push_back({r.seconds, r.error, r.level});
  return s;
}

// Least-squares slope of log(y) against log(x).
double logSlope(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = x.size();
  if (n < 2) return 0.0;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t k = 0; k < n; ++k) {
    const double lx = std::log(x[k]), ly = std::log(std::max(y[k], 1e-12));
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
  }
  const double d = n * sxx - sx * sx;
  return d != 0 ? (n * sxy - sx * sy) / d : 0.0;
}

}  // namespace

double relativeL1(const std::vector<float>& a, const std::vector<float>& ref) {
  double diff = 0, sum = 0;
  for (size_t i = 0; i < a.size(); ++i) diff += std::abs(static_cast<double>(a[i]) - ref[i]), sum += std::abs(static_cast<double>(ref[i]));
  return sum > 0 ? diff / sum : 0.0;
}

std::string benchMachineDescription() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(cpuinfo, line))
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  return model + ", " + std::to_string(std::thread::hardware_concurrency()) + " hardware threads";
}

void writeCsvFile(const BenchOptions& o, const std::string& name, const std::string& text, std::ostream& table) {
  if (o.csvDir.empty()) return;
  fs::create_directories(o.csvDir);
  const std::string path = (fs::path(o.csvDir) / name).string();
  writeTextAtomically(path, text);
  table << "\nCSV: " << path << "\n";
}

void writePlot(const BenchOptions& o, const std::string& name, const std::string& svg, std::ostream& table) {
  if (o.csvDir.empty()) return;
  const fs::path dir = fs::path(o.csvDir) / "plots";
  fs::create_directories(dir);
  const std::string path = (dir / (name + ".svg")).string();
  writeTextAtomically(path, svg);
  table << "Plot: " << path << "\n";
}

// Wind-effect surface: the red-black Gauss-Seidel at falling tolerances and the default upwind
// sweep, against red-black converged to 1e-7 m.
std::string windAccuracyBench(const BenchOptions& o, std::ostream& log, int threads) {
  std::ostringstream table, csv;
  const std::string dem = o.sharedDataDir + "/dem/front_range_srtm3.asc";
  Terrain t;
  std::string name;
  if (fs::exists(dem)) {
    t = loadDem(dem);
    name = "front_range_srtm3.asc";
  } else {
    DefaultTerrainOptions d;
    d.size = 256;
    d.cellSizeM = 40.0;
    t = makeBuiltinTerrain(d);
    name = "builtin ridged 256² at 40 m (" + dem + " not found)";
  }
  const auto& spec = t.info.spec;
  const ModelParameters p;
  const WindState state{300.0, 12.0};
  Grid<float> wx, wy, fx, fy;
  computeWindVectors(t.heightsM, t.valid, spec, state, p, wx, wy);
  computeFreeStream(t.heightsM, t.valid, spec, state, p, fx, fy);
  auto solve = [&](WindOrdering ordering, double tol, int maxIterations, Grid<float>& wz) {
    WindSolverOptions so;
    so.ordering = ordering;
    so.toleranceM = tol;
    so.maxIterations = maxIterations;
    Grid<float> wsz;
    return solveWindEffectSurface(t.heightsM, t.valid, spec, wx, wy, fx, fy, p.windCapDecelerationMps2, so, wz, wsz);
  };
  Grid<float> ref;
  const WindSolveStats rs = solve(WindOrdering::RedBlack, 1e-7, 100000, ref);
  table << "Wind-effect surface W_z, " << name << " (" << spec.width << " x " << spec.height << "), wind from 300 deg at 12 m/s, "
        << benchMachineDescription() << ", " << threads << " threads. Reference: red-black Gauss-Seidel to 1e-7 m (" << rs.iterations
        << " iterations, " << fmt("%.2f", rs.seconds) << " s). Quality knob: the iteration cap (the tolerance alone is not one: "
        << "information crosses the grid one cell an iteration, so a loose tolerance still takes as many iterations). Error: max |W_z - W_z,ref| (m) "
        << "over the valid cells.\n\n";
  csv << "ordering,max_iterations,iterations,seconds,max_error_m,default\n";
  auto maxError = [&](const Grid<float>& wz) {
    double e = 0;
    for (size_t i = 0; i < wz.size(); ++i)
      if (t.valid.values()[i]) e = std::max(e, static_cast<double>(std::abs(wz.values()[i] - ref.values()[i])));
    return e;
  };
  std::vector<AccuracyRow> rows, upwind;
  for (int cap : {4, 16, 64, 256}) {
    Grid<float> wz;
    const WindSolveStats st = solve(WindOrdering::RedBlack, 1e-4, cap, wz);
    const double e = maxError(wz);
    rows.push_back({"red-black, at most " + std::to_string(cap) + " it. (" + std::to_string(st.iterations) + ")", st.seconds, e, false});
    csv << "red-black," << cap << "," << st.iterations << "," << st.seconds << "," << e << ",0\n";
  }
  for (int cap : {1, 100000}) {
    Grid<float> wz;
    const WindSolveStats st = solve(WindOrdering::UpwindSweep, 1e-4, cap, wz);
    const double e = maxError(wz);
    upwind.push_back({"upwind sweep, " + std::to_string(st.iterations) + " it.", st.seconds, e, cap > 1});
    csv << "upwind," << cap << "," << st.iterations << "," << st.seconds << "," << e << "," << (cap > 1) << "\n";
  }
  table << accuracyTable(rows, "max error (m)", "time (s)") << "\nThe default, the upwind sweep to 1e-4 m: " << fmt("%.3f", upwind[1].seconds)
        << " s, max error " << fmt("%.3e", upwind[1].error) << " m (" << upwind[1].level << "; after its first sweep: "
        << fmt("%.3e", upwind[0].error) << " m).\n";
  writeCsvFile(o, "wind_accuracy.csv", csv.str(), table);
  writePlot(o, "wind_accuracy",
            logLogSvg("Wind-effect surface: error against time", "time (s)", "max |W_z - W_z,ref| (m)",
                      {seriesOf("red-black Gauss-Seidel", rows), seriesOf("upwind sweep (default)", upwind)}),
            table);
  log << "  wind accuracy done\n";
  return table.str();
}

// The season at k x the default step rates (snowfall, state changes, diffusion, wind transport)
// against a run at 4x: fixed storm windows and no spontaneous avalanches, so the steps' rate is
// the only difference.
std::string seasonAccuracyBench(const BenchOptions& o, std::ostream& log, int threads) {
  std::ostringstream table, csv;
  const int size = o.seasonAccuracySize;
  auto run = [&](double factor, double& seconds) {
    SnowState s = referenceRangeState(size);
    SeasonConfig c = referenceWinter(o.days);
    c.params.avalancheRatePerKm2PerDay = 0.0;
    c.params.skiersPerHour = 0.0;
    for (double start = 5; start + 3 <= o.days; start += 14) c.weather.snowfallPeriods.push_back({start, start + 3});
    c.params.snowfallStepsPerDay *= factor;
    c.params.stateChangeStepsPerDay *= factor;
    c.params.diffusionStepsPerDay *= factor;
    c.params.windTransportStepsPerDay *= factor;
    computeTemperatureBase(s, c.params);
    auto backend = createCpuBackend();
    const auto t0 = WallClock::now();
    runSeason(*backend, s, c);
    seconds = elapsedSeconds(t0);
    return s.depthGrid().values();
  };
  double refSeconds = 0;
  const std::vector<float> ref = run(4.0, refSeconds);
  table << "Season, step-rate refinement: the reference scenario (" << size << "² at " << fmt("%.0f", 10240.0 / size) << " m, " << o.days
        << " days, a 3-day storm every 14 days, no spontaneous avalanches or skiers) with every step rate (snowfall, melt and stability, "
           "powder diffusion, wind transport) at k times its default, against k = 4 ("
        << fmt("%.2f", refSeconds) << " s). Error: relative L1 of the final snow depth. " << benchMachineDescription() << ", " << threads
        << " threads.\n\n";
  csv << "factor,seconds,depth_rel_l1,default\n";
  std::vector<AccuracyRow> rows;
  for (double k : {0.25, 0.5, 1.0, 2.0}) {
    double seconds = 0;
    const std::vector<float> d = run(k, seconds);
    const double e = relativeL1(d, ref);
    rows.push_back({"k = " + fmt("%g", k) + " (" + fmt("%g", 2.0 * k) + " steps a day)", seconds, e, k == 1.0});
    csv << k << "," << seconds << "," << e << "," << (k == 1.0) << "\n";
    log << "  season accuracy k = " << k << ": " << fmt("%.2f", seconds) << " s\n";
  }
  table << accuracyTable(rows, "depth, relative L1", "season (s)");
  writeCsvFile(o, "season_accuracy.csv", csv.str(), table);
  writePlot(o, "season_accuracy", logLogSvg("Season: error against time (step rate)", "season (s)", "relative L1 of the depth", {seriesOf("season", rows)}),
            table);
  return table.str();
}

// One avalanche (the benchmark release) at falling step lengths against a step of 1/16 of the
// default's, on 5 m cells and on the default scene's 10 m (the same avalanche, the same extent).
std::string avalancheAccuracyBench(const BenchOptions& o, std::ostream& log, int threads) {
  std::ostringstream table, csv;
  auto run = [&](double cellM, double stepS, double& seconds, AvalancheRecord& rec) {
    const int size = static_cast<int>(std::lround(2560.0 / cellM));
    SnowState s = referenceAvalancheState(size, cellM);
    auto backend = createCpuBackend();
    backend->upload(s);
    ModelParameters p;
    p.avalancheStepS = stepS;
    AvalancheRun a(*backend, p, s);
    const auto t0 = WallClock::now();
    if (!a.release(size / 2, size / 2, 0.0, 0.0, true)) throw std::runtime_error("the benchmark avalanche did not release");
    rec = a.runToRest();
    seconds = elapsedSeconds(t0);
    backend->download(s);
    return s.depthGrid().values();
  };
  table << "Avalanche step: the benchmark release (2560 m square, 512² at 5 m and 256² at 10 m; core/reference_scenario.h) with steps of "
           "avalanche_step_s (substeps of at most 0.2 sqrt(L/g) within each: 0.143 s at 5 m, 0.202 s at 10 m), against 0.00625 s on the same "
           "cells. Error: relative L1 of the snow depth at rest. "
        << benchMachineDescription() << ", " << threads << " threads.\n\n";
  csv << "cell_m,step_s,seconds,depth_rel_l1,runout_m,default\n";
  std::vector<PlotSeries> series;
  for (double cellM : {5.0, 10.0}) {
    double refSeconds = 0;
    AvalancheRecord refRec;
    const std::vector<float> ref = run(cellM, 0.1 / 16, refSeconds, refRec);
    std::vector<AccuracyRow> cellRows;
    for (double step : {0.4, 0.1, 0.05, 0.025}) {
      double seconds = 0;
      AvalancheRecord rec;
      const std::vector<float> d = run(cellM, step, seconds, rec);
      const double e = relativeL1(d, ref);
      cellRows.push_back({fmt("%g m, ", cellM) + fmt("%g s", step) + " (runout " + fmt("%.0f m", rec.runoutM) + ")", seconds, e, step == 0.1});
      csv << cellM << "," << step << "," << seconds << "," << e << "," << rec.runoutM << "," << (step == 0.1) << "\n";
    }
    table << fmt("%g m cells", cellM) << " (" << 2560.0 / cellM << "²), against 0.00625 s (runout " << fmt("%.0f", refRec.runoutM) << " m, "
          << fmt("%.2f", refSeconds) << " s):\n\n"
          << accuracyTable(cellRows, "depth at rest, relative L1", "release to rest (s)") << "\n";
    series.push_back(seriesOf(fmt("%g m cells", cellM), cellRows));
  }
  log << "  avalanche accuracy done\n";
  writeCsvFile(o, "avalanche_accuracy.csv", csv.str(), table);
  writePlot(o, "avalanche_accuracy", logLogSvg("Avalanche: error against time (step length)", "release to rest (s)", "relative L1 of the depth", series),
            table);
  return table.str();
}

// ---- Scaling: each size in its own process (its peak memory is its own) ----

std::string scalingChild(const BenchOptions& o, int size) {
  const auto tAll = WallClock::now();
  auto t0 = WallClock::now();
  DefaultTerrainOptions d;
  d.size = size;
  d.cellSizeM = 10240.0 / size;
  const Terrain t = makeBuiltinTerrain(d);
  const double terrainS = elapsedSeconds(t0);
  t0 = WallClock::now();
  const ModelParameters p;
  ExposureSettings es;
  es.quality = sunQuality("draft");
  es.latitudeDeg = 46.5;
  es.startDayOfYear = 335;
  es.seasonDays = o.days;
  es.horizonSweep = true;
  const Exposure e = computeExposure(nullptr, t.heightsM, t.valid, t.info.spec, p, es);
  const double sunS = elapsedSeconds(t0);
  t0 = WallClock::now();
  Grid<float> wx, wy, fx, fy, wz, wsz;
  computeWindVectors(t.heightsM, t.valid, t.info.spec, WindState{300.0, 12.0}, p, wx, wy);
  computeFreeStream(t.heightsM, t.valid, t.info.spec, WindState{300.0, 12.0}, p, fx, fy);
  solveWindEffectSurface(t.heightsM, t.valid, t.info.spec, wx, wy, fx, fy, p.windCapDecelerationMps2, WindSolverOptions{}, wz, wsz);
  const double windS = elapsedSeconds(t0);
  t0 = WallClock::now();
  SnowState s = referenceRangeState(size);
  s.exposureHours = e.totalAt(0);
  const SeasonConfig c = referenceWinter(o.days);
  computeTemperatureBase(s, c.params);
  auto backend = createCpuBackend();
  runSeason(*backend, s, c);
  const double seasonS = elapsedSeconds(t0);
  t0 = WallClock::now();
  const fs::path dir = fs::temp_directory_path() / ("snowbake_scaling_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  for (SnowLayer l : {SnowLayer::Compacted, SnowLayer::Stable, SnowLayer::Unstable, SnowLayer::Powder})
    writeFloatImage((dir / snowLayerName(l)).string(), "exr", s.layer(l), snowLayerName(l));
  writeFloatImage((dir / "depth").string(), "exr", s.depthGrid(), "depth");
  fs::remove_all(dir);
  const double outputsS = elapsedSeconds(t0);
  // The peak resident set of this process's own address space (VmHWM): the parent's rusage
  // would carry the spawning process's peak across the exec.
  double peakKiB = 0;
  std::ifstream status("/proc/self/status");
  for (std::string l; std::getline(status, l);)
    if (l.rfind("VmHWM:", 0) == 0) peakKiB = std::stod(l.substr(6));
  std::ostringstream line;
  line << size << "," << terrainS << "," << sunS << "," << windS << "," << seasonS << "," << outputsS << "," << elapsedSeconds(tAll) << "," << peakKiB;
  return line.str();
}

namespace {

// One size of the scaling stage in a child process (`bench --stage scaling-child`), so each size's
// peak memory is its own: the CSV line it prints last, as numbers (size, the five stages' seconds,
// the total, the peak in KiB) and as printed.
std::vector<double> runScalingChild(int size, int threads, double days, std::string& line) {
  int pipefd[2];
  if (::pipe(pipefd) != 0) throw std::runtime_error("pipe failed");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, pipefd[1], 1);
  posix_spawn_file_actions_addclose(&actions, pipefd[0]);
  const std::string sizeArg = std::to_string(size), threadArg = std::to_string(threads), daysArg = fmt("%g", days);
  std::vector<std::string> args = {"snowbake", "bench", "--stage", "scaling-child", "--sizes", sizeArg, "--threads", threadArg, "--days", daysArg};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, "/proc/self/exe", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(pipefd[1]);
  if (rc != 0) {
    ::close(pipefd[0]);
    throw std::runtime_error(std::string("cannot start the scaling child: ") + std::strerror(rc));
  }
  std::string out;
  char buf[4096];
  for (ssize_t n; (n = ::read(pipefd[0], buf, sizeof buf)) > 0;) out.append(buf, static_cast<size_t>(n));
  ::close(pipefd[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw std::runtime_error("the scaling child for " + sizeArg + "² failed");
  std::istringstream in(out);
  std::string l;
  line.clear();
  while (std::getline(in, l))
    if (!l.empty()) line = l;
  std::vector<double> v;
  std::stringstream ls(line);
  for (std::string f; std::getline(ls, f, ',');) v.push_back(std::stod(f));
  if (v.size() != 8) throw std::runtime_error("the scaling child for " + sizeArg + "² printed '" + line + "'");
  return v;
}

// The scaling table's growth line: least squares of log time against log cells, from the sizes
// above 256² where there are two or more (small grids are dominated by fixed costs).
std::string scalingGrowth(const std::vector<double>& cells, const std::vector<double>& total, const std::vector<double>& peak,
                          const std::vector<std::vector<double>>& stages) {
  std::vector<double> c2, t2, p2;
  std::vector<std::vector<double>> s2(5);
  size_t large = 0;
  for (double c : cells) large += c > 256.0 * 256.0;
  for (size_t k = 0; k < cells.size(); ++k)
    if (cells[k] > 256.0 * 256.0 || large < 2) {
      c2.push_back(cells[k]), t2.push_back(total[k]), p2.push_back(peak[k]);
      for (int j = 0; j < 5; ++j) s2[static_cast<size_t>(j)].push_back(stages[static_cast<size_t>(j)][k]);
    }
  return "\nFitted growth (least squares of log time against log cells" + std::string(c2.size() < cells.size() ? ", sizes above 256²" : "") +
         "): total ~ n^" + fmt("%.2f", logSlope(c2, t2)) + " (n cells); terrain n^" + fmt("%.2f", logSlope(c2, s2[0])) + ", sun n^" +
         fmt("%.2f", logSlope(c2, s2[1])) + ", wind n^" + fmt("%.2f", logSlope(c2, s2[2])) + ", season n^" + fmt("%.2f", logSlope(c2, s2[3])) +
         ", outputs n^" + fmt("%.2f", logSlope(c2, s2[4])) + "; peak memory n^" + fmt("%.2f", logSlope(c2, p2)) + ".\n";
}

}  // namespace

std::string scalingBench(const BenchOptions& o, std::ostream& log, int threads) {
  std::ostringstream table, csv;
  table << "Scaling: the builtin range over 10.24 km at each grid size, every stage in its own process: terrain, sun exposure (draft, "
           "horizon sweep, "
        << o.days << " days), wind (one state, field and W_z), the reference season (" << o.days
        << " days, no wind), the four layers and the depth as EXR. Peak memory is the child process's peak resident set (VmHWM), libraries included (about 140 MiB). "
        << benchMachineDescription() << ", " << threads << " threads; sizes whose predicted time would pass the stage's budget of "
        << fmt("%.0f", o.scalingBudgetS) << " s are skipped.\n\n"
        << "| grid | terrain (s) | sun (s) | wind (s) | season (s) | outputs (s) | total (s) | peak memory (MiB) |\n|---|---|---|---|---|---|---|---|\n";
  csv << "size,terrain_s,sun_s,wind_s,season_s,outputs_s,total_s,peak_mib\n";
  std::vector<double> cells, total, peak;
  std::vector<std::vector<double>> stages(5);
  const auto start = WallClock::now();
  std::string skipped;
  for (int size : o.scalingSizes) {
    if (!total.empty()) {
      const double ratio = static_cast<double>(size) * size / cells.back();
      const double slope = total.size() >= 2 ? std::max(1.0, logSlope(cells, total)) : 1.5;
      const double predicted = total.back() * std::pow(ratio, slope);
      if (elapsedSeconds(start) + predicted > o.scalingBudgetS) {
        skipped += "| " + std::to_string(size) + "² | skipped: predicted " + fmt("%.0f", predicted) + " s (growth n^" + fmt("%.2f", slope) +
                   ") would pass the budget | | | | | | |\n";
        continue;
      }
    }
    std::string last;
    const std::vector<double> v = runScalingChild(size, threads, o.days, last);
    const double mib = v[7] / 1024.0;
    table << "| " << size << "² | " << fmt("%.2f", v[1]) << " | " << fmt("%.2f", v[2]) << " | " << fmt("%.2f", v[3]) << " | " << fmt("%.2f", v[4])
          << " | " << fmt("%.2f", v[5]) << " | " << fmt("%.2f", v[6]) << " | " << fmt("%.0f", mib) << " |\n";
    csv << last.substr(0, last.rfind(',')) << "," << mib << "\n";
    cells.push_back(static_cast<double>(size) * size);
    total.push_back(v[6]);
    peak.push_back(mib);
    for (int k = 0; k < 5; ++k) stages[static_cast<size_t>(k)].push_back(std::max(v[static_cast<size_t>(k) + 1], 1e-6));
    log << "  scaling " << size << "²: " << fmt("%.1f", v[6]) << " s, " << fmt("%.0f", mib) << " MiB\n";
  }
  table << skipped;
  if (cells.size() >= 2) table << scalingGrowth(cells, total, peak, stages);
  writeCsvFile(o, "scaling.csv", csv.str(), table);
  return table.str();
}

// ---- Machine limit ----

namespace {

// Bytes each kernel moves per cell (reads + writes of 4-byte floats and 1-byte masks), counted
// from its code; a neighbour's value is counted once (it is another cell's own read). The CPU
// fuses snowfall and the stability change with their slope snapshot by rows (no slope field
// written or read); CUDA runs the snapshot as a pass of its own.
struct KernelBytes {
  const char* name;
  int cpuBytes, gpuBytes;
  const char* derivation;
};
const KernelBytes kKernelBytes[] = {
    {"snowfall", 46, 75,
     "CPU, fused with its slope by rows: valid, B, C, S, U, P, T_base read, P, U, S, delta written (41); sum: delta, valid (5). GPU: slope pass: "
     "B, C, S, U, P read, valid, slope written (25); snowfall: valid, B+4 layers, slope, T_base read, P, U, S, delta written (45); sum (5)"},
    {"melt", 54, 54, "valid, T_base, 4 layers, melted read; 4 layers, delta, melted written (49); sum: delta, valid (5)"},
    {"stability", 37, 58,
     "CPU, fused with its slope by rows: valid, B, C, S, U, P, T_base, wind loading read, S, U written (37). GPU: slope pass (25); valid, "
     "T_base, slope, wind loading, S, U read, S, U written (33)"},
    {"wind transport", 74, 74, "shares pass: valid, B+4 layers, W_x, W_y, W_z read, two shares written (41); gather pass: valid, the shares read, P, scour, deposit read and written (33)"},
    {"powder diffusion (one substep)", 34, 34,
     "base pass, once a step: B, C, S, U, valid read, B + C + S + U written (21); the substep's two passes row by row (shares in cache): base, P, "
     "valid read, P written (13)"},
};

double hostCopyBandwidthGBs(size_t floats) {
  std::vector<float> a(floats, 1.f), b(floats, 0.f);
  double best = 1e30;
  for (int rep = 0; rep < 5; ++rep) {
    const auto t0 = WallClock::now();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, floats, 1 << 20), [&](const tbb::blocked_range<size_t>& r) {
      std::memcpy(b.data() + r.begin(), a.data() + r.begin(), (r.end() - r.begin()) * sizeof(float));
    });
    best = std::min(best, elapsedSeconds(t0));
  }
  if (b[floats / 2] != 1.f) throw std::runtime_error("copy check failed");
  return 2.0 * floats * sizeof(float) / best / 1e9;
}

SnowState bandwidthState(int size) {
  SnowState s = referenceRangeState(size);
  s.powderM.fill(0.3f);
  s.stableM.fill(0.5f);
  s.unstableM.fill(0.1f);
  s.compactedM.fill(0.2f);
  s.windXMps.fill(5.f);
  s.windYMps.fill(2.f);
  s.windEffectZM = s.bedrockM;
  s.windLoadingMps2.fill(0.01f);
  computeTemperatureBase(s, ModelParameters{});
  return s;
}

// Seconds per step of each kernel on `backend`.
std::vector<double> kernelSeconds(SnowBackend& backend, const SnowState& s, int reps) {
  // Every cell does the full work: snow falls everywhere (no rain limit), every cell melts.
  ModelParameters p;
  p.rainSnowLimitM = -1000.0;
  WeatherState warm;
  warm.seaLevelTemperatureC = 40.0;
  std::vector<double> out;
  backend.upload(s);
  auto time = [&](const std::function<void()>& f) {
    f();  // warm-up
    backend.maxTemperatureBaseC();
    const auto t0 = WallClock::now();
    for (int r = 0; r < reps; ++r) f();
    backend.maxTemperatureBaseC();  // waits for queued device work
    out.push_back(elapsedSeconds(t0) / reps);
  };
  time([&] { backend.snowfall(makeSnowfallArgs(p, 0.01, warm)); });
  time([&] { backend.melt(makeMeltArgs(p, 0.001, warm)); });
  time([&] { backend.stabilityChange(makeStabilityArgs(p, 0.01, warm)); });
  time([&] { backend.windTransport(makeWindTransportArgs(p, 0.01)); });
  PowderDiffusionArgs d = makePowderDiffusionArgs(p, 0.01);  // one substep at 10 m cells
  time([&] { backend.powderDiffusion(d); });
  return out;
}

}  // namespace

std::string bandwidthBench(const BenchOptions& o, std::ostream& log, int threads) {
  std::ostringstream table, csv;
  const int size = o.bandwidthSize;
  const double copy = hostCopyBandwidthGBs(size_t{64} << 20);
  const SnowState s = bandwidthState(size);
  const double cells = static_cast<double>(s.spec.cellCount());
  auto cpu = createCpuBackend();
  const std::vector<double> cpuSeconds = kernelSeconds(*cpu, s, o.bandwidthReps);
  table << "Machine limit: the season kernels on " << size << "² (snow in every layer, wind everywhere), bytes per cell counted from each "
        << "kernel's reads and writes, against the copy bandwidth measured in the same run (a parallel memcpy of 256 MiB, read + write "
           "counted, best of 5).\n\nCPU: "
        << benchMachineDescription() << ", " << threads << " threads: copy bandwidth " << fmt("%.1f", copy) << " GB/s.\n\n"
        << "| kernel | bytes per cell | ms per step | achieved GB/s | share of copy |\n|---|---|---|---|---|\n";
  csv << "device,kernel,bytes_per_cell,seconds_per_step,achieved_gbs,copy_gbs,share\n";
  for (size_t k = 0; k < cpuSeconds.size(); ++k) {
    const double gbs = kKernelBytes[k].cpuBytes * cells / cpuSeconds[k] / 1e9;
    table << "| " << kKernelBytes[k].name << " | " << kKernelBytes[k].cpuBytes << " | " << fmt("%.2f", cpuSeconds[k] * 1e3) << " | " << fmt("%.1f", gbs)
          << " | " << fmt("%.0f %%", 100.0 * gbs / copy) << " |\n";
    csv << "cpu," << kKernelBytes[k].name << "," << kKernelBytes[k].cpuBytes << "," << cpuSeconds[k] << "," << gbs << "," << copy << "," << gbs / copy << "\n";
  }
  table << "\nWhat each count holds:\n\n";
  for (const auto& kb : kKernelBytes) table << "- " << kb.name << ": " << kb.derivation << ".\n";
  const cuda::DeviceInfo info = cuda::probeDevice();
  if (info.available) {
    auto gpu = cuda::createCudaBackend();
    const double devCopy = cuda::deviceCopyBandwidthGBs();
    const std::vector<double> gpuSeconds = kernelSeconds(*gpu, s, o.bandwidthReps * 5);
    table << "\nGPU: " << info.description << ": device copy bandwidth " << fmt("%.0f", devCopy) << " GB/s.\n\n"
          << "| kernel | bytes per cell | ms per step | achieved GB/s | share of copy |\n|---|---|---|---|---|\n";
    for (size_t k = 0; k < gpuSeconds.size(); ++k) {
      const double gbs = kKernelBytes[k].gpuBytes * cells / gpuSeconds[k] / 1e9;
      table << "| " << kKernelBytes[k].name << " | " << kKernelBytes[k].gpuBytes << " | " << fmt("%.3f", gpuSeconds[k] * 1e3) << " | "
            << fmt("%.0f", gbs) << " | " << fmt("%.0f %%", 100.0 * gbs / devCopy) << " |\n";
      csv << "gpu," << kKernelBytes[k].name << "," << kKernelBytes[k].gpuBytes << "," << gpuSeconds[k] << "," << gbs << "," << devCopy << ","
          << gbs / devCopy << "\n";
    }
  } else {
    table << "\nGPU: not measured (" << info.reason << ").\n";
  }
  log << "  bandwidth done\n";
  writeCsvFile(o, "bandwidth.csv", csv.str(), table);
  return table.str();
}

std::string agreementBench(const BenchOptions& o, std::ostream& log, int threads) {
  (void)threads;
  std::ostringstream table;
  const cuda::DeviceInfo info = cuda::probeDevice();
  table << "CPU against CUDA: the reference season (" << o.agreementSize << "², " << o.days << " days) on both backends.\n\n";
  if (!info.available) {
    table << "Skipped: no CUDA device (" << info.reason << ").\n";
    return table.str();
  }
  SnowState a = referenceRangeState(o.agreementSize), b = a;
  const SeasonConfig c = referenceWinter(o.days);
  computeTemperatureBase(a, c.params);
  computeTemperatureBase(b, c.params);
  auto cpu = createCpuBackend();
  auto gpu = cuda::createCudaBackend();
  auto t0 = WallClock::now();
  runSeason(*cpu, a, c);
  const double cpuS = elapsedSeconds(t0);
  t0 = WallClock::now();
  runSeason(*gpu, b, c);
  const double gpuS = elapsedSeconds(t0);
  size_t differ = 0;
  double worst = 0;
  for (SnowLayer l : {SnowLayer::Compacted, SnowLayer::Stable, SnowLayer::Unstable, SnowLayer::Powder})
    for (size_t i = 0; i < a.spec.cellCount(); ++i) {
      const float x = a.layer(l).values()[i], y = b.layer(l).values()[i];
      if (std::memcmp(&x, &y, sizeof x) != 0) ++differ, worst = std::max(worst, static_cast<double>(std::abs(x - y)));
    }
  table << "| backend | grid | season (s) |\n|---|---|---|\n| cpu | " << o.agreementSize << "² | " << fmt("%.2f", cpuS) << " |\n| "
        << info.description << " | " << o.agreementSize << "² | " << fmt("%.2f", gpuS) << " |\n";
  {
    // The GPU alone on the largest grid.
    SnowState big = referenceRangeState(4096);
    computeTemperatureBase(big, c.params);
    auto gpuBig = cuda::createCudaBackend();
    t0 = WallClock::now();
    runSeason(*gpuBig, big, c);
    table << "| " << info.description << " | 4096² | " << fmt("%.2f", elapsedSeconds(t0)) << " |\n";
  }
  table << "\nLayer values that differ between the backends (" << o.agreementSize << "²): " << differ << " of " << 4 * a.spec.cellCount()
        << " (largest difference " << fmt("%.3g", worst) << " m).\n";
  log << "  agreement done\n";
  return table.str();
}

// The default scene at 1024² with every output: the bakers' cost on top of the season.
std::string bakeBench(const BenchOptions& o, std::ostream& log, int threads) {
  const fs::path dir = fs::temp_directory_path() / ("snowbake_bench_bake_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  BakeOptions b;
  b.scene = "preset:default";
  b.outDir = dir.string();
  b.threads = threads;
  b.backend = o.backend == "auto" ? "auto" : o.backend;
  b.useCache = false;
  b.progress = false;
  b.sets = {"terrain.size=1024",
            "outputs.layers=[\"compacted\",\"stable\",\"unstable\",\"powder\",\"depth\",\"bedrock\",\"surface\",\"valid_mask\","
            "\"wind_speed\",\"wind_direction\",\"wind_shadow_depth\",\"wind_shadow_mask\",\"sun_exposure\",\"temperature\",\"wind_scour\","
            "\"wind_deposit\",\"melt\",\"avalanche_scour\",\"avalanche_deposit\",\"ski_tracks\",\"avalanche_preview\",\"preview\"]",
            "outputs.encodings=[\"png16\",\"png8\",\"r16\"]", "outputs.multichannel_exr=true", "outputs.displacement_size=[2048,2048]",
            "outputs.vdb=true", "outputs.meshes=[\"glb\",\"obj\",\"ply\",\"fbx\"]", "outputs.mesh_parts=[\"surface\",\"body\"]"};
  std::ostringstream bakeLog;
  // The process's CPU time (user + system, every thread) over the bake: how busy the cores were.
  auto cpuSeconds = [] {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return u.ru_utime.tv_sec + u.ru_utime.tv_usec * 1e-6 + u.ru_stime.tv_sec + u.ru_stime.tv_usec * 1e-6;
  };
  const double cpu0 = cpuSeconds();
  const auto t0 = WallClock::now();
  const BakeResult r = runBake(b, bakeLog);
  const double total = elapsedSeconds(t0);
  const double cpu = cpuSeconds() - cpu0;
  uintmax_t bytes = 0;
  for (const auto& f : r.files) {
    std::error_code ec;
    const auto n = fs::file_size(f, ec);
    if (!ec) bytes += n;
  }
  fs::remove_all(dir);
  std::ostringstream table;
  table << "A bake with every output: the default scene at 1024² (10 m, 120 days, frames at day 60 and the end) with 20 layers as EXR, "
           "16-bit PNG, 8-bit PNG and .r16 (among them the 8192² ski-track texture), the multi-channel EXR, 2048² displacement maps, the "
           "VDB, surface and body meshes in glb/obj/ply/fbx, previews; "
        << benchMachineDescription() << ", " << threads << " threads, backend " << r.backendName << ": **" << fmt("%.1f", total) << " s**, "
        << r.files.size() << " files, " << fmt("%.2f", bytes / 1e9) << " GB; CPU time " << fmt("%.1f", cpu) << " s (user + system), "
        << fmt("%.2f", cpu / total) << " cores busy on average. The season's simulation took " << fmt("%.1f", r.season.seconds)
        << " s of it (the frame day's outputs are written beside it, on their own thread). The bake's own log:\n\n```\n";
  std::istringstream in(bakeLog.str());
  for (std::string line; std::getline(in, line);)
    if (line.rfind("precompute:", 0) == 0 || line.rfind("season:", 0) == 0 || line.rfind("  powder diffusion", 0) == 0 ||
        line.rfind("outputs:", 0) == 0 || (line.size() > 2 && line[0] == ' ' && line.find(" s") != std::string::npos &&
                                           line.find("avalanche day") == std::string::npos && line.find("skier") == std::string::npos &&
                                           bakeLog.str().find("outputs:") < bakeLog.str().find(line)) ||
        line.rfind("total:", 0) == 0)
      table << line << "\n";
  table << "```\n";
  log << "  bake with every output: " << fmt("%.1f", total) << " s\n";
  return table.str();
}

}  // namespace snow
