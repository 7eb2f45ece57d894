// One avalanche on a SnowBackend (paper §6.1): release, steps of 0.1 s of simulated time until
// the snow is at rest, deposit. The model and its kernels are in phenomena/avalanches.h; this
// host side picks the release zone, the substep length and the active box, and keeps the records.
//
// Release (§6.1): at the rupture cell the unstable snow must be at least avalanche_min_unstable_m
// deep. The release zone is the connected unstable snow within a reach of
// avalanche_reach_m_per_m x U(rupture) metres of the rupture point. The unstable snow downslope
// is set moving as the avalanche reaches it: a cell that receives moving snow entrains its own
// unstable snow and powder (phenomena/avalanches.h). (Setting all downslope unstable snow moving
// at once, a literal reading of §6.1, released whole mountainsides after a storm: every slope above
// s_U holds some U.) Powder on moving cells joins the flow.
//
// Time step: each avalanche step is avalanche_step_s (0.1 s) of simulated time, cut into
// substeps of at most 0.2 sqrt(L_min / g): the pipe model's pressure waves have angular
// frequency up to about sqrt(16 g / L), so this keeps the explicit update well inside its
// stability limit for any terrain and snow depth; the outflow rescaling keeps every cell
// non-negative whatever the flows. Snow crosses at most one cell a substep, which is what lets
// the box grow by one cell a substep and no more. The shallow-water flow (season.avalanche_flow)
// takes more where the last step's fastest signal needs them (substepsOfStep).
//
// At rest: when no pipe carries more than avalanche_stop_speed_mps (flow / pipe cross-section)
// once the snow has moved faster than that or 2 s have passed (short steps would otherwise stop
// snow that has only begun to accelerate), when the flow's kinetic energy has fallen below
// avalanche_stop_energy_fraction of its peak (com1DFA's kind of stopping criterion), or after
// avalanche_max_duration_s of simulated time (reported), the moving snow is deposited as
// stable snow and the records are kept.
#pragma once
#include <algorithm>
#include <chrono>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "backend.h"
#include "parameters.h"

