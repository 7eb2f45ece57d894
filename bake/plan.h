// `snowbake plan`: what a bake would do, before it does it: the scene validated and resolved, the
// files it would write (listed by the bake's own writers in plan mode, OutputSources::plan), the
// stages it would run or skip and why, the memory model's peak (memory_model.h) and a rough time
// class. It reads the scene, the terrain (its size and NODATA cells decide the outputs) and the
// occluder meshes; it computes no precompute, no season and writes nothing.
#pragma once
#include <ostream>
#include <string>
#include <vector>

#include "bake.h"
#include "bakers/output_sink.h"
#include "memory_model.h"

namespace snow {

struct PlannedStage {
  std::string name;
  bool runs = true;
  std::string why;  // what it does, or why it is skipped ("no wind in the season")
};

struct BakePlan {
  std::string scene, sceneName, mode, outDir;
  int width = 0, height = 0;  // the grid (0 in mode = "mesh")
  size_t triangles = 0;       // mode = "mesh": the input mesh's
  double days = 0;
  std::vector<PlannedStage> stages;
  std::vector<PlannedFile> files;
  MemoryPrediction memory;
  double budgetBytes = 0;
  std::string timeClass;  // "seconds", "tens of seconds", "minutes", "hours": from the work (cells x days), rough
  double work = 0;        // what the time class is read from: cell-days (season), cells (occlusion), launch sites (mesh)
};

// Throws InputError (exit status 2) for what the bake would refuse before any work.
BakePlan planBake(const BakeOptions& options);
std::string planToJson(const BakePlan& plan);
void printPlan(const BakePlan& plan, std::ostream& out);

}  // namespace snow
