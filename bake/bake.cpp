// runBake: the scene, then the mode's driver (modes.h) over the stages (stages.h).
#include "bake.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <iostream>

#include "memory_trace.h"
#include "modes.h"
#include "progress.h"

#ifndef SNOWBAKE_VERSION
#define SNOWBAKE_VERSION "0.0.0"
#endif

namespace snow {

const char* programVersion() { return SNOWBAKE_VERSION; }

BakeResult runBake(const BakeOptions& options, std::ostream& log) {
  const auto tStart = WallClock::now();
  HumanProgress human(log, stderrIsTerminal() && &log == &std::cerr, options.progress);
  const ProgressScope progressScope(options.progressSink ? *options.progressSink : human);
  progress().stage("scene", 0.0);
  const Scene scene = resolveScene(options);
  progress().stage("scene", 1.0);
  const int threads = scene.threads > 0 ? scene.threads : tbb::info::default_concurrency();
  tbb::global_control threadLimit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  log << "snowbake " << programVersion() << ": scene " << scene.sourceName << " (" << scene.name << "), seed " << scene.seed << ", "
      << threads << " thread" << (threads == 1 ? "" : "s") << "\n";
  resetStageMemory();  // the stages' memory of this bake, for the peak's stage (memory_trace.h)
  if (scene.mode == SceneMode::Mesh) return runMeshBake(scene, options, log, tStart);
  return runGridBake(scene, options, threads, log, tStart);
}

}  // namespace snow
