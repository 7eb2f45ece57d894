// snowbake: the command-line program. The only translation unit that includes CLI11.
//   snowbake bake SCENE | --scene-list FILE --index N  [--terrain FILE] [--out DIR] [--seed N] [--threads N] [--backend cpu|cuda|auto] [--set KEY=VALUE]...
//                [--cache-dir DIR] [--no-cache] [--quiet] [--progress human|json] [--log-file FILE]
//   snowbake plan SCENE [every option of bake] [--json]
//   snowbake demo [--out DIR]
//   snowbake cache prune [--cache-dir DIR] [--older-than-days D] [--max-size-gb G] [--dry-run]
//   snowbake cache check [--cache-dir DIR]
//   snowbake info FILE [--json] [--set KEY=VALUE]...
//   snowbake help scene [--markdown]
//   snowbake bench [--stage sun|wind|season|avalanche|avalanche-reference|stability|occlusion|mesh|bedforms|skiers|meshsnow|scaling|bandwidth|agreement|bake|all] [--sizes 256,512,...] [--days D] [--threads N]
//                  [--backend cpu|cuda|auto] [--sun-size N] [--csv-dir DIR] [--data DIR]
//   snowbake --version | --help
// Exit status: 0 success, 2 usage or input error (one line naming the file and the problem),
// 130 bake stopped by SIGINT or SIGTERM (core/stop_request.h), 1 any other failure.
#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <new>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/errors.h"
#include "core/stop_request.h"
#include "bake/across_ranks.h"
#include "bake/bake.h"
#include "bake/bake_stage.h"
#include "bake/plan.h"
#include "bake/progress.h"
#include "bake/scene_list.h"
#include "bake/stages.h"
#include "bench/bench.h"
#include "distributed/launch.h"
#include "precompute/cache.h"
#include "precompute/cache_folder.h"
#include "scene/scene_reference.h"
#include "tools/info.h"

