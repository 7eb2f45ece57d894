// The season's view of a compute backend: one group of virtuals per phenomenon (core/phenomena/,
// one module header each, says what it models). The CPU backend (TBB, core/cpu_backend.cpp) and
// the CUDA backend (cuda/) both implement it with ExecBackend<Exec> (core/exec_backend.h), which
// runs each module's runX over the backend's forEachCell and fixed-order reductions.
// This header is plain C++ so that host code never needs CUDA headers.
#pragma once
#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include <vector>

#include "phenomena/avalanches.h"
#include "phenomena/bedforms.h"
#include "phenomena/melt.h"
#include "phenomena/powder_diffusion.h"
#include "phenomena/skiers.h"
#include "phenomena/snowfall.h"
#include "phenomena/stability_change.h"
#include "phenomena/timeline_edits.h"
#include "phenomena/wind_transport.h"
#include "snow_state.h"

namespace snow {

// Totals in cubic metres of snow, summed in double in a fixed order (identical for any thread
// count and on both backends).
struct LayerTotals {
  double compactedM3 = 0, stableM3 = 0, unstableM3 = 0, powderM3 = 0;
  double totalM3() const { return compactedM3 + stableM3 + unstableM3 + powderM3; }
};

class SnowBackend {
 public:
  virtual ~SnowBackend() = default;
  virtual std::string name() const = 0;

  // Copies the whole state (layers and static fields) in.
  virtual void upload(const SnowState& state) = 0;
  // Copies the evolving fields (snow layers and the moving flag) out.
  virtual void download(SnowState& state) = 0;
  // The season's first upload and last download, handing the fields it downloads over instead
  // of copying them (the season's start and end held the state twice): uploadTaking leaves the
  // host's grids of those fields empty; downloadGiving fills them and leaves the backend without
  // them, so it must be uploaded again before its next step.
  virtual void uploadTaking(SnowState& state) {
    upload(state);
    state.releaseFields(downloadedWithState);
  }
  virtual void downloadGiving(SnowState& state) {
    state.restoreFields(downloadedWithState);  // uploadTaking left them without a size
    download(state);
  }
  // A frame written while the season waits (SeasonConfig::lendFrames): downloadGiving lends the
  // fields to the host's state, returnState takes them back as they were; nothing else of the
  // backend changes in between.
  virtual void returnState(SnowState& state) = 0;
  // Where the snow layers live in host memory: C, S, U, P's own storage (read only, valid until the
  // stateVersion changes), so the avalanche runner reads them in place of a snapshot. False on a
  // device.
  virtual bool hostSnowLayers(const float* layers[4]) {
    (void)layers;
    return false;
  }
  // A field's own storage in host memory (the field table's element type, width × height of
  // them), where a halo exchange between ranks reads and writes it in place (distributed/). Null
  // on a device, for a field the backend does not hold, or one absent this season.
  virtual void* hostField(SnowField field) {
    (void)field;
    return nullptr;
  }
  // The same for a scratch field (snow_fields.h), while the backend holds it: the last step's
  // `delta`, which a distributed run sums over the cells each rank owns.
  virtual void* hostScratch(ScratchField field) {
    (void)field;
    return nullptr;
  }
  // Calls `f` once, before the next kernel that may write the snow layers (any but the
  // avalanche's); an empty `f` cancels. Fixed-time actions (a user's skiers, a timeline edit, a
  // storm's edge) run even while an avalanche is in motion: the avalanche runner keeps the layers
  // at release of the cells it has not reached before they change.
  void beforeNextWrite(std::function<void()> f) { beforeWrite_ = std::move(f); }
  // The skiers' storage freed and the route map forgotten (its owner, SkiRun, is gone).
  virtual void releaseRouteMap() {}
  // Frees the scratch that no step holds between events: the fields made with the state, the
  // skiers' storage (uploadRouteMap again before the next batch) and, with `avalancheFields`
  // (no avalanche in motion), the avalanche's, made again at the next release.
  virtual void releaseScratch(bool avalancheFields) { (void)avalancheFields; }
  // Host work of the runners cut into independent chunks [a, b) of [0, n) (the spontaneous
  // release weights, band by band): on the backend's host threads where it has them, else in
  // order. Each chunk writes only its own output, so the result is the same on any split.
  virtual void forEachHostChunk(int n, int chunk, const std::function<void(int, int)>& f) {
    for (int a = 0; a < n; a += chunk) f(a, std::min(n, a + chunk));
  }
  // Counts the calls that may have changed the snow layers, but the avalanche's own (release,
  // steps, settle): while it stays the same, the avalanche runner's snapshot needs only the boxes
  // of its own avalanches (AvalancheRun::trySpontaneous).
  virtual uint64_t stateVersion() const = 0;
  // Replaces the static fields (exposure, temperature base, wind) only.
  virtual void uploadStaticFields(const SnowState& state) = 0;
  // Counts the uploads of static fields (a day's temperature may come while an avalanche runs:
  // its friction reads the temperature, AvalancheRun's live spans watch this).
  uint64_t staticFieldsVersion() const { return staticFieldsVersion_; }

