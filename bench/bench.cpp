#include "bench.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <functional>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "core/atomic_file.h"
#include "core/avalanche_runs.h"
#include "core/cpu_backend.h"
#include "core/errors.h"
#include "core/reference_scenario.h"
#include "cuda/cuda_backend.h"
#include "precompute/exposure.h"
#include "precompute/horizon.h"
#include "static_snow/occlusion.h"
#include "bakers/mesh_writer.h"
#include "bakers/rtin.h"
#include "inputs/terrain_loader.h"
#include "precompute/wind.h"
#include "bench_suite.h"

namespace snow {

namespace {
constexpr auto format = benchFormat;
}  // namespace

namespace {

std::string windBench(const BenchOptions& o, std::ostream& log, int threads);
std::string sunBench(const BenchOptions& o, std::ostream& log, int threads);
std::string avalancheBench(const BenchOptions& o, std::ostream& log, int threads);
std::string seasonAvalancheCostBench(const BenchOptions& o, std::ostream& log, const std::string& backendName, int threads);
std::string occlusionBench(const BenchOptions& o, std::ostream& log, int threads);
std::string meshBench(const BenchOptions& o, std::ostream& log, int threads);

}  // namespace

std::string runBench(const BenchOptions& o, std::ostream& log) {
  const int threads = o.threads > 0 ? o.threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  static const std::vector<std::string> stages = {"sun", "wind", "season", "avalanche", "avalanche-reference", "stability", "occlusion", "mesh", "bedforms", "skiers", "meshsnow", "scaling", "bandwidth", "agreement", "bake", "all"};
  if (o.stage == "scaling-child") {  // internal: one size of the scaling stage, in its own process
    if (o.scalingSizes.size() != 1) throw InputError("--stage scaling-child: needs one size in --sizes");
    return scalingChild(o, o.scalingSizes[0]) + "\n";
  }
  if (std::find(stages.begin(), stages.end(), o.stage) == stages.end())
    throw InputError("--stage " + o.stage + ": must be sun, wind, season, avalanche, avalanche-reference, stability, occlusion, mesh, bedforms, skiers, meshsnow, scaling, bandwidth, agreement, bake or all");
  const auto t0 = WallClock::now();
  std::string out;
  auto run = [&](const char* name, const std::function<std::string()>& f) {
    if (o.stage != "all" && o.stage != name) return;
    const auto ts = WallClock::now();
    log << "bench: " << name << "\n";
    const std::string body = f();
    out += "## " + std::string(name) + "\n\n" + body + "\n(stage time " + format("%.0f", elapsedSeconds(ts)) + " s)\n\n";
  };
  run("sun", [&] { return sunBench(o, log, threads); });
  run("wind", [&] { return windBench(o, log, threads) + "\n" + windAccuracyBench(o, log, threads); });
  run("season", [&] { return seasonAccuracyBench(o, log, threads); });
  run("avalanche", [&] { return avalancheBench(o, log, threads) + "\n" + avalancheAccuracyBench(o, log, threads); });
  run("avalanche-reference", [&] { return avalancheReferenceBench(o, log, threads); });
  run("stability", [&] { return stabilityBench(o, log, threads); });
  run("occlusion", [&] { return occlusionBench(o, log, threads); });
  run("mesh", [&] { return meshBench(o, log, threads); });
  run("bedforms", [&] { return bedformBench(o, log, threads); });
  run("skiers", [&] { return skierBench(o, log, threads); });
  run("meshsnow", [&] { return meshSnowBench(o, log, threads); });
  run("scaling", [&] { return scalingBench(o, log, threads); });
  run("bandwidth", [&] { return bandwidthBench(o, log, threads); });
  run("agreement", [&] { return agreementBench(o, log, threads); });
  run("bake", [&] { return bakeBench(o, log, threads); });
  out += "Total: " + format("%.0f", elapsedSeconds(t0)) + " s on " + benchMachineDescription() + ", " + std::to_string(threads) + " threads.\n";
  if (!o.csvDir.empty()) {
    std::filesystem::create_directories(o.csvDir);
    writeTextAtomically((std::filesystem::path(o.csvDir) / "bench.md").string(), out);
  }
  return out;
}

namespace {

constexpr double kSunBenchLatitudeDeg = 46.5;
const std::vector<std::string> kSunLevels{"draft", "production", "reference"};

// The sun bench's timing: each quality level's season exposure (horizon sweep) and 120 days of
// temperature on the builtin range at o.sunSize^2; the seconds per level.
std::vector<double> sunTimingPart(const BenchOptions& o, const ModelParameters& p, int threads, std::ostream& table, std::ostream& csv,
                                  std::ostream& log) {
  const double latitude = kSunBenchLatitudeDeg;
  const int startDoy = 335;  // 1 December
  const std::vector<std::string>& levels = kSunLevels;
  DefaultTerrainOptions big;
  big.size = o.sunSize;
  big.cellSizeM = 10240.0 / o.sunSize;
  const Terrain tb = makeBuiltinTerrain(big);
  table << "Sun exposure, 120-day season from 1 December at 46.5 N, builtin range " << o.sunSize << "² at "
        << format("%.0f", big.cellSizeM) << " m, " << benchMachineDescription() << ", " << threads << " threads\n\n"
        << "| quality | method | horizons (s) | sky (s) | direct (s) | indirect (s) | temperature, 120 days (s) | total (s) |\n"
        << "|---|---|---|---|---|---|---|---|\n";
  std::vector<double> levelSeconds;
  for (const auto& name : levels) {
    ExposureSettings es;
    es.quality = sunQuality(name);
    es.latitudeDeg = latitude;
    es.startDayOfYear = startDoy;
    es.seasonDays = 120;
    es.horizonSweep = true;
    const auto t0 = WallClock::now();
    const Exposure e = computeExposure(nullptr, tb.heightsM, tb.valid, tb.info.spec, p, es);
    const auto t1 = WallClock::now();
    SnowState st;
    st.allocate(tb.info.spec);
    st.bedrockM = tb.heightsM;
    for (int day = 0; day < 120; ++day) {
      st.exposureHours = e.totalAt(day);
      computeTemperatureBase(st, p);
    }
    const double tempSeconds = elapsedSeconds(t1);
    const double total = elapsedSeconds(t0);
    table << "| " << name << " | horizon sweep | " << format("%.2f", e.timings.horizonSeconds) << " | " << format("%.2f", e.timings.skySeconds)
          << " | " << format("%.2f", e.timings.sunSeconds) << " | " << format("%.2f", e.timings.indirectSeconds) << " | "
          << format("%.2f", tempSeconds) << " | " << format("%.2f", total) << " |\n";
    csv << "time," << name << ",horizon," << o.sunSize << "," << e.timings.horizonSeconds << "," << e.timings.skySeconds << ","
        << e.timings.sunSeconds << "," << e.timings.indirectSeconds << "," << tempSeconds << "," << total << ",,,,\n";
    log << "  sun " << name << " " << o.sunSize << "²: " << format("%.1f", total) << " s\n";
    levelSeconds.push_back(total);
  }
  return levelSeconds;
}

// The sun bench's accuracy: each level and method on one day against the Embree path at reference
// quality; the horizon sweep's rows with the level's season seconds (`levelSeconds`).
std::vector<AccuracyRow> sunAccuracyPart(const BenchOptions& o, const ModelParameters& p, const std::vector<double>& levelSeconds,
                                         std::ostream& table, std::ostream& csv) {
  const double latitude = kSunBenchLatitudeDeg;
  const std::vector<std::string>& levels = kSunLevels;
  std::vector<AccuracyRow> accuracy;
  DefaultTerrainOptions small;
  small.size = o.sunAccuracySize;
  small.cellSizeM = 10240.0 / o.sunAccuracySize;
  const Terrain ts = makeBuiltinTerrain(small);
  const RayScene scene(ts.heightsM, ts.info.spec);
  const int doy = 20;  // 20 January
  auto oneDay = [&](const SunQuality& q, bool sweep, Grid<float>& sky, Grid<float>& sun, Grid<float>& ind) {
    if (sweep) {
      sky = skyFromHorizons(computeHorizonsBySweep(ts.heightsM, ts.valid, ts.info.spec, q.azimuths), ts.valid, p.skyAmbientWeightHours);
      sun = directSunFromHorizons(computeHorizonsBySweep(ts.heightsM, ts.valid, ts.info.spec, 4 * q.azimuths), ts.heightsM, ts.valid,
                                  ts.info.spec, latitude, doy, q.hourStep, p.directSunWeightHours);
    } else {
      sky = computeSkyExposure(scene, ts.valid, ts.info.spec, q.azimuths, q.bisections, p.skyAmbientWeightHours);
      sun = computeDirectSun(scene, ts.heightsM, ts.valid, ts.info.spec, latitude, doy, q.hourStep, p.directSunWeightHours);
    }
    ind = computeIndirectSun(sun, ts.heightsM, ts.valid, ts.info.spec, q.indirectDirections, q.indirectRings, q.indirectRadiusM,
                             p.indirectSunWeightHours / p.directSunWeightHours);
  };
  Grid<float> refSky, refSun, refInd;
  oneDay(sunQuality("reference"), false, refSky, refSun, refInd);
  Grid<float> refTotal = refSky;
  for (size_t i = 0; i < refTotal.size(); ++i) refTotal.values()[i] += refSun.values()[i] + refInd.values()[i];
  table << "\nError on 20 January against the Embree path at reference quality (relative L1 over the grid), builtin range "
        << o.sunAccuracySize << "² at " << format("%.0f", small.cellSizeM) << " m:\n\n"
        << "| quality | method | I_sky | I_sun | I_ind | I |\n|---|---|---|---|---|---|\n";
  for (const auto& name : levels)
    for (bool sweep : {true, false}) {
      if (!sweep && name == "reference") continue;  // the reference itself
      Grid<float> sky, sun, ind;
      oneDay(sunQuality(name), sweep, sky, sun, ind);
      Grid<float> total = sky;
      for (size_t i = 0; i < total.size(); ++i) total.values()[i] += sun.values()[i] + ind.values()[i];
      const double es = relativeL1(sky.values(), refSky.values()), eu = relativeL1(sun.values(), refSun.values()),
                   ei = relativeL1(ind.values(), refInd.values()), et = relativeL1(total.values(), refTotal.values());
      table << "| " << name << " | " << (sweep ? "horizon sweep" : "Embree") << " | " << format("%.4f", es) << " | " << format("%.4f", eu)
            << " | " << format("%.4f", ei) << " | " << format("%.4f", et) << " |\n";
      csv << "error," << name << "," << (sweep ? "horizon" : "embree") << "," << o.sunAccuracySize << ",,,,,,," << es << "," << eu << ","
          << ei << "," << et << "\n";
      if (sweep) {
        const size_t k = static_cast<size_t>(&name - &levels[0]);
        accuracy.push_back({name, levelSeconds[k], et, name == "draft"});
      }
    }
  return accuracy;
}

// Sun exposure: run time of each term for a 120-day season on a sunSize^2 grid, per quality
// level, and each level's error on one day against the Embree path at reference quality.
std::string sunBench(const BenchOptions& o, std::ostream& log, int threads) {
  std::ostringstream table, csv;
  const ModelParameters p;
  csv << "part,quality,method,size,horizons_s,sky_s,direct_s,indirect_s,temperature_s,total_s,err_sky,err_sun,err_ind,err_total\n";
  const std::vector<double> levelSeconds = sunTimingPart(o, p, threads, table, csv, log);
  const std::vector<AccuracyRow> accuracy = sunAccuracyPart(o, p, levelSeconds, table, csv);
  table << "\nDefault level: draft (precompute.sun_quality), " << format("%.2f", accuracy[0].seconds) << " s for the season's exposure on "
        << o.sunSize << "², error of I " << format("%.4f", accuracy[0].error) << ". Error against time, horizon sweep:\n\n"
        << "| level | season exposure on " << o.sunSize << "² (s) | I, relative L1 |\n|---|---|---|\n";
  for (const auto& r : accuracy)
    table << "| " << r.level << (r.isDefault ? " (default)" : "") << " | " << format("%.2f", r.seconds) << " | " << format("%.4f", r.error) << " |\n";
  {
    PlotSeries ps{"horizon sweep", {}};
    for (const auto& r : accuracy) ps.points.push_back({r.seconds, r.error, r.level});
    writePlot(o, "sun_accuracy", logLogSvg("Sun exposure: error against time", "season exposure, " + std::to_string(o.sunSize) + "² (s)",
                                           "relative L1 of I (20 January)", {ps}), table);
  }
  writeCsvFile(o, "sun.csv", csv.str(), table);
  return table.str();
}

std::string windBench(const BenchOptions& o, std::ostream& log, int threads) {
  std::ostringstream table, csv;
  table << "Wind field and wind-effect surface, one wind state (from 300 deg at 12 m/s), tolerance 1e-4, " << benchMachineDescription()
        << ", " << threads << " threads\n\n"
        << "| terrain | grid | ordering | iterations | last update | residual | field (s) | surface (s) | converged |\n"
        << "|---|---|---|---|---|---|---|---|---|\n";
  csv << "terrain,width,height,ordering,iterations,last_update,residual,field_s,surface_s,converged\n";
  struct Case {
    std::string name;
    Terrain terrain;
  };
  std::vector<Case> cases;
  for (int size : {256, 1024}) {
    DefaultTerrainOptions d;
    d.size = size;
    d.cellSizeM = 10240.0 / size;
    cases.push_back({"builtin ridged, " + format("%.0f", d.cellSizeM) + " m", makeBuiltinTerrain(d)});
  }
  const std::string dem = o.sharedDataDir + "/dem/front_range_srtm3.asc";
  if (std::filesystem::exists(dem)) cases.push_back({"front_range_srtm3.asc", loadDem(dem)});
  else table << "(skipped " << dem << ": not found)\n\n";
  ModelParameters p;
  const WindState state{300.0, 12.0};
  for (const auto& c : cases) {
    for (WindOrdering ordering : {WindOrdering::UpwindSweep, WindOrdering::RedBlack}) {
      const auto t0 = WallClock::now();
      Grid<float> wx, wy, fx, fy, wz, wsz;
      computeWindVectors(c.terrain.heightsM, c.terrain.valid, c.terrain.info.spec, state, p, wx, wy);
      computeFreeStream(c.terrain.heightsM, c.terrain.valid, c.terrain.info.spec, state, p, fx, fy);
      const double fieldSeconds = elapsedSeconds(t0);
      WindSolverOptions so;
      so.ordering = ordering;
      const WindSolveStats st = solveWindEffectSurface(c.terrain.heightsM, c.terrain.valid, c.terrain.info.spec, wx, wy, fx, fy,
                                                       p.windCapDecelerationMps2, so, wz, wsz);
      const auto& sp = c.terrain.info.spec;
      table << "| " << c.name << " | " << sp.width << " x " << sp.height << " | " << st.ordering << " | " << st.iterations << " | "
            << format("%.1e", st.lastUpdate) << " | " << format("%.1e", st.residual) << " | " << format("%.3f", fieldSeconds)
            << " | " << format("%.3f", st.seconds) << " | " << (st.converged ? "yes" : "no") << " |\n";
      csv << '"' << c.name << "\"," << sp.width << "," << sp.height << "," << st.ordering << "," << st.iterations << ","
          << st.lastUpdate << "," << st.residual << "," << fieldSeconds << "," << st.seconds << "," << st.converged << "\n";
      log << "  wind " << c.name << " " << st.ordering << ": " << st.iterations << " iterations, " << format("%.2f", st.seconds)
          << " s\n";
    }
  }
  writeCsvFile(o, "wind.csv", csv.str(), table);
  return table.str();
}

// The avalanche stage's backend by name ("cpu" or "cuda"), and the words its tables name it by.
std::unique_ptr<SnowBackend> avalancheBackend(const std::string& backendName) {
  return backendName == "cuda" ? cuda::createCudaBackend() : createCpuBackend();
}
std::string avalancheBackendDescription(const std::string& backendName, int threads) {
  return backendName == "cpu" ? benchMachineDescription() + ", " + std::to_string(threads) + " threads" : cuda::probeDevice().description;
}

std::string avalancheBench(const BenchOptions& o, std::ostream& log, int threads) {
  std::string backendName = o.backend;
  if (backendName == "auto") backendName = cuda::probeDevice().available ? "cuda" : "cpu";
  if (backendName == "cuda" && !cuda::probeDevice().available)
    throw InputError("--backend cuda: no usable CUDA device: " + cuda::probeDevice().reason);
  std::ostringstream table, csv;
  table << "Avalanche, one release on the embedded range at 5 m cells (core/reference_scenario.h), "
        << avalancheBackendDescription(backendName, threads)
        << "\n\n| grid | steps | simulated (s) | ms per step | largest box (cells) | runout (m) | mass error |\n|---|---|---|---|---|---|---|\n";
  csv << "size,backend,steps,simulated_s,ms_per_step,box_cells,runout_m,mass_error\n";
  for (int size : o.avalancheSizes) {
    SnowState s = referenceAvalancheState(size);
    auto backend = avalancheBackend(backendName);
    backend->upload(s);
    const double before = backend->totals().totalM3();
    const ModelParameters params;
    AvalancheRun run(*backend, params, s);
    if (!run.release(size / 2, size / 2, 0.0, 0.0, true)) throw std::runtime_error("the benchmark avalanche did not release");
    const AvalancheRecord r = run.runToRest();
    const double error = std::abs(backend->totals().totalM3() - before) / before;
    table << "| " << size << "² | " << r.steps << " | " << format("%.1f", r.simulatedS) << " | " << format("%.3f", r.secondsPerStep() * 1e3)
          << " | " << r.boxCellsMax << " | " << format("%.0f", r.runoutM) << " | " << format("%.1e", error) << " |\n";
    csv << size << "," << backend->name() << "," << r.steps << "," << r.simulatedS << "," << r.secondsPerStep() * 1e3 << ","
        << r.boxCellsMax << "," << r.runoutM << "," << error << "\n";
    log << "  avalanche on " << size << "² done\n";
  }
  writeCsvFile(o, "avalanche.csv", csv.str(), table);
  return table.str() + "\n" + seasonAvalancheCostBench(o, log, backendName, threads);
}

// The avalanches of a season (the reference winter on the embedded range, spontaneous releases
// at the default rate) grouped by their active box, the cells a step's passes may cover: the
// time a step takes against that box, so that the cost can be seen to follow the avalanche.
std::string seasonAvalancheCostBench(const BenchOptions& o, std::ostream& log, const std::string& backendName, int threads) {
  const int size = o.avalancheSeasonSize;
  SnowState s = referenceRangeState(size);
  SeasonConfig c = referenceWinter(o.days);
  computeTemperatureBase(s, c.params);
  auto backend = avalancheBackend(backendName);
  const SeasonReport report = runSeason(*backend, s, c);
  struct Bin {
    double below;
    int avalanches = 0;
    double steps = 0, boxCellSteps = 0, seconds = 0;
  };
  std::vector<Bin> bins = {{100}, {1000}, {10000}, {100000}, {1e300}};
  Bin all{0};
  for (const AvalancheRecord& r : report.avalanches) {
    if (!r.released || r.steps == 0) continue;
    const double meanBox = r.boxCellSteps / r.steps;
    Bin& b = *std::find_if(bins.begin(), bins.end(), [&](const Bin& b) { return meanBox < b.below; });
    for (Bin* x : {&b, &all}) ++x->avalanches, x->steps += r.steps, x->boxCellSteps += r.boxCellSteps, x->seconds += r.stepSeconds;
  }
  std::ostringstream table, csv;
  table << "The avalanches of a season by their mean active box: the reference winter (" << o.days << " days) on the embedded range at "
        << size << "² (" << format("%.0f", 10240.0 / size) << " m cells), spontaneous releases at the default rate; "
        << avalancheBackendDescription(backendName, threads)
        << ". The box is the cells a step's passes may cover (its rows' spans cover fewer).\n\n"
        << "| mean box (cells) | avalanches | steps | mean box | ms per step | ns per box cell and step |\n|---|---|---|---|---|---|\n";
  csv << "box_below,avalanches,steps,mean_box_cells,ms_per_step,ns_per_box_cell_step\n";
  double lower = 0;
  auto row = [&](const std::string& label, const Bin& b, double below) {
    if (b.steps == 0) return;
    table << "| " << label << " | " << b.avalanches << " | " << format("%.0f", b.steps) << " | " << format("%.0f", b.boxCellSteps / b.steps) << " | "
          << format("%.4f", 1e3 * b.seconds / b.steps) << " | " << format("%.2f", 1e9 * b.seconds / b.boxCellSteps) << " |\n";
    csv << below << "," << b.avalanches << "," << b.steps << "," << b.boxCellSteps / b.steps << "," << 1e3 * b.seconds / b.steps << ","
        << 1e9 * b.seconds / b.boxCellSteps << "\n";
  };
  for (const Bin& b : bins) {
    row(b.below > 1e299 ? format("%.0f or more", lower) : format("%.0f", lower) + "–" + format("%.0f", b.below), b, b.below);
    lower = b.below;
  }
  row("all", all, 0);
  log << "  the season's avalanches by box done\n";
  writeCsvFile(o, "avalanche_season.csv", csv.str(), table);
  return table.str();
}

// Occlusion mode, part 1: a canyon 100 m wide and 50 m deep, 1200 m long at 2 m cells, whose
// floor's middle sees cos(atan(2H/W)) of the sky: the ambient occlusion value against it.
void occlusionCanyonPart(OcclusionSettings s, int threads, std::ostream& table, std::ostream& csv) {
  const double W = 100.0, H = 50.0, cell = 2.0;
  GridSpec spec;
  spec.width = 600, spec.height = 120, spec.cellSizeXM = spec.cellSizeYM = cell;
  Grid<float> z(spec.width, spec.height, 0.f);
  Grid<uint8_t> valid(spec.width, spec.height, 1);
  for (int y = 0; y < spec.height; ++y)
    for (int x = 0; x < spec.width; ++x) z(x, y) = std::abs(y * cell - 120.0) < W / 2 ? 1000.f : static_cast<float>(1000.0 + H);
  const RayScene scene(z, spec);
  const double analytic = std::cos(std::atan(2.0 * H / W));
  table << "Occlusion mode: ambient occlusion value a at the middle of a canyon floor (W = 100 m, H = 50 m, 2 m cells) against the "
           "analytic sky-view factor cos(atan(2H/W)) = "
        << format("%.4f", analytic) << ", 100 cells along the floor, " << benchMachineDescription() << ", " << threads << " threads\n\n"
        << "| rays per point | mean a | mean error | max abs error (one cell) | M rays/s |\n|---|---|---|---|---|\n";
  for (int rays : {16, 64, 256, 1024}) {
    s.aoRays = rays;
    s.sunPositions = 0;
    const OcclusionSnow r = computeOcclusionSnowOnTerrain(scene, z, valid, spec, s);
    double mean = 0.0, maxErr = 0.0;
    for (int x = 250; x < 350; ++x) {
      const double a = r.ambient[static_cast<size_t>(60) * spec.width + x];
      mean += a / 100.0;
      maxErr = std::max(maxErr, std::abs(a - analytic));
    }
    const double rate = r.aoRayCount / std::max(r.aoSeconds, 1e-9) / 1e6;
    table << "| " << rays << " | " << format("%.4f", mean) << " | " << format("%+.4f", mean - analytic) << " | " << format("%.4f", maxErr)
          << " | " << format("%.1f", rate) << " |\n";
    csv << "canyon," << rays << ",600x120," << r.aoSeconds << ",,," << rate << "," << mean - analytic << "," << maxErr << "\n";
  }
}

// Occlusion mode, part 2: quality levels on the builtin range, the error against a 4096-ray run on
// a small grid and the time on the full one.
void occlusionQualityPart(const BenchOptions& o, OcclusionSettings s, std::ostream& log, std::ostream& table, std::ostream& csv) {
  DefaultTerrainOptions small;
  small.size = 128;
  small.cellSizeM = 10240.0 / 256;
  const Terrain ts = makeBuiltinTerrain(small);
  const RayScene scene(ts.heightsM, ts.info.spec);
  s.aoRays = 4096;
  const OcclusionSnow ref = computeOcclusionSnowOnTerrain(scene, ts.heightsM, ts.valid, ts.info.spec, s);
  double refSnow = 0.0;
  for (float v : ref.snowM) refSnow += v;
  const int timingSize = std::max(64, o.sunSize / 2);
  table << "\nQuality levels: error against 4096 rays per cell (builtin range 128² at 40 m), and time on the builtin range " << timingSize
        << "² at " << format("%.0f", 10240.0 / timingSize) << " m (10 sun positions, 21 December, 46.5 N):\n\n"
        << "| quality | rays per cell | mean abs error of a | snow, relative L1 | AO (s) | sun (s) | total (s) | M rays/s |\n"
        << "|---|---|---|---|---|---|---|---|\n";
  DefaultTerrainOptions big;
  big.size = timingSize;
  big.cellSizeM = 10240.0 / timingSize;
  const Terrain tb = makeBuiltinTerrain(big);
  const RayScene bigScene(tb.heightsM, tb.info.spec);
  PlotSeries ps{"ambient occlusion", {}};
  for (const char* q : {"draft", "production", "reference"}) {
    s.aoRays = occlusionRaysForQuality(q);
    const OcclusionSnow r = computeOcclusionSnowOnTerrain(scene, ts.heightsM, ts.valid, ts.info.spec, s);
    double errA = 0.0, errSnow = 0.0;
    for (size_t k = 0; k < r.ambient.size(); ++k) {
      errA += std::abs(r.ambient[k] - ref.ambient[k]) / r.ambient.size();
      errSnow += std::abs(r.snowM[k] - ref.snowM[k]);
    }
    errSnow /= std::max(refSnow, 1e-12);
    const auto t0 = WallClock::now();
    const OcclusionSnow b = computeOcclusionSnowOnTerrain(bigScene, tb.heightsM, tb.valid, tb.info.spec, s);
    const double total = elapsedSeconds(t0);
    const double rate = (b.aoRayCount + b.sunRayCount) / std::max(b.aoSeconds + b.sunSeconds, 1e-9) / 1e6;
    table << "| " << q << " | " << s.aoRays << " | " << format("%.4f", errA) << " | " << format("%.4f", errSnow) << " | "
          << format("%.2f", b.aoSeconds) << " | " << format("%.2f", b.sunSeconds) << " | " << format("%.2f", total) << " | "
          << format("%.1f", rate) << " |\n";
    csv << "quality_" << q << "," << s.aoRays << "," << timingSize << "," << b.aoSeconds << "," << b.sunSeconds << "," << total << "," << rate
        << "," << errA << "," << errSnow << "\n";
    log << "  occlusion " << q << " " << timingSize << "²: " << format("%.1f", total) << " s\n";
    ps.points.push_back({total, errA, q});
  }
  table << "\nDefault level: draft (precompute.sun_quality; 64 rays). Error falls monotonically with the rays per cell.\n";
  writePlot(o, "occlusion_accuracy",
            logLogSvg("Occlusion mode: error against time", "time on " + std::to_string(timingSize) + "² (s)", "mean |a - a_ref|", {ps}), table);
}

// Occlusion mode, part 3: the paper's Puget Sound size, a mesh of 500 000 triangles (the builtin
// range triangulated, 501 x 501 vertices), snow per vertex, everything from the Embree build on.
void occlusionMeshPart(OcclusionSettings s, std::ostream& log, std::ostream& table, std::ostream& csv) {
  DefaultTerrainOptions m;
  m.size = 501;
  m.cellSizeM = 20.0;
  const Terrain t = makeBuiltinTerrain(m);
  TriangleMesh mesh;
  const int n = 501;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) mesh.positions.push_back({float(i * 20.0), float((n - 1 - j) * 20.0), t.heightsM(i, j)});
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const uint32_t a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      mesh.triangles.push_back({a, c, d});
      mesh.triangles.push_back({a, d, b});
    }
  mesh.boundsMin = {0.f, 0.f, t.info.minElevationM > 0 ? float(t.info.minElevationM) : 0.f};
  mesh.boundsMax = {float((n - 1) * 20.0), float((n - 1) * 20.0), float(t.info.maxElevationM)};
  table << "\nA mesh of " << mesh.triangles.size() << " triangles (" << mesh.positions.size()
        << " vertices; the paper's Puget Sound took about 7 minutes on a 2007 GPU), snow per vertex, target 60 s:\n\n"
        << "| quality | rays per vertex | Embree build (s) | AO (s) | sun (s) | total (s) | M rays/s |\n|---|---|---|---|---|---|---|\n";
  for (const char* q : {"draft", "production"}) {
    s.aoRays = occlusionRaysForQuality(q);
    const auto t0 = WallClock::now();
    const Grid<float> none;
    const RayScene scene(none, GridSpec{}, {mesh});
    const double build = elapsedSeconds(t0);
    const OcclusionSnow r = computeOcclusionSnowOnMesh(scene, mesh, s);
    const double total = elapsedSeconds(t0);
    const double rate = (r.aoRayCount + r.sunRayCount) / std::max(r.aoSeconds + r.sunSeconds, 1e-9) / 1e6;
    table << "| " << q << " | " << s.aoRays << " | " << format("%.2f", build) << " | " << format("%.2f", r.aoSeconds) << " | "
          << format("%.2f", r.sunSeconds) << " | " << format("%.2f", total) << " | " << format("%.1f", rate) << " |\n";
    csv << "mesh_" << q << "," << s.aoRays << "," << mesh.triangles.size() << "," << r.aoSeconds << "," << r.sunSeconds << "," << total << ","
        << rate << ",,\n";
    log << "  occlusion mesh " << q << ": " << format("%.1f", total) << " s\n";
  }
}