namespace {

using namespace snow;

// Each subcommand's values live in one struct that CLI11 writes into while parsing, so it must
// outlive app.parse().
struct BakeCommand {
  CLI::App* cmd = nullptr;
  BakeOptions bake;
  std::string scene;
  std::string sceneList;
  long long index = -1;
  std::string terrainFile, backend;
  uint64_t seed = 0;
  int threads = 0;
  bool quiet = false;
  std::string cacheDir;
  bool noCache = false;
  bool verbose = false;
  std::string progress = "human", logFile;
  bool json = false;  // plan --json
};

struct CacheCommand {
  CLI::App* cmd = nullptr;
  CLI::App* prune = nullptr;
  CLI::App* check = nullptr;
  CachePruneOptions options;
  std::string checkDir;
  double olderThanDays = 0, maxSizeGb = 0;
};

struct DemoCommand {
  CLI::App* cmd = nullptr;
  std::string out = "snowbake-demo";
};

struct InfoCommand {
  CLI::App* cmd = nullptr;
  std::string file;
  bool json = false;
  std::vector<std::string> sets;
};

struct HelpCommand {
  CLI::App* cmd = nullptr;
  std::string topic;
  bool markdown = false;
};

struct BenchCommand {
  CLI::App* cmd = nullptr;
  BenchOptions options;
  std::string sizes;
};

// The options of bake, which plan takes too (so a plan is of the very bake the same line runs).
void addBakeOptions(BakeCommand& c) {
  c.cmd->add_option("SCENE", c.scene, "Scene file (TOML), or preset:NAME (preset:default)");
  c.cmd->add_option("--scene-list", c.sceneList, "One level of a list, `NAME SCENE [KEY=VALUE ...]` a line, into OUT/NAME (docs/farm.md)");
  c.cmd->add_option("--index", c.index, "Which level of --scene-list, from 0 (e.g. $SLURM_ARRAY_TASK_ID)");
  c.cmd->add_option("--terrain", c.terrainFile, "Terrain file that replaces the scene's terrain");
  c.cmd->add_option("--out", c.bake.outDir, "Output folder (created if missing)")->capture_default_str();
  c.cmd->add_option("--seed", c.seed, "Random seed (overrides run.seed)");
  c.cmd->add_option("--threads", c.threads, "CPU threads, 0 = all cores (overrides run.threads)");
  c.cmd->add_option("--backend", c.backend, "cpu, cuda or auto (CUDA when a device works)")
      ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  c.cmd->add_option("--set", c.bake.sets, "Override a scene key by its dotted path, e.g. --set season.days=30 (repeatable)");
  c.cmd->add_flag("--quiet", c.quiet, "No progress bar");
  c.cmd->add_option("--cache-dir", c.cacheDir, "Precompute cache folder (default $XDG_CACHE_HOME/snowbake or ~/.cache/snowbake)");
  c.cmd->add_flag("--no-cache", c.noCache, "Neither read nor write the precompute cache");
  c.cmd->add_flag("--verbose", c.verbose, "Log where the memory went: the memory model's owners by group against the measured peak (docs/memory.md)");
  c.cmd->add_option("--progress", c.progress, "human (a bar on stderr) or json (one JSON object a line on stderr, docs/command-line.md)")
      ->check(CLI::IsMember({"human", "json"}))
      ->capture_default_str();
  c.cmd->add_option("--log-file", c.logFile, "Write the human log to FILE (with --progress json, stderr carries only JSON)");
}

void addBakeCommand(CLI::App& app, BakeCommand& c) {
  c.cmd = app.add_subcommand("bake", "Simulate a season on a scene's terrain and write its outputs.");
  addBakeOptions(c);
}

void addPlanCommand(CLI::App& app, BakeCommand& c) {
  c.cmd = app.add_subcommand("plan", "Say what `bake` would do with the same options: files, stages, peak memory, time class. Writes nothing.");
  addBakeOptions(c);
  c.cmd->add_flag("--json", c.json, "Print JSON (docs/command-line.md)");
}

void addDemoCommand(CLI::App& app, DemoCommand& c) {
  c.cmd = app.add_subcommand("demo", "Run the main job on the embedded default terrain (no input needed).");
  c.cmd->add_option("--out", c.out, "Output folder")->capture_default_str();
}

void addCacheCommand(CLI::App& app, CacheCommand& c) {
  c.cmd = app.add_subcommand("cache", "Look after the precompute cache folder.");
  c.cmd->require_subcommand(1);
  c.prune = c.cmd->add_subcommand("prune", "Remove entries unused for a number of days, then the least recently used beyond a size.");
  c.prune->add_option("--cache-dir", c.options.directory, "Cache folder (default $XDG_CACHE_HOME/snowbake or ~/.cache/snowbake)");
  c.prune->add_option("--older-than-days", c.olderThanDays, "Remove entries not used for more than D days");
  c.prune->add_option("--max-size-gb", c.maxSizeGb, "Then remove the least recently used until the rest take at most G GB (10^9 bytes)");
  c.prune->add_flag("--dry-run", c.options.dryRun, "List what would be removed, remove nothing");
  c.check = c.cmd->add_subcommand("check", "Read every entry and check its checksum; exit status 1 when one is damaged.");
  c.check->add_option("--cache-dir", c.checkDir, "Cache folder (default $XDG_CACHE_HOME/snowbake or ~/.cache/snowbake)");
}

void addInfoCommand(CLI::App& app, InfoCommand& c) {
  c.cmd = app.add_subcommand("info", "Show what snowbake understands of a terrain file.");
  c.cmd->add_option("FILE", c.file, "A DEM (any GDAL raster), a scene file or preset:NAME (for heightmaps, raw files and "
                                    "meshes, whose reading options live in the scene), or builtin:ridged")->required();
  c.cmd->add_flag("--json", c.json, "Print JSON");
  c.cmd->add_option("--set", c.sets, "Override a scene key (as for bake)");
}

void addHelpCommand(CLI::App& app, HelpCommand& c) {
  c.cmd = app.add_subcommand("help", "Print a reference: `help scene` lists every scene key and model parameter.");
  c.cmd->add_option("TOPIC", c.topic, "scene")->required()->check(CLI::IsMember({"scene"}));
  c.cmd->add_flag("--markdown", c.markdown, "As Markdown (docs/scene.md is this output)");
}

void addBenchCommand(CLI::App& app, BenchCommand& c) {
  BenchOptions& o = c.options;
  c.cmd = app.add_subcommand("bench", "The benchmark suite: error against time per stage, scaling, machine limit, CPU against CUDA.");
  c.cmd->add_option("--sizes", c.sizes, "Comma-separated grid sizes of the scaling stage (default 256,512,1024,2048,4096)");
  c.cmd->add_option("--days", o.days, "Season length in days")->capture_default_str();
  c.cmd->add_option("--scaling-budget-s", o.scalingBudgetS, "Scaling stage: sizes predicted to take longer than this are skipped (8192 with --sizes and about 3600)")
      ->capture_default_str();
  c.cmd->add_option("--backend", o.backend, "cpu, cuda or auto")->check(CLI::IsMember({"cpu", "cuda", "auto"}))
      ->capture_default_str();
  c.cmd->add_option("--threads", o.threads, "CPU threads, 0 = all cores");
  c.cmd->add_option("--sun-size", o.sunSize, "Grid size of the sun-exposure timing table")->capture_default_str();
  c.cmd->add_option("--stage", o.stage, "sun, wind, season, avalanche, avalanche-reference, stability, occlusion, mesh, bedforms, skiers, meshsnow, scaling, bandwidth, agreement, bake or all")
      ->check(CLI::IsMember({"sun", "season", "wind", "avalanche", "avalanche-reference", "stability", "occlusion", "mesh", "bedforms", "skiers", "meshsnow", "scaling", "bandwidth", "agreement", "bake", "all", "scaling-child"}))
      ->capture_default_str();
  c.cmd->add_option("--csv-dir", o.csvDir, "Folder for the CSV files (empty: none)")->capture_default_str();
  c.cmd->add_flag("--fit", o.avalancheFit, "avalanche-reference: also run the grid search of the flow's friction (about 2 minutes)");
  c.cmd->add_option("--data", o.sharedDataDir, "Folder of the real DEMs (its dem/ subfolder)")->capture_default_str();
}

// SCENE, or the level --index of --scene-list: its scene, its sets before the command line's
// (which win), and its own folder under --out.
void chooseScene(const BakeCommand& c, BakeOptions& bake, std::ostream& log) {
  const bool list = c.cmd->count("--scene-list") > 0, index = c.cmd->count("--index") > 0;
  if (list && !c.scene.empty()) throw InputError("bake: give SCENE or --scene-list, not both");
  if (list != index) throw InputError("bake: --scene-list and --index go together");
  if (!list) {
    if (c.scene.empty()) throw InputError("bake: no scene (give SCENE, or --scene-list FILE --index N)");
    bake.scene = c.scene;
    return;
  }
  const SceneListEntry level = sceneListEntry(c.sceneList, c.index);
  bake.scene = level.scene;
  bake.sets = level.sets;
  bake.sets.insert(bake.sets.end(), c.bake.sets.begin(), c.bake.sets.end());
  bake.outDir = (std::filesystem::path(c.bake.outDir) / level.name).string();
  log << "level " << c.index << " of " << c.sceneList << " (line " << level.line << "): " << level.name << " -> " << bake.outDir << "\n";
}

// The command line's values over the scene's; unset options leave the scene's choice.
BakeOptions bakeOptions(const BakeCommand& c, const std::vector<std::string>& argv, std::ostream& log) {
  BakeOptions bake = c.bake;
  bake.commandLine = argv;
  chooseScene(c, bake, log);
  if (!c.terrainFile.empty()) bake.terrainFile = c.terrainFile;
  if (c.cmd->count("--seed")) bake.seed = c.seed;
  if (c.cmd->count("--threads")) bake.threads = c.threads;
  if (!c.backend.empty()) bake.backend = c.backend;
  bake.progress = !c.quiet;
  if (!c.cacheDir.empty()) bake.cacheDir = c.cacheDir;
  bake.useCache = !c.noCache;
  bake.verbose = c.verbose;
  return bake;
}

ProgressOutcome bakeOutcome(const BakeResult& r) {
  ProgressOutcome o{"ok", 0};
  o.files = static_cast<long long>(r.files.size()) - 1;  // the manifest lists every file but itself
  o.manifest = r.files.back();
  if (r.season.final.totalM3() > 0 || r.season.initial.totalM3() > 0) o.massBalance = r.season.massBalanceRelativeError();
  return o;
}

// A command's failure in one line on `err`, and its exit status.
int describeFailure(std::exception_ptr failure, std::ostream& err) {
  try {
    std::rethrow_exception(failure);
  } catch (const InputError& e) {
    err << "snowbake: error: " << e.what() << "\n";
    return 2;
  } catch (const Interrupted& e) {
    err << "snowbake: " << e.what() << "\n";
    return kInterruptedExitStatus;
  } catch (const std::bad_alloc&) {
    // The memory model refuses what it predicts will not fit; this is what it did not foresee.
    const std::string stage = currentBakeStage();
    err << "snowbake: failed: out of memory" << (stage.empty() ? std::string() : " during the " + stage + " stage")
        << " (the memory model's prediction was short: see docs/memory.md; lower run.max_memory_gb or bake a smaller grid)\n";
    return 1;
  } catch (const std::exception& e) {
    err << "snowbake: failed: " << e.what() << "\n";
    return 1;
  } catch (...) {
    err << "snowbake: failed\n";
    return 1;
  }
}

// mpirun -np N / srun -n N snowbake bake: refused before any work unless the scene can be baked
// across ranks (bake/across_ranks.h); rank 0 alone logs.
int runBakeCommandAcrossRanks(const BakeCommand& c, const BakeOptions& bake, int ranks, const std::string& levelNote) {
  const std::string started = "started as " + std::to_string(ranks) + " processes (mpirun or srun)";
  if (c.progress == "json") throw InputError("--progress json: " + started + ", a bake across ranks reports on its log only (docs/distributed.md)");
  if (const std::string why = acrossRanksRefusal(resolveScene(bake)); !why.empty()) throw InputError(why + "; " + started + ": change the scene, or run one process");
  std::ofstream logFile;
  const auto openLog = [&]() -> std::ostream& {
    std::ostream* log = &std::cerr;
    if (!c.logFile.empty()) {
      logFile.open(c.logFile);
      if (!logFile) throw InputError(c.logFile + ": cannot write the log file (--log-file)");
      log = &logFile;
    }
    *log << levelNote;
    return *log;
  };
  return runBakeAcrossRanks(bake, openLog, describeFailure);
}

// The bake, its human log on stderr or in --log-file; with --progress json the last line on
// stderr says how it ended (and errors are reported there, not as text). The scene (or level) is
// chosen before the log is opened, so a bad list or index writes nothing.
int runBakeCommand(const BakeCommand& c, const std::vector<std::string>& argv) {
  std::ostringstream levelNote;
  BakeOptions bake;
  try {
    bake = bakeOptions(c, argv, levelNote);
  } catch (const InputError& e) {
    if (c.progress != "json") throw;
    JsonProgress(std::cerr).finish({"input_error", 2, -1, "", -1, e.what()});
    return 2;
  }
  const StopOnSignals stopOnSignals;  // Ctrl-C and SIGTERM stop the bake between steps: exit 130
  if (const int ranks = snow::dist::launchedRanks(); ranks > 1) {
    return runBakeCommandAcrossRanks(c, bake, ranks, levelNote.str());
  }
  std::ofstream logFile;
  std::ostream nowhere(nullptr);
  std::ostream* log = &std::cerr;
  if (!c.logFile.empty()) {
    logFile.open(c.logFile);
    if (!logFile) throw InputError(c.logFile + ": cannot write the log file (--log-file)");
    log = &logFile;
  } else if (c.progress == "json") {
    log = &nowhere;
  }
  *log << levelNote.str();
  if (c.progress != "json") {
    runBake(bake, *log);
    return 0;
  }
  JsonProgress json(std::cerr);
  bake.progressSink = &json;
  try {
    json.finish(bakeOutcome(runBake(bake, *log)));
    return 0;
  } catch (const InputError& e) {
    *log << "snowbake: error: " << e.what() << "\n";
    json.finish({"input_error", 2, -1, "", -1, e.what()});
    return 2;
  } catch (const Interrupted& e) {
    *log << "snowbake: " << e.what() << "\n";
    json.finish({"interrupted", kInterruptedExitStatus, -1, "", -1, e.what()});
    return kInterruptedExitStatus;
  } catch (const std::exception& e) {
    *log << "snowbake: failed: " << e.what() << "\n";
    json.finish({"failed", 1, -1, "", -1, e.what()});
    return 1;
  }
}

void runPlanCommand(const BakeCommand& c, const std::vector<std::string>& argv) {
  std::ostringstream levelNote;  // the level's line is for a bake's log
  const BakePlan plan = planBake(bakeOptions(c, argv, levelNote));
  if (c.json)
    std::cout << planToJson(plan);
  else
    printPlan(plan, std::cout);
}

void runDemoCommand(const DemoCommand& c) {
  BakeOptions demo;
  demo.outDir = c.out;
  runBake(demo, std::cerr);
  std::cerr << "demo: outputs and manifest.json are in " << c.out << "\n";
}

void runCachePrune(CacheCommand& c) {
  CachePruneOptions o = c.options;
  if (o.directory.empty()) o.directory = PrecomputeCache::defaultDirectory();
  if (c.prune->count("--older-than-days")) o.olderThanDays = c.olderThanDays;
  if (c.prune->count("--max-size-gb")) o.maxSizeGb = c.maxSizeGb;
  const CachePruneReport r = pruneCache(o, std::chrono::system_clock::now());
  for (const std::string& path : r.removed) std::cout << (o.dryRun ? "would remove " : "removed ") << path << "\n";
  std::cout << "cache " << o.directory << ": " << (o.dryRun ? "would remove " : "removed ") << r.removed.size() << " files ("
            << r.removedBytes << " bytes), kept " << r.keptEntries << " entries (" << r.keptBytes << " bytes)\n";
}

int runCacheCheck(const CacheCommand& c) {
  const std::string dir = c.checkDir.empty() ? PrecomputeCache::defaultDirectory() : c.checkDir;
  size_t damaged = 0;
  const std::vector<CacheEntryStatus> entries = checkCacheFolder(dir);
  for (const CacheEntryStatus& e : entries) {
    std::cout << (e.problem.empty() ? "ok " : "damaged ") << e.path << (e.problem.empty() ? "" : " (" + e.problem + ")") << "\n";
    damaged += !e.problem.empty();
  }
  std::cout << "cache " << dir << ": " << entries.size() << " entries, " << damaged << " damaged\n";
  return damaged ? 1 : 0;
}

// "256,512" -> {256, 512}; throws InputError naming the item that is not a number.
std::vector<int> parseSizeList(const std::string& text) {
  std::vector<int> sizes;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) {
    try {
      sizes.push_back(std::stoi(item));
    } catch (const std::exception&) {
      throw InputError("--sizes: '" + item + "' is not a whole number");
    }
  }
  return sizes;
}

