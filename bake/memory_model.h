// The bake's peak memory, predicted from the resolved scene before any work (docs/memory.md): a
// table of owners (the state, the backend's copies, exposure samples, frames in flight, the
// ski-track texture, the VDB, ...), grouped by the phase of the bake that holds them at once.
// The peak is the largest phase plus the libraries. runBake refuses a scene whose peak is above
// the budget (run.max_memory_gb, default 80 % of MemAvailable), naming the owner that needs the
// most and the key that sizes it; tools/measure-memory.sh checks the prediction against the
// measured peak resident set.
#pragma once
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/grid.h"
#include "frame_timing.h"
#include "memory_vdb.h"
#include "scene/scene.h"

namespace snow {

// The groups of the breakdown that `bake --verbose` prints and the manifest's "memory" line holds
// (memoryGroups(): their names and what each holds); every owner belongs to one.
enum class MemoryGroup : uint8_t {
  State, StaticFields, ExposureSamples, WindFields, Scratch, Records, Writers, FramesInFlight, PrecomputeWork
};
struct MemoryGroupInfo {
  MemoryGroup group;
  const char* name;  // as printed and in the manifest: "state", "static fields", ...
  const char* holds;
};
const std::vector<MemoryGroupInfo>& memoryGroups();
const char* memoryGroupName(MemoryGroup g);

struct MemoryOwner {
  std::string name;   // "snow state", "ski-track texture", ...
  double bytes = 0;
  std::string key;    // the scene key that sizes it most ("" where it is the grid itself)
  MemoryGroup group = MemoryGroup::State;
};

struct MemoryPhase {
  std::string name;   // "precompute", "season", "outputs", ...
  std::vector<MemoryOwner> owners;
  double bytes() const;
  const MemoryOwner& largest() const;
};

struct MemoryPrediction {
  double libraryBytes = 0;  // the program and its libraries, resident before the bake allocates
  std::vector<MemoryPhase> phases;
  const MemoryPhase& peakPhase() const;
  double peakBytes() const { return libraryBytes + peakPhase().bytes(); }
  // One line: the peak, its phase and its three largest owners.
  std::string summary() const;
  // The peak phase's bytes by group (memoryGroups() order; the libraries not included).
  std::vector<std::pair<MemoryGroup, double>> peakByGroup() const;
};

// The breakdown against the measured peak (VmHWM) and the stage it came in: the lines `bake
// --verbose` prints, and the manifest's one-line JSON object ("memory"). `units`: the grid's cells
// (`unit` "cell"), or mesh mode's launch sites ("site"), the count the bytes are shown per.
std::string memoryBreakdownText(const MemoryPrediction& p, double measuredPeakBytes, const std::string& peakStage, double units,
                                const std::string& unit = "cell");
std::string memoryBreakdownJson(const MemoryPrediction& p, double measuredPeakBytes, const std::string& peakStage, double units,
                                const std::string& unit = "cell");
// Both against the process's peak so far and the stage it was reached by (memory_trace.h): the
// lines written to `log` when `verbose`; the manifest's object returned.
std::string measuredMemoryBreakdown(const MemoryPrediction& p, double units, const std::string& unit, bool verbose, std::ostream& log);

// What a grid bake (mode = "season" or "occlusion") holds on a grid of `spec`, with
// `occluderTriangles` triangles of occluder meshes; `reach` (the terrain's heights against the
// rain-snow limit) sizes the VDB by the snow expected on its day, unknown: every column snowed.
// `timing`: when the frame days' outputs are written (frame_timing.h; Auto: as the scene's
// run.frame_writing asks).
MemoryPrediction predictGridBake(const Scene& scene, const GridSpec& spec, size_t occluderTriangles, const SnowReach& reach = {},
                                 FrameTiming timing = FrameTiming::Auto);
// The FrameTiming of the scene's run.frame_writing.
FrameTiming frameTimingOf(const Scene& scene);
// The prediction a grid bake runs by, and when its frames are written: `timing` as asked, or for
// FrameTiming::Auto as the scene asks unless that passes `budgetBytes` and another way does not
// (paused, then after the season).
struct GridMemoryPlan {
  MemoryPrediction prediction;
  FrameTiming timing = FrameTiming::Paused;
  double askedBytes = 0;  // the peak the way the scene asked (when another was chosen)
};
GridMemoryPlan planGridMemory(const Scene& scene, const GridSpec& spec, size_t occluderTriangles, const SnowReach& reach,
                              double budgetBytes, FrameTiming timing);
// mode = "mesh": the lattice and the snow body over a mesh of `triangles` triangles whose
// bounding box is `extentM` (x, y, z).
MemoryPrediction predictMeshBake(const Scene& scene, size_t triangles, const double extentM[3]);

// The budget: run.max_memory_gb, else 80 % of /proc/meminfo's MemAvailable.
double memoryBudgetBytes(const Scene& scene);
// Throws InputError when the prediction is above the budget: what needs the memory (the phase
// and its largest owner, with the key where the scene sets it) and what to change.
void refuseAboveBudget(const Scene& scene, const MemoryPrediction& prediction, double budgetBytes);

// A bake across ranks (docs/distributed.md): the peak each rank on this machine is predicted to
// hold (rank 0 writes the whole grid's outputs; the others hold their local grid), and their sum,
// which the machine's memory holds at once.
struct RanksMemory {
  int ranks = 1;             // of the launch
  int ranksHere = 1;         // on this machine
  bool rankZeroHere = true;  // rank 0 is one of them
  bool rankZeroGathers = true;  // rank 0 writes the whole grid's outputs (not each rank its tiles)
  std::string rankZeroHolds;    // what rank 0 holds beyond the others, for the refusal (empty: nothing)
  double rankZeroBytes = 0, otherBytes = 0;
  double hereBytes() const { return rankZeroHere ? rankZeroBytes + (ranksHere - 1) * otherBytes : ranksHere * otherBytes; }
};
// Throws InputError when this machine's ranks together pass the budget: their count, each one's
// peak, the key that sizes rank 0's largest owner, and what to change (fewer ranks a machine).
void refuseRanksAboveBudget(const Scene& scene, const MemoryPrediction& rankZero, const RanksMemory& ranks, double budgetBytes);
// Where each rank writes its tiles and the outputs have whole files (no [outputs.tiles], or those
// of outputs.tiles.resize beside the tiles): what rank 0 holds beside its local grid to write them,
// one at a time, each gathered from the ranks (the one-process writers' owners of those files on
// the whole grid's `cells`, and a layer's cells with their mask gathered).
double wholeFilesOnRankZeroBytes(const Scene& scene, double cells);
// Across ranks: what each rank holds of the skiers' layers beyond its local grid's share of them
// (a rank's bake is predicted on its local grid): every rank keeps the whole grid's ski-track
// texture (with the layer made from it and their copies at once) and makes the whole route map
// before it cuts its window.
double wholeSkiLayersBeyondLocalBytes(const Scene& scene, double wholeCells, double localCells);

// Sizes the model cannot hold whatever the memory (coordinates past OpenVDB's 32-bit range, a
// displacement map or ski-track texture of more than 2^31 pixels): InputError naming the key.
void refuseBeyondTheModel(const Scene& scene, const GridSpec& spec);

}  // namespace snow