// Occlusion mode (Foldes & Benes 2007): the ambient occlusion value against an analytic
// sky-view factor and against a many-ray run, the cost per quality on a terrain, and the paper's
// 500 000-triangle mesh.
std::string occlusionBench(const BenchOptions& o, std::ostream& log, int threads) {
  std::ostringstream table, csv;
  csv << "part,rays,size,ao_s,sun_s,total_s,mrays_per_s,err_mean,err_max\n";
  OcclusionSettings s;
  s.latitudeDeg = 46.5;
  s.dayOfYear = 355;
  occlusionCanyonPart(s, threads, table, csv);
  s.sunPositions = 10;
  occlusionQualityPart(o, s, log, table, csv);
  occlusionMeshPart(s, log, table, csv);
  writeCsvFile(o, "occlusion.csv", csv.str(), table);
  return table.str();
}

// The adaptive triangulation on a real DEM: triangles against the vertical error bound, the
// error measured on the output, and the time (triangulation and glTF writing).
std::string meshBench(const BenchOptions& o, std::ostream& log, int threads) {
  std::ostringstream table, csv;
  const std::string dem = o.sharedDataDir + "/dem/tyrol_avaWog_5m.asc";
  if (!std::filesystem::exists(dem)) return "Mesh simplification: skipped (" + dem + " not found)\n";
  TerrainSource src;
  src.file = dem;
  const Terrain t = loadTerrain(src);
  const GridSpec& spec = t.info.spec;
  const size_t full = 2 * static_cast<size_t>(spec.width - 1) * (spec.height - 1);
  table << "Mesh simplification, tyrol_avaWog_5m.asc (" << spec.width << " x " << spec.height << " cells of "
        << format("%.1f", spec.cellSizeXM) << " m; a full-resolution triangulation has " << full << " triangles), "
        << benchMachineDescription() << ", " << threads << " threads\n\n"
        << "| vertical error bound (m) | triangles | share of full | measured max error (m) | triangulation (s) | glb (s) | glb size (MB) |\n"
        << "|---|---|---|---|---|---|---|\n";
  csv << "bound_m,triangles,vertices,max_error_m,triangulation_s,glb_s,glb_bytes\n";
  const std::string dir = o.csvDir.empty() ? std::filesystem::temp_directory_path().string() : o.csvDir;
  std::filesystem::create_directories(dir);
  PlotSeries meshSeries{"adaptive triangulation", {}};
  for (double bound : {0.0, 0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 5.0}) {
    const auto t0 = WallClock::now();
    const RtinMesh m = buildRtin({&t.heightsM}, t.valid, bound);
    const double tri = elapsedSeconds(t0);
    const double err = rtinMaxVerticalError(m, t.heightsM);
    const auto t1 = WallClock::now();
    const MeshData mesh = surfaceMesh(m, t.heightsM, spec);
    const std::string path = (std::filesystem::path(dir) / "mesh_bench.glb").string();
    writeMesh(path, "glb", mesh);
    const double glb = elapsedSeconds(t1);
    const double mb = std::filesystem::file_size(path) / 1e6;
    table << "| " << format("%.2f", bound) << " | " << m.triangles.size() << " | " << format("%.3f", double(m.triangles.size()) / full) << " | "
          << format("%.3f", err) << " | " << format("%.2f", tri) << " | " << format("%.2f", glb) << " | " << format("%.1f", mb) << " |\n";
    csv << bound << "," << m.triangles.size() << "," << mesh.positions.size() << "," << err << "," << tri << "," << glb << ","
        << std::filesystem::file_size(path) << "\n";
    log << "  mesh bound " << bound << " m: " << m.triangles.size() << " triangles\n";
    meshSeries.points.push_back({tri + glb, err, format("%g m", bound)});
  }
  std::filesystem::remove(std::filesystem::path(dir) / "mesh_bench.glb");
  table << "\nDefault level: outputs.mesh_max_error_m = 0.1 m. The measured error grows with the bound (never above it) while the triangle "
           "count and the time fall.\n";
  writePlot(o, "mesh_accuracy",
            logLogSvg("Mesh simplification: error against time", "triangulation + glb (s)", "measured max vertical error (m)", {meshSeries}), table);
  writeCsvFile(o, "mesh.csv", csv.str(), table);
  return table.str();
}

}  // namespace

}  // namespace snow