void runBenchCommand(BenchCommand& c) {
  if (!c.sizes.empty()) c.options.scalingSizes = parseSizeList(c.sizes);
  std::cout << runBench(c.options, std::cerr);
}

// Parses the command line; returns the exit status when it ends the program (help, version,
// a usage error), nothing when a subcommand is to run.
std::optional<int> parseCommandLine(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "snowbake: " << e.what() << " (see snowbake --help)\n";
    return 2;
  }
  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"snowbake: turns a terrain into a season of snow, and bakes it into maps, meshes and volumes."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("snowbake ") + programVersion());
  BakeCommand bake, plan;
  DemoCommand demo;
  CacheCommand cache;
  InfoCommand info;
  HelpCommand help;
  BenchCommand bench;
  addBakeCommand(app, bake);
  addPlanCommand(app, plan);
  addDemoCommand(app, demo);
  addCacheCommand(app, cache);
  addInfoCommand(app, info);
  addHelpCommand(app, help);
  addBenchCommand(app, bench);
  if (const std::optional<int> status = parseCommandLine(app, argc, argv)) return *status;
  // Under mpirun -np N or srun -n N only a bake runs decomposed (docs/distributed.md); any other
  // command would run N times over: refused, on every rank alike.
  if (const int ranks = snow::dist::launchedRanks(); ranks > 1 && !*bake.cmd && !*info.cmd && !*help.cmd) {
    std::cerr << "snowbake: error: started as " << ranks
              << " processes (mpirun or srun): only `snowbake bake` runs across ranks (docs/distributed.md); run one process\n";
    return 2;
  }

  try {
    if (*bake.cmd) {
      return runBakeCommand(bake, std::vector<std::string>(argv, argv + argc));
    } else if (*plan.cmd) {
      runPlanCommand(plan, std::vector<std::string>(argv, argv + argc));
    } else if (*demo.cmd) {
      runDemoCommand(demo);
    } else if (*cache.prune) {
      runCachePrune(cache);
    } else if (*cache.check) {
      return runCacheCheck(cache);
    } else if (*bench.cmd) {
      runBenchCommand(bench);
    } else if (*info.cmd) {
      std::cout << describeTerrain(info.file, info.json, info.sets);
    } else if (*help.cmd) {
      std::cout << (help.markdown ? sceneReferenceMarkdown() : sceneReferenceText());
    }
  } catch (const InputError&) {
    // Started by mpirun or srun, every rank has the same input error: rank 0 says it, and ends
    // first (mpirun ends the job at the first process that fails).
    if (snow::dist::launchedRanks() > 1 && snow::dist::launchedRank() != 0) {
      std::this_thread::sleep_for(std::chrono::seconds(1));
      return 2;
    }
    return describeFailure(std::current_exception(), std::cerr);
  } catch (...) {
    return describeFailure(std::current_exception(), std::cerr);
  }
  return 0;
}