namespace snow {

// A crop of a grid: values for the cells [x0, x0 + grid.width()) x [y0, y0 + grid.height()).
struct GridCrop {
  int x0 = 0, y0 = 0;
  Grid<float> grid;
};

// On request: the avalanche's own maps (release zone 1/0, net scour and deposit in metres) and
// frames of its motion (snow depth C + S + U + P every frameIntervalS of simulated time), each
// cropped to where the avalanche was; `depthAtRelease` is the full grid they paste onto.
struct AvalancheMaps {
  GridCrop release, scour, deposit, peakThickness, peakSpeed;
  Grid<float> depthAtRelease;
  std::vector<std::pair<double, GridCrop>> frames;  // (simulated seconds, depth)
};

struct AvalancheRecord {
  double day = 0;
  int ruptureX = 0, ruptureY = 0;
  bool user = false;
  bool released = false;     // false: no unstable snow at the rupture point
  std::string why;           // why it did not release, or why it stopped
  int releaseCells = 0;      // cells set moving at release
  int footprintCells = 0;    // cells whose snow changed by more than 1 mm
  double releasedM3 = 0;     // unstable snow and powder set moving at release
  double depositM3 = 0;      // net gain summed over the cells that gained
  double runoutM = 0;        // horizontal distance from the rupture point to the farthest deposit (> 1 cm)
  double fallHeightM = 0;    // snow-surface altitude at the rupture point minus that of the lowest deposit
  double ruptureSlopeDeg = 0;  // the snow surface's steepest drop to an 8-neighbour at the rupture point
  int steps = 0, substeps = 0;
  double simulatedS = 0;     // simulated duration
  double seconds = 0;        // wall-clock time, release and deposit included
  double stepSeconds = 0;    // wall-clock time of the steps alone
  double secondsPerStep() const { return steps > 0 ? stepSeconds / steps : 0.0; }
  float maxSpeedMps = 0;     // fastest flow seen (the snow's speed; the pipes': flow / cross-section)
  int boxCellsMax = 0;       // the largest active box, in cells
  double boxCellSteps = 0;   // the active box's cells summed over the steps: the work the steps covered
  std::shared_ptr<AvalancheMaps> maps;  // when asked for (AvalancheRun::keepMaps)
};

class AvalancheRun {
 public:
  // `terrain` supplies the grid, bedrock, valid cells and release factors (the backend holds the
  // snow); the run reads them through a reference, so the state must outlive it.
  AvalancheRun(SnowBackend& backend, const ModelParameters& params, const SnowState& terrain);
  ~AvalancheRun();
  AvalancheRun(const AvalancheRun&) = delete;
  AvalancheRun& operator=(const AvalancheRun&) = delete;
  AvalancheRun(SnowBackend& backend, const ModelParameters& params, SnowState&& terrain) = delete;
  // It keeps a reference to the parameters: a temporary would dangle (AddressSanitizer found
  // three callers doing so: stack-use-after-scope).
  AvalancheRun(SnowBackend& backend, ModelParameters&& params, const SnowState& terrain) = delete;
  // Releases at cell (x, y) of the current backend state. Returns false (and says why in the
  // record) when there is no unstable snow to release there.
  bool release(int x, int y, double day, double seaLevelTemperatureC, bool user);
  // Releases every cell of `zone` (one byte per cell, a painted release zone) that holds at
  // least avalanche_min_unstable_m of unstable snow, as one avalanche; its rupture point (for
  // runout and fall height) is the zone's highest released cell. False when none holds any.
  bool releaseZone(const std::vector<uint8_t>& zone, double day, double seaLevelTemperatureC, bool user);
  // A spontaneous release (§6.1): the rupture cell drawn by `cellDraw` among the cells that can
  // release, each weighted by how unstable it is, min(1, U / 1 m x (s - tan theta_c) / (1 - tan theta_c))
  // (s the steepest drop of the snow surface to an 8-neighbour; U >= avalanche_min_unstable_m;
  // times the scene's avalanche_release multiplier): nothing releases below the rest angle, and
  // nothing at all where no cell can (false). Downloads the state unless only this runner's
  // avalanches have run since its last snapshot (then it weighs their rows again only); each row's
  // weights summed in order in double, then the rows, so the draw is the same on every backend
  // and thread count.
  bool trySpontaneous(double cellDraw, double day, double seaLevelTemperatureC);
  uint64_t snapshotsKept() const { return snapshotsKept_; }  // tries that found the snapshot kept
  // Frees the snapshot and the release flags between avalanches (a frame written while the season
  // waits): the next try downloads the state again. Nothing while an avalanche is in motion.
  void releaseScratch();
  bool active() const { return active_; }
  bool atRest() const { return atRest_; }
  // One step of avalanche_step_s. Returns true when the snow has come to rest (or the duration
  // cap is reached); then call settle().
  bool step();
  // Deposits the snow and fills the record.
  AvalancheRecord settle();
  // Steps until at rest, then settles; the record (also of a release that did not happen).
  AvalancheRecord runToRest();
  const AvalancheRecord& record() const { return record_; }
  // Keep each avalanche's maps, and frames of its motion every `frameIntervalS` simulated
  // seconds (0: no frames). Frames download the state: they cost O(grid) each.
  void keepMaps(bool maps, double frameIntervalS) {
    keepMaps_ = maps || frameIntervalS > 0.0;
    frameIntervalS_ = frameIntervalS;
  }
  // Off: every step's passes run over the whole box, not its rows' spans (the reference whose
  // bytes the spans must give: Avalanche.RowSpansGiveTheSameBytesAsTheWholeBox).
  void useRowSpans(bool on) { rowSpans_ = on; }
  // Off: the flow, scale and height passes keep to the source spans alone, not also the live
  // spans (AvalancheArgs::live; the tests compare them).
  void useLiveSpans(bool on) { liveSpans_ = on; }
  int liveSteps() const { return liveSteps_; }  // this avalanche's steps that used them

  // The spontaneous release weights of rows [y0, y1), width doubles a row, into w (public for
  // the tests, which check its AVX2 lanes against its per-cell loop).
  void releaseWeights(int y0, int y1, double* w) const;