  // Each step returns the snow volume it added (positive) or removed (negative), in m^3.
  virtual double snowfall(const SnowfallArgs& args) = 0;
  virtual double melt(const MeltArgs& args) = 0;
  // Transport: conserves mass; runs its own substeps (see powderDiffusionSubsteps).
  virtual void powderDiffusion(const PowderDiffusionArgs& args) = 0;
  // Called after each of powder diffusion's substeps, when set (a distributed run refreshes the
  // powder's halo there); never changes a result.
  void afterEachPowderSubstep(std::function<void()> f) { afterPowderSubstep_ = std::move(f); }
  virtual void windTransport(const WindTransportArgs& args) = 0;  // conserves mass
  // Moves snow between the stable and unstable layers (conserves mass).
  virtual void stabilityChange(const StabilityArgs& args) = 0;

  // A timeline edit (phenomena/timeline_edits.h) weighted per cell by `weights` (one per cell, row order;
  // empty: 1 everywhere); returns the snow volume it added (negative: removed), in m^3.
  virtual double applyEdit(const EditArgs& args, const std::vector<float>& weights) = 0;

  virtual LayerTotals totals() = 0;
  // Highest temperature (degC) of any valid cell for a sea-level temperature of 0: lets the
  // season skip melt kernels on days when no cell can melt.
  virtual float maxTemperatureBaseC() = 0;

  // The snow depth (C + S + U + P) and U of cells in rows y0..y0+rows-1, columns x0..x0+cols-1
  // (clipped to the grid by the caller), row after row: a cheap look at a few cells.
  virtual void readCells(int x0, int y0, int cols, int rows, std::vector<float>& depth, std::vector<float>& unstable) = 0;

  // The snow layers (and with `peaks` the current avalanche's peak thickness and speed) of the box
  // box.x0, box.y0, box.width x box.height (clipped to the grid by the caller) into `box`.
  virtual void downloadBox(SnowBox& box, bool peaks) = 0;

  // Wind bedforms (phenomena/bedforms.h): `args.rounds` polling rounds over the cells of the domain
  // (valid, inside state.bedformMask when it is set, bed slope within args.tanMaxSlope); conserves
  // mass (whole slabs). The cohesion field persists from step to step (0 at upload).
  virtual BedformStepReport bedformStep(const BedformArgs& args) = 0;
  // The bedform cohesion per cell (false, and `out` untouched, before the first bedform step).
  virtual bool bedformCohesion(Grid<float>& out) = 0;
  // The bedform domain of the last step (one byte a cell, 1 where the bedform model runs, which
  // wind transport and powder diffusion leave): false, and `out` untouched, before the first
  // bedform step. A backend that runs no bedform step reads the one given to it instead (a rank's
  // local grid, cut from the whole grid's replica; empty: none), until its next upload.
  virtual bool bedformDomain(std::vector<uint8_t>& out) {
    (void)out;
    return false;
  }
  virtual void useBedformDomain(const std::vector<uint8_t>& domain) { (void)domain; }

  // Skiers (core/ski_runs.h). The route map of the bedrock by the cellular automaton
  // (RouteMapStepKernel) on the backend's device; false on host backends, where a one-pass sort
  // over the cells gives the same bytes faster.
  virtual bool routeMapOnDevice(Grid<float>& out) {
    (void)out;
    return false;
  }
  // The route map the skier kernels read (phenomena/skiers.h); before the first skierBatch. A host
  // backend reads `route` itself: it must outlive the batches (SkiRun's own).
  virtual void uploadRouteMap(const Grid<float>& route) = 0;
  // A batch of skiers moved together, one move of every skier at a time, until all have stopped
  // (phenomena/skiers.h): in, each agent's startCell and id; out, their final state, and in `paths`
  // each one's large-scale path as x, y pairs (metres). Each cell a skier enters (its start cell
  // too) turns args.compactionM of U into S, or of S into C where U runs short (conserves mass).
  virtual void skierBatch(const SkierArgs& args, std::vector<SkierAgent>& agents, std::vector<std::vector<double>>& paths) = 0;

  // Avalanches (phenomena/avalanches.h; the host loop is core/avalanche_runs.h). Release: `moving` (one
  // byte per cell) marks the released cells, all inside `box` ([x0, x1) x [y0, y1)); records U + P
  // and joins their powder to U.
  virtual void avalancheRelease(const std::vector<uint8_t>& moving, const AvalancheArgs& box) = 0;
  // `substeps` substeps of args.dtS, the box dilated by one cell before each (snow moves at most
  // one cell a substep), then per-row statistics of the final box: 4 floats per row y0..y1-1
  // (fastest pipe m/s, deepest moving snow m, first and last column holding moving snow or -1).
  virtual std::vector<float> avalancheSteps(const AvalancheArgs& args, int substeps) = 0;
  // Deposits the moving snow in the box and adds the scour and deposit records.
  virtual void avalancheSettle(const AvalancheArgs& box) = 0;
 protected:
  void fireBeforeWrite() {
    if (!beforeWrite_) return;
    const std::function<void()> f = std::move(beforeWrite_);
    beforeWrite_ = nullptr;
    f();
  }

  std::function<void()> afterPowderSubstep_;
  void staticFieldsUploaded() { ++staticFieldsVersion_; }

 private:
  std::function<void()> beforeWrite_;
  uint64_t staticFieldsVersion_ = 0;
};

}  // namespace snow
