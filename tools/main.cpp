// snowbake: the command-line program. The only translation unit that includes CLI11.
//   snowbake bake SCENE [--terrain FILE] [--out DIR] [--seed N] [--threads N] [--backend cpu|cuda|auto] [--set KEY=VALUE]...
//                [--cache-dir DIR] [--no-cache] [--quiet]
//   snowbake demo [--out DIR]
//   snowbake info FILE [--json] [--set KEY=VALUE]...
//   snowbake help scene [--markdown]
//   snowbake bench [--stage sun|wind|season|avalanche|occlusion|mesh|bedforms|skiers|meshsnow|scaling|bandwidth|agreement|bake|all] [--sizes 256,512,...] [--days D] [--threads N]
//                  [--backend cpu|cuda|auto] [--sun-size N] [--csv-dir DIR] [--data DIR]
//   snowbake --version | --help
// Exit status: 0 success, 2 usage or input error (one line naming the file and the problem),
// 1 any other failure.
#include <CLI/CLI.hpp>

#include <iostream>
#include <sstream>

#include "core/errors.h"
#include "bake/bake.h"
#include "bench/bench.h"
#include "scene/scene_reference.h"
#include "tools/info.h"

int main(int argc, char** argv) {
  using namespace snow;
  CLI::App app{"snowbake: turns a terrain into a season of snow, and bakes it into maps, meshes and volumes."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("snowbake ") + programVersion());

  BakeOptions bake;
  std::string scene;
  std::string terrainFile, backend;
  uint64_t seed = 0;
  int threads = 0;
  bool quiet = false;
  CLI::App* bakeCmd = app.add_subcommand("bake", "Simulate a season on a scene's terrain and write its outputs.");
  bakeCmd->add_option("SCENE", scene, "Scene file (TOML), or preset:NAME (preset:default)")->required();
  bakeCmd->add_option("--terrain", terrainFile, "Terrain file that replaces the scene's terrain");
  bakeCmd->add_option("--out", bake.outDir, "Output folder (created if missing)")->capture_default_str();
  bakeCmd->add_option("--seed", seed, "Random seed (overrides run.seed)");
  bakeCmd->add_option("--threads", threads, "CPU threads, 0 = all cores (overrides run.threads)");
  bakeCmd->add_option("--backend", backend, "cpu, cuda or auto (CUDA when a device works)")
      ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  bakeCmd->add_option("--set", bake.sets, "Override a scene key by its dotted path, e.g. --set season.days=30 (repeatable)");
  bakeCmd->add_flag("--quiet", quiet, "No progress bar");
  std::string cacheDir;
  bool noCache = false;
  bakeCmd->add_option("--cache-dir", cacheDir, "Precompute cache folder (default $XDG_CACHE_HOME/snowbake or ~/.cache/snowbake)");
  bakeCmd->add_flag("--no-cache", noCache, "Neither read nor write the precompute cache");

  std::string demoOut = "snowbake-demo";
  CLI::App* demoCmd = app.add_subcommand("demo", "Run the main job on the embedded default terrain (no input needed).");
  demoCmd->add_option("--out", demoOut, "Output folder")->capture_default_str();

  std::string infoFile;
  bool infoJson = false;
  CLI::App* infoCmd = app.add_subcommand("info", "Show what snowbake understands of a terrain file.");
  std::vector<std::string> infoSets;
  infoCmd->add_option("FILE", infoFile, "A DEM (any GDAL raster), a scene file or preset:NAME (for heightmaps, raw files and "
                                        "meshes, whose reading options live in the scene), or builtin:ridged")->required();
  infoCmd->add_flag("--json", infoJson, "Print JSON");
  infoCmd->add_option("--set", infoSets, "Override a scene key (as for bake)");

  std::string helpTopic;
  bool helpMarkdown = false;
  CLI::App* helpCmd = app.add_subcommand("help", "Print a reference: `help scene` lists every scene key and model parameter.");
  helpCmd->add_option("TOPIC", helpTopic, "scene")->required()->check(CLI::IsMember({"scene"}));
  helpCmd->add_flag("--markdown", helpMarkdown, "As Markdown (docs/scene.md is this output)");

  BenchOptions benchOptions;
  std::string benchSizes;
  CLI::App* benchCmd = app.add_subcommand("bench", "The benchmark suite: error against time per stage, scaling, machine limit, CPU against CUDA.");
  benchCmd->add_option("--sizes", benchSizes, "Comma-separated grid sizes of the scaling stage (default 256,512,1024,2048,4096)");
  benchCmd->add_option("--days", benchOptions.days, "Season length in days")->capture_default_str();
  benchCmd->add_option("--backend", benchOptions.backend, "cpu, cuda or auto")->check(CLI::IsMember({"cpu", "cuda", "auto"}))
      ->capture_default_str();
  benchCmd->add_option("--threads", benchOptions.threads, "CPU threads, 0 = all cores");
  benchCmd->add_option("--sun-size", benchOptions.sunSize, "Grid size of the sun-exposure timing table")->capture_default_str();
  benchCmd->add_option("--stage", benchOptions.stage, "sun, wind, season, avalanche, occlusion, mesh, bedforms, skiers, meshsnow, scaling, bandwidth, agreement, bake or all")
      ->check(CLI::IsMember({"sun", "season", "wind", "avalanche", "occlusion", "mesh", "bedforms", "skiers", "meshsnow", "scaling", "bandwidth", "agreement", "bake", "all", "scaling-child"}))
      ->capture_default_str();
  benchCmd->add_option("--csv-dir", benchOptions.csvDir, "Folder for the CSV files (empty: none)")->capture_default_str();
  benchCmd->add_option("--data", benchOptions.sharedDataDir, "Folder of the real DEMs (its dem/ subfolder)")->capture_default_str();

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

  try {
    if (*bakeCmd) {
      bake.scene = scene;
      if (!terrainFile.empty()) bake.terrainFile = terrainFile;
      if (bakeCmd->count("--seed")) bake.seed = seed;
      if (bakeCmd->count("--threads")) bake.threads = threads;
      if (!backend.empty()) bake.backend = backend;
      bake.progress = !quiet;
      if (!cacheDir.empty()) bake.cacheDir = cacheDir;
      bake.useCache = !noCache;
      runBake(bake, std::cerr);
    } else if (*demoCmd) {
      BakeOptions demo;
      demo.outDir = demoOut;
      runBake(demo, std::cerr);
      std::cerr << "demo: outputs and manifest.json are in " << demoOut << "\n";
    } else if (*benchCmd) {
      if (!benchSizes.empty()) {
        benchOptions.scalingSizes.clear();
        std::stringstream list(benchSizes);
        for (std::string item; std::getline(list, item, ',');) {
          try {
            benchOptions.scalingSizes.push_back(std::stoi(item));
          } catch (const std::exception&) {
            throw InputError("--sizes: '" + item + "' is not a whole number");
          }
        }
      }
      std::cout << runBench(benchOptions, std::cerr);
    } else if (*infoCmd) {
      std::cout << describeTerrain(infoFile, infoJson, infoSets);
    } else if (*helpCmd) {
      std::cout << (helpMarkdown ? sceneReferenceMarkdown() : sceneReferenceText());
    }
  } catch (const InputError& e) {
    std::cerr << "snowbake: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "snowbake: failed: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