 private:
  bool releaseFromSnapshot(int x, int y, double day, double seaLevelTemperatureC, bool user);
  // tan of the steepest drop of the snapshot's snow surface from (x, y) to a valid 8-neighbour.
  double steepestDrop(int x, int y) const;
  void beginRecord(int rx, int ry, double day, bool user);
  // The bounds of the cells a release sets moving (add() is called for each): start() scans them
  // instead of the grid, and they are the avalanche's first box.
  struct CellBox {
    int x0 = std::numeric_limits<int>::max(), y0 = std::numeric_limits<int>::max(), x1 = 0, y1 = 0;
    void add(int x, int y) {
      x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x + 1), y1 = std::max(y1, y + 1);
    }
  };
  // One byte a cell, 1 where a release sets snow moving; all zeros between releases (start()
  // clears its box), so a release does not make and zero a grid-sized flag array of its own.
  std::vector<uint8_t> moving_;
  std::vector<uint8_t>& movingCells();
  // Sets the cells of moving_ (all inside `released`) in motion from the snapshot (records, box,
  // substep arguments), then clears them.
  void start(const CellBox& released, double seaLevelTemperatureC, std::chrono::steady_clock::time_point t0);
  SnowBackend& backend_;
  bool rowSpans_ = true, liveSpans_ = true;
  const ModelParameters& p_;
  const SnowState& terrain_;
  // The snow layers a release reads (C, S, U, P over the grid): the backend's own fields where they
  // live in host memory (SnowBackend::hostSnowLayers), else snapshot_, a download kept while only
  // this runner's avalanches change the state.
  const float* layers_[4] = {};
  SnowBox snapshot_;
  double layersSurface(size_t i) const;  // A = B + C + S + U + P of layers_ at cell i, in double
  // The layers at release of every cell the avalanche may have changed (growBeforeBox takes them
  // from layers_ before the step that may reach them), and those of its box at its end or at a
  // frame: not whole copies of the state (they were 2 x 82 bytes a cell, then a 16-byte snapshot).
  SnowBox before_, after_;
  void growBeforeBox(int x0, int y0, int x1, int y1);
  // Running totals of the spontaneous release weights at each row's start (in place of one
  // double a cell): the draw rescans only the row it falls in.
  std::vector<double> rowStartWeights_;
  std::vector<double> rowWeights_;  // each row's weights summed in order
  std::vector<double> weights_;     // a band of rows' release weights
  void weighRows(int r0, int r1);
  // The snapshot kept between tries: while the backend's stateVersion is the one it was taken at,
  // only the avalanches since have changed the state, and settle() copies their boxes in.
  bool haveSnapshot_ = false;
  uint64_t snapshotsKept_ = 0;
  uint64_t snapshotVersion_ = 0;
  int staleY0_ = 0, staleY1_ = 0;  // the rows whose weights are out of date
  void keepSnapshotOfBox();
  // hypot of the offsets to the neighbour (dx, dy) in metres, at 3 (dy + 1) + dx + 1: steepestDrop's
  // divisors, the same doubles at every call.
  double neighbourDistanceM_[9] = {};
  void takeSnapshot();
  AvalancheArgs args_;
  AvalancheArgs unionBox_;
  // The live spans (AvalancheArgs::live): each set of row statistics' rows, and the first step
  // that may use them (two after the release or after anything else wrote the state).
  int statsY0_[2] = {0, 0}, statsY1_[2] = {0, 0};
  int liveFrom_ = 2, liveSteps_ = 0;
  uint64_t staticFieldsSeen_ = 0;  // the backend's staticFieldsVersion at release or the last change
  void onOutsideWrite();
  // A step's parts: its arguments (the substep and the spans the passes keep to), the box and
  // row statistics it returns taken in (the next box; the fastest pipe and kinetic energy), and
  // whether the avalanche is now at rest, and why.
  struct StepTotals {
    float speed = 0.f;
    double energy = 0.0;
    float signal = 0.f;  // the shallow water's fastest signal, 1/s
  };
  int substepsOfStep(double stepS) const;
  float lastSignal_ = 0.f;
  AvalancheArgs stepArgs(double stepS, int substeps);
  StepTotals takeStepStats(const std::vector<float>& stats, int statsOut);
  void checkRest(const StepTotals& totals);
  AvalancheRecord record_;
  bool active_ = false, atRest_ = false;
  float lastSpeed_ = 0.f;
  double peakEnergy_ = 0.0;  // the largest kinetic energy of a step (m^5/s^2: per unit density)
  bool keepMaps_ = false;
  double frameIntervalS_ = 0.0, nextFrameS_ = 0.0;
  void captureFrame();
  void downloadAfter(bool peaks);
  GridCrop boxDepth() const;
  double wallSeconds_ = 0;
};

}  // namespace snow
