// The season: the phenomena of the paper's §5 registered with the Poisson scheduler and run on
// a SnowBackend. Phenomena of later stages (wind transport, avalanches, skiers) plug in here.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "avalanche_runs.h"
#include "bedform_runs.h"
#include "backend.h"
#include "ski_runs.h"
#include "parameters.h"
#include "weather.h"

namespace snow {

// Skiers asked for in the scene: start cell, day, how many (they start together, one batch). With
// `startWeights` (one per cell, from a start mask), each skier's start cell is drawn from the
// weights instead (among cells with snow enough to ski).
struct UserSkier {
  double day = 0;
  int x = 0, y = 0;
  int count = 1;
  std::shared_ptr<const std::vector<float>> startWeights;
};

// An avalanche asked for in the scene: rupture cell and day, or with `zone` (one byte per cell,
// from a mask) a release of every unstable cell inside the zone.
struct UserAvalanche {
  double day = 0;
  int x = 0, y = 0;
  bool bySkier = false;  // set off by a skier (recorded as not a user release)
  std::shared_ptr<const std::vector<uint8_t>> zone;
};

// A timeline edit (phenomena/timeline_edits.h) on a given day; `weights` one per cell (null: 1 everywhere).
struct SeasonEdit {
  double day = 0;
  EditArgs args;
  std::shared_ptr<const std::vector<float>> weights;
  std::string label;  // for the log and the manifest
};

struct EditRecord {
  double day = 0;
  std::string label;
  double volumeM3 = 0;  // snow added (negative: removed)
};

struct SeasonConfig {
  double days = 120.0;
  uint64_t seed = 1;
  ModelParameters params;
  WeatherTimeline weather;
  std::vector<SnowfallPeriod> userSnowfalls;  // storms requested as user events
  std::vector<UserAvalanche> userAvalanches;  // avalanches requested as user events
  std::vector<UserSkier> userSkiers;          // skiers requested as user events
  std::vector<SeasonEdit> edits;              // timeline edits (art direction)
  SkiTracks* skiTracks = nullptr;             // the ski-track texture to draw into (null: no texture)
  bool avalancheMaps = false;                 // keep each avalanche's maps in its record
  double avalancheFrameIntervalS = 0.0;       // and frames of its motion (0: none)
  std::vector<double> frameDays;              // days at which to hand the state to onFrame
  // onFrame writes the frame before it returns and leaves the state as it was: the season waits,
  // frees its scratch and lends the backend's fields to its host state instead of copying them.
  // A frame whose instant falls inside an avalanche is copied, set aside on disk in spillFolder
  // (empty: the system's temporary folder) and written once the avalanche has settled.
  bool lendFrames = false;
  std::string spillFolder;
  // The record fields (scour, deposit, melt, avalanche peaks) the season keeps: the others are
  // freed at its start and never written, so neither the backend nor a frame holds them.
  SnowFieldSet recordFields = kAllRecordFields;
  // Per-day static fields: when set, called at the start of every season day (0, 1, 2, ...) to
  // refill the state's static fields for that day (temperature from that day's sun exposure,
  // the wind of that day); the backend's static fields are then replaced.
  std::function<void(int day, SnowState& state)> updateStaticFields;
  // Wind transport runs only when the season has wind (the static wind fields are non-zero).
  bool windTransport = false;
  // Wind bedforms (phenomena/bedforms.h), when set: over the whole terrain or, with
  // state.bedformMask, inside the mask; in their domain (cells whose snow bed is at most
  // max_slope_deg steep) they replace the layered wind transport and powder diffusion.
  std::optional<BedformParameters> bedforms;
  // The whole grid's terrain, static fields and art direction, when the season's state is one
  // rank's part of it (distributed/): the runners of avalanches, skiers and bedforms work on the
  // whole grid's cells, which the backend steps on a replica of the whole grid (null: the state's
  // own). The ski-track texture is then the whole grid's, faded by the backend's whole layers.
  const SnowState* eventTerrain = nullptr;
};

struct PhenomenonReport {
  std::string name;
  uint64_t starts = 0, steps = 0, stops = 0;
  uint64_t skippedSteps = 0;  // steps whose kernels were not needed (e.g. melt below freezing)
  std::string skippedWhy;     // for the log: why (the last reason given)
  double seconds = 0.0;
};

struct SeasonReport {
  std::vector<PhenomenonReport> phenomena;
  LayerTotals initial, final;
  double snowfallAddedM3 = 0.0;   // ledger, summed in double
  double meltRemovedM3 = 0.0;     // positive
  double editsNetM3 = 0.0;        // added by timeline edits (negative: removed)
  double noSnowRemovedM3 = 0.0;   // initial snow removed from no-snow cells at the start
  std::vector<EditRecord> edits;
  uint64_t events = 0;
  double seconds = 0.0;
  std::vector<AvalancheRecord> avalanches;  // every avalanche released, and every user release that could not be
  uint64_t avalancheTries = 0;              // spontaneous release tries (most find nothing to release)
  uint64_t avalancheTryCalls = 0;           // the tries with their retries at later state-change steps
  uint64_t avalancheSnapshotsKept = 0;      // calls that found the runner's snapshot kept (AvalancheRun::trySpontaneous)
  double avalancheTrySeconds = 0.0;         // wall time of the calls (within the avalanche's time)
  std::vector<SkierRecord> skiers;          // every skier's descent (path kept for user skiers only)
  int framesSetAside = 0;                   // frames whose instant fell inside an avalanche (SeasonConfig::lendFrames)
  // Wind bedforms: polling rounds run, slabs the wind lifted, slab moves of the repose
  // relaxation, steps without wind above the threshold (sintering only), and whether every
  // step ended with the domain at rest (within the repose angle).
  struct Bedforms {
    long long rounds = 0, slabsEroded = 0, slabsAvalanched = 0, calmSteps = 0, domainCells = 0;
    bool atRest = true;
  } bedforms;
  // |final - (initial + added - melted)| relative to the snow that passed through.
  double massBalanceRelativeError() const;
};

// The frame's state is the callee's: it may move from it (the frame writer keeps it while it writes).
using FrameCallback = std::function<void(double day, SnowState& state)>;
using ProgressCallback = std::function<void(double fraction)>;
// Each avalanche's record when it comes to rest (or fails to release), while the season runs.
// The record fields a season must keep for outputs that read `read` (a layer's records) and, with
// `avalancheMaps`, each avalanche's peak maps: the season peaks are made from the current
// avalanche's, and the current peaks' two fields are kept together.
SnowFieldSet recordFieldsToKeep(SnowFieldSet read, bool avalancheMaps);

using AvalancheCallback = std::function<void(const AvalancheRecord& avalanche)>;

// Runs the season on `backend`, starting from `state` (uploaded here), and leaves the final
// layers in `state`. Cells where state.noSnow is set are outside the snow domain for the whole
// season (their snow is removed at the start; no transport enters or leaves them); state and
// frames keep the terrain's own validCell. Frames are downloaded into a copy of `state` at each frame day.
SeasonReport runSeason(SnowBackend& backend, SnowState& state, const SeasonConfig& config,
                       const ProgressCallback& progress = {}, const FrameCallback& onFrame = {},
                       const AvalancheCallback& onAvalanche = {});

// k_t * A + k_i * I: the temperature less the sea-level T0 (paper §4.1).
inline float temperatureBaseC(const ModelParameters& p, float altitudeM, float exposureHours) {
  return static_cast<float>(p.lapseRateCPerM * altitudeM + p.sunWarmingCPerHour * exposureHours);
}

// Fills temperatureBaseC from the bedrock and the exposure (T = T0 + base).
void computeTemperatureBase(SnowState& state, const ModelParameters& params);

// The snow of the valid cells state.noSnow marks, removed; returns its volume (m^3), summed in
// row order (the season's SeasonReport::noSnowRemovedM3).
double removeSnowOfNoSnowCells(SnowState& state);
// The cells state.noSnow marks, outside the snow domain from here on: their validity cleared.
void leaveNoSnowCellsOutside(SnowState& state);

// Whether a frame day is handed to onFrame: within the season, its start (0) and end included.
inline bool frameDayInSeason(double day, double seasonDays) { return day >= 0.0 && day <= seasonDays; }

}  // namespace snow
