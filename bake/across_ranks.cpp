#include "across_ranks.h"

#include <algorithm>
#include <functional>
#include <optional>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "core/cpu_backend.h"
#include "core/errors.h"
#include "core/format.h"
#include "core/grid_window.h"
#include "core/release_memory.h"
#include "core/stop_request.h"
#include "distributed/communicator.h"
#include "distributed/continuous_step.h"
#include "distributed/decomposition.h"
#include "distributed/distributed_backend.h"
#include "distributed/launch.h"
#include "distributed/local_state.h"
#include "distributed/wind_across_ranks.h"
#include "distributed/whole_replica.h"
#include "memory_model.h"
#include "frame_writer.h"
#include "memory_trace.h"
#include "progress.h"
#include "scene/layers.h"
#include "stages.h"
#include "tiles_on_ranks.h"

namespace snow {

namespace {

// Set while the launch's MPI is up for a bake, and while the ranks exchange (the wind's solve, the
// season: a failure then ends every rank at once, the others waiting in an exchange).
bool acrossRanks = false;
bool inExchanges = false;

bool seasonAgreed = false;  // the ranks have agreed at the season's start, the last agreement

// The season's peak resident memory per rank, in a window of its own (memory_trace.h).
bool peakWindows = false;
double seasonPeakBytes = 0.0;

// Another rank failed before the season: this one ends with its status, having said nothing.
struct OtherRankFailed {
  int status;
};

// An agreement before the ranks exchange (each wind state's cache read and solve on the local
// grids, the season's start): every rank's status (0: fine), in rank order. A rank that failed
// joins the next one from runBakeAcrossRanks, where every other rank ends.
std::vector<double> agreedStatuses(const dist::Communicator& comm, int status, bool seasonStart) {
  seasonAgreed = seasonAgreed || seasonStart;
  return comm.allGather({static_cast<double>(status)});
}
void agreeBeforeExchanges(const dist::Communicator& comm, bool seasonStart) {
  const std::vector<double> statuses = agreedStatuses(comm, 0, seasonStart);
  if (const double worst = *std::max_element(statuses.begin(), statuses.end()); worst != 0) throw OtherRankFailed{static_cast<int>(worst)};
}
// inExchanges for a scope; still set when a failure leaves it (the others wait in an exchange).
struct Exchanging {
  int failing = std::uncaught_exceptions();
  Exchanging() { inExchanges = true; }
  ~Exchanging() {
    if (std::uncaught_exceptions() == failing) inExchanges = false;
  }
};

// A grid of the rank's local grid made the whole grid's on every rank: its owned cells gathered
// from every rank.
Grid<float> wholeOnEveryRank(const dist::Communicator& comm, const dist::Decomposition& d, const Grid<float>& local, const GridSpec& spec) {
  if (local.empty()) return Grid<float>();
  Grid<float> out(spec.width, spec.height);
  dist::allGatherOwned(comm, d, local.data(), out.data(), sizeof(float));
  return out;
}

// The whole grid's exposure on every rank from each rank's of its local grid: each sample grid's
// owned cells gathered from every rank (a grid folding freed is freed on every rank alike).
Exposure wholeExposureOnEveryRank(const dist::Communicator& comm, const dist::Decomposition& d, const Exposure& share, const GridSpec& spec) {
  Exposure whole;
  whole.timings = share.timings;
  whole.folded = share.folded;
  auto gathered = [&](const Grid<float>& g) { return wholeOnEveryRank(comm, d, g, spec); };
  whole.skyHours = gathered(share.skyHours);
  for (const DailyExposure& day : share.days)
    whole.days.push_back({day.seasonDay, day.dayOfYear, gathered(day.sunHours), gathered(day.indirectHours)});
  return whole;
}

// The wind on a rank's local grid, its solve exchanging with the other ranks' (each rank solves
// the same states in the same order).
WindPart windPartOn(const dist::Communicator& comm, const dist::Decomposition& d, const dist::CellRect& cells) {
  return WindPart{cells,
                  [comm, d](const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& s, const WindState& state,
                            const ModelParameters& p, const WindSolverOptions& o, WindField& f, Grid<float>& loading) {
                    agreeBeforeExchanges(comm, false);
                    const Exchanging exchanging;
                    return dist::solveWindOnLocalGrid(comm, d, altitude, valid, s, state, p, o, f, loading);
                  },
                  [comm](bool found) {  // after the failures' agreement, as a solve: a rank that failed joins that
                    agreeBeforeExchanges(comm, false);
                    const std::vector<double> all = comm.allGather({found ? 1.0 : 0.0});
                    return std::all_of(all.begin(), all.end(), [](double f) { return f == 1.0; });
                  }};
}

}  // namespace

std::string acrossRanksRefusal(const Scene& s) {
  auto at = [&](const std::string& key, const std::string& what) {
    return s.keyLocation(key) + ": " + what + ": a bake across ranks does not run it yet (docs/distributed.md)";
  };
  if (s.mode != SceneMode::Season) return at("mode", "mode = \"" + std::string(s.mode == SceneMode::Occlusion ? "occlusion" : "mesh") + "\"");
  if (s.backend == BackendChoice::Cuda) return at("run.backend", "run.backend = \"cuda\"");
  return "";
}

bool bakingAcrossRanks() { return acrossRanks; }
bool writesOutputs() { return !acrossRanks || dist::Communicator::world().rank() == 0; }

namespace {
// The launch's ranks' split of `spec`'s grid (std::invalid_argument where it cannot be split):
// cut on the tiles' starts where the ranks write their own tiles (tiles_on_ranks.h).
dist::Decomposition decompositionOf(const Scene& scene, const GridSpec& spec) {
  const int ranks = dist::Communicator::world().size();
  if (std::optional<dist::Decomposition> onTiles = decompositionOnTiles(scene, spec, ranks, dist::kContinuousHalo)) return *onTiles;
  return dist::Decomposition::choose(ranks, spec.width, spec.height, dist::kContinuousHalo);
}
}  // namespace

void checkRanksSuitTheGrid(const Scene& scene, const GridSpec& spec) {
  if (!acrossRanks) return;
  try {
    decompositionOf(scene, spec);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("the terrain's grid cannot be baked across ranks: ") + e.what() + " (run fewer ranks)");
  }
}

namespace {

// Each day's static fields filled on the whole grid (on a state lent the terrain alone), then cut
// to the rank's and to the whole state the replica's runners read: the fields the fill makes, and
// no others, as the single process's state has.
std::function<void(int, SnowState&)> wholeThenCutFill(std::function<void(int, SnowState&)> fill, SnowState& whole, dist::CellRect cells) {
  return [fill = std::move(fill), &whole, cells](int day, SnowState& s) {
    SnowState filled;
    filled.spec = whole.spec;
    auto lend = [&] { std::swap(filled.bedrockM, whole.bedrockM), std::swap(filled.validCell, whole.validCell); };
    lend();
    try {
      fill(day, filled);
    } catch (...) {
      lend();
      throw;
    }
    lend();
    auto isStatic = [](FieldRole r) { return r == FieldRole::Static; };
    dist::cutFields(filled, cells, isStatic, s);
    dist::cutFields(filled, dist::CellRect{0, 0, whole.spec.width, whole.spec.height}, isStatic, whole);
  };
}

// Without a replica: each day's static fields filled on the rank's local grid from its own cells
// of the precompute, `mine` (the fill makeSeasonConfig makes, dailyStaticFill: each cell's
// temperature and wind are its own, so the bytes are the whole grid's): a part the precompute
// made on the local grid as it is, a whole grid's cut. The whole grid's precompute is freed, but
// on rank 0 where its layers read it. Returns the precompute that holds the rank's cells: `mine`,
// or `pre` where it is the rank's parts alone.
Precomputed& fillFromOwnCells(Precomputed& pre, Precomputed& mine, dist::CellRect cells, const ModelParameters& params, bool keepWhole,
                      uint8_t outputNeeds, SeasonConfig& config) {
  if ((!pre.exposure || pre.exposure->cells == cells) && (!pre.wind || pre.wind->cells() == cells)) {
    config.updateStaticFields = dailyStaticFill(pre, params);  // the precompute is the rank's part alone
    return pre;
  }
  if (pre.exposure)
    mine.exposure = pre.exposure->cells == cells ? *pre.exposure : pre.exposure->window(cells.x0, cells.y0, cells.width(), cells.height());
  if (pre.wind) mine.wind = pre.wind->cells() == cells ? *pre.wind : pre.wind->window(cells.x0, cells.y0, cells.width(), cells.height());
  config.updateStaticFields = dailyStaticFill(mine, params);
  if (pre.exposure && !(keepWhole && (outputNeeds & kNeedsSun))) pre.exposure->release();
  if (pre.wind && !(keepWhole && (outputNeeds & kNeedsWind))) pre.wind->releaseFields();
  return mine;
}

// Whether the season runs on the replica (dist::seasonNeedsReplica of the config makeSeasonConfig
// will make), before the terrain is read: the scene's events (art direction's masked ones among
// them; a mask that starts none leaves the season without a replica, which this still counts),
// its bedforms.
bool seasonOnReplica(const Scene& scene) {
  SeasonConfig c;
  c.params = scene.params;
  for (const Scene::AvalancheEvent& a : scene.userAvalanches) c.userAvalanches.push_back({a.day, 0, 0, false, nullptr});
  for (const Scene::AvalancheEvent& a : scene.userSkiers) c.userSkiers.push_back({a.day, 0, 0, a.count, nullptr});
  if (scene.bedforms.enabled) c.bedforms = scene.bedforms.params;
  return dist::seasonNeedsReplica(c);
}

// Bytes a cell of the initial state rank 0 keeps on the whole grid until the season for a no-snow
// mask (initialStateCells): the terrain's and the snow's fields (initialState), the mask and the
// multipliers' factors.
double initialStateBytesPerCell(const Scene& scene) {
  double bytes = sizeof(uint8_t);  // the no-snow mask
#define SNOW_INITIAL_BYTES(member, view, Element, role, access, fill) \
  if (FieldRole::role == FieldRole::Terrain || FieldRole::role == FieldRole::Evolved) bytes += sizeof(Element);
  SNOW_STATE_FIELDS(SNOW_INITIAL_BYTES)
#undef SNOW_INITIAL_BYTES
  return bytes + sizeof(float) * scene.multipliers.factorCount();
}

// Bytes a cell of the whole grid art direction holds on every rank (prepareArtDirection): each
// raster use placed on the whole grid and held until it is done (a raster used twice counted
// twice: an upper bound), and the masked edits' weights, held through the season.
double artDirectionBytesPerCell(const Scene& scene) {
  size_t rasters = 0;
  for (const InitialSnowLayer& l : scene.initialSnow)
    rasters += l.kind == InitialSnowLayer::Kind::Raster || l.kind == InitialSnowLayer::Kind::Mask;
  const Multipliers& m = scene.multipliers;
  rasters += m.factorCount() + m.noSnow.has_value();
  for (const EditSpec& e : scene.edits) rasters += 2 * e.mask.has_value();  // placed, and its weights kept
  return sizeof(float) * static_cast<double>(rasters) + (m.noSnow ? sizeof(uint8_t) : 0);  // the no-snow mask thresholded whole
}

// The season's own peak resident memory per rank, below the precompute's: a window of the
// kernel's count from its start (startSeasonPeak) to its end, then one for what follows.
void startSeasonPeak() {
  releaseFreedMemory();
  peakWindows = startPeakWindow();
}
void endSeasonPeak() {
  if (!peakWindows) return;
  seasonPeakBytes = peakInWindow();
  releaseFreedMemory();
  startPeakWindow();  // what follows: rank 0's outputs
}

}  // namespace

std::optional<RanksMemory> ranksMemory(const Scene& scene, const GridSpec& whole, const MemoryPrediction& onWhole,
                                       const std::function<MemoryPrediction(const Scene&, const GridSpec&)>& predictOn) {
  if (!acrossRanks) return std::nullopt;
  const dist::Communicator comm = dist::Communicator::world();
  dist::Decomposition d;
  try {
    d = decompositionOf(scene, whole);
  } catch (const std::invalid_argument&) {
    return std::nullopt;  // checkRanksSuitTheGrid says why
  }
  GridSpec local = whole;  // the largest of the ranks' local grids; the widest and highest subdomain
  int ownedWidth = 0, ownedHeight = 0;
  for (int r = 0; r < d.ranks(); ++r) {
    if (d.local(r).cells() > local.cellCount() || r == 0) local.width = d.local(r).width(), local.height = d.local(r).height();
    ownedWidth = std::max(ownedWidth, d.owned(r).width()), ownedHeight = std::max(ownedHeight, d.owned(r).height());
  }
  // Where each rank writes its tiles, its resampled images are its tiles' window of the image.
  const MemoryPrediction onLocal =
      predictOn(ranksWriteTheirTiles(scene, whole) ? sceneOfTheRanksTiles(scene, whole, ownedWidth, ownedHeight) : scene, local);
  const double libraries = onWhole.libraryBytes, localAbove = onLocal.peakBytes() - onLocal.libraryBytes;
  const double cells = static_cast<double>(whole.cellCount());
  const double terrain = (sizeof(float) + sizeof(uint8_t)) * cells;  // the whole terrain's heights and validity, every rank
  RanksMemory m;
  m.ranks = comm.size();
  m.ranksHere = dist::Communicator::node().ranks;
  m.rankZeroHere = dist::Communicator::node().holdsRankZero;
  if (seasonOnReplica(scene)) {  // every rank: the whole grid's bake beside its local grid's backend
    m.rankZeroBytes = m.otherBytes = onWhole.peakBytes() + localAbove;
    m.rankZeroHolds = "writes the whole grid's outputs";
  } else {  // the others: the whole terrain until the season and art direction's whole grids beside their local grid's bake
    m.otherBytes = libraries + terrain + artDirectionBytesPerCell(scene) * cells + localAbove +
                   wholeSkiLayersBeyondLocalBytes(scene, cells, static_cast<double>(local.cellCount()));
    // Rank 0 writes the whole grid's outputs; or, where each rank writes its tiles, it is one of the
    // others (its local grid's outputs in localAbove) with, beside, a no-snow mask's whole initial
    // state and the whole files it writes one at a time (no [outputs.tiles], or those beside the
    // tiles of outputs.tiles.resize).
    m.rankZeroGathers = !ranksWriteTheirTiles(scene, whole);
    if (m.rankZeroGathers) {
      m.rankZeroBytes = onWhole.peakBytes();
      m.rankZeroHolds = "writes the whole grid's outputs";
      return m;
    }
    m.rankZeroBytes = m.otherBytes;
    auto holds = [&](double bytes, const std::string& what) {
      m.rankZeroBytes += bytes;
      m.rankZeroHolds += (m.rankZeroHolds.empty() ? "" : " and ") + what;
    };
    if (scene.multipliers.noSnow) holds(initialStateBytesPerCell(scene) * cells, "keeps the whole initial state for the no-snow mask");
    const OutputTiles& tiles = scene.outputs.tiles;
    if (tiles.convention == TileConvention::None) holds(wholeFilesOnRankZeroBytes(scene, cells), "writes the whole files, one at a time");
    else if (tiles.resizeWidth > 0)
      holds(wholeFilesOnRankZeroBytes(scene, cells), "writes the whole files beside the tiles (outputs.tiles.resize)");
  }
  return m;
}

PrecomputeParts rankPrecomputeParts(const Scene& scene, const GridSpec& spec, uint8_t outputNeeds) {
  PrecomputeParts parts;
  if (!acrossRanks) return parts;
  const dist::Communicator comm = dist::Communicator::world();
  const dist::Decomposition d = decompositionOf(scene, spec);
  const dist::CellRect cells = d.local(comm.rank());
  if (seasonOnReplica(scene)) {  // the replica reads the whole grid's exposure: each rank makes its share
    if (comm.size() == 1) return parts;  // its share would be the whole grid
    parts.exposureShare = cells;
    parts.wholeExposure = [comm, d, spec](const Exposure& share) {
      agreeBeforeExchanges(comm, false);
      const Exchanging exchanging;
      return wholeExposureOnEveryRank(comm, d, share, spec);
    };
    parts.windShare = windPartOn(comm, d, cells);
    parts.wholeWind = [comm, d, spec](const WindTimeline& share, const Grid<float>& altitude) {
      agreeBeforeExchanges(comm, false);
      const Exchanging exchanging;
      return share.gatheredWhole(altitude, [&](const Grid<float>& g) { return wholeOnEveryRank(comm, d, g, spec); });
    };
    return parts;
  }
  // Where each rank writes its tiles, the sun's and the wind's layers read the rank's part too.
  const bool tilesOnRanks = ranksWriteTheirTiles(scene, spec);
  if (tilesOnRanks || !(comm.rank() == 0 && (outputNeeds & kNeedsSun))) parts.exposure = cells;
  if (tilesOnRanks || !(outputNeeds & kNeedsWind)) parts.wind = windPartOn(comm, d, cells);
  return parts;
}

CellRect initialStateCells(const Scene& scene, const GridSpec& whole, const PrecomputeParts& parts) {
  if (!acrossRanks || !parts.any()) return CellRect::whole(whole);
  // Rank 0 gathers the whole grid's state for its outputs, unless every rank writes its own tiles;
  // it keeps a no-snow mask's whole grid to take the snow it removes in the single process's order.
  const int rank = dist::Communicator::world().rank();
  if (rank == 0 && (!ranksWriteTheirTiles(scene, whole) || scene.multipliers.noSnow)) return CellRect::whole(whole);
  return decompositionOf(scene, whole).local(rank);
}

bool ranksWriteTheirTiles(const Scene& scene, const GridSpec& spec) {
  return acrossRanks && decompositionOnTiles(scene, spec, dist::Communicator::world().size(), dist::kContinuousHalo).has_value();
}

void shareTheRanksTiles(OutputSources& sources, const Scene& scene, const GridSpec& spec, const Precomputed& pre, Precomputed& local) {
  if (!ranksWriteTheirTiles(scene, spec)) return;
  const dist::Communicator comm = dist::Communicator::world();
  const dist::Decomposition d = decompositionOf(scene, spec);
  shareTheTiles(sources, comm, d);
  if (pre.partsOnRanks) return;  // rankPrecomputeParts: both parts on the local grid
  const uint8_t needs = layersNeeds(sources.layers);
  const dist::CellRect c = d.local(comm.rank());
  if ((needs & kNeedsSun) && pre.exposure) {
    local.exposure = pre.exposure->window(c.x0, c.y0, c.width(), c.height());
    sources.exposure = &*local.exposure;
  }
  if ((needs & kNeedsWind) && pre.wind) {
    local.wind = pre.wind->window(c.x0, c.y0, c.width(), c.height());
    sources.wind = &*local.wind;
  }
}

Grid<float> theRanksWindow(Grid<float> whole, const Scene& scene, const GridSpec& spec) {
  if (whole.empty() || !ranksWriteTheirTiles(scene, spec)) return whole;
  return gridWindow(whole, decompositionOf(scene, spec).local(dist::Communicator::world().rank()));
}

void mergeTheRanksFiles(OutputSink& files) {
  if (!inExchanges) throw std::logic_error("mergeTheRanksFiles: the ranks left their exchanges after the season");
  mergeTheRanksFiles(dist::Communicator::world(), files);
  inExchanges = false;  // the ranks' last exchange before the end's agreement
}

namespace {
// The log's lines on how the ranks split the grid and who writes the outputs.
void logTheRanksLayout(const Scene& scene, const dist::Communicator& comm, const dist::Decomposition& d, bool tilesOnRanks, std::ostream& log) {
  const bool untiled = scene.outputs.tiles.convention == TileConvention::None;
  log << "season: across " << comm.size() << " ranks, a " << d.columns << " x " << d.rows << " process grid"
      << (tilesOnRanks && !untiled ? " cut on the tiles' starts" : "") << "; rank 0's subdomain " << d.owned(0).width() << " x "
      << d.owned(0).height() << " cells, halo " << d.halo << "\n";
  if (tilesOnRanks && untiled)
    log << "outputs: rank 0 writes every file, each gathered from the ranks one at a time\n";
  else if (tilesOnRanks)
    log << "outputs: each rank writes the tiles that start in its subdomain\n";
  else if (const std::string why = whyRankZeroWritesEveryFile(scene); !why.empty())
    log << "outputs: rank 0 gathers the whole grid and writes every file: " << why << "\n";
  else if (untiled)
    log << "outputs: rank 0 gathers the whole grid and writes every file: a rank's local grid is the whole grid\n";
  else
    log << "outputs: rank 0 gathers the whole grid and writes every file: the grid does not split into bands of whole tiles, one a rank,"
           " or a rank's local grid would be the whole grid\n";
}

// A whole-grid state on rank 0 from every rank's owned cells (an empty state on the others).
SnowState gatheredOnRankZero(const dist::Communicator& comm, const dist::Decomposition& d, const SnowState& s, const GridSpec& whole) {
  SnowState out = comm.rank() == 0 ? dist::wholeLike(s, whole) : SnowState();
  dist::gatherOwned(comm, d, s, out);
  return out;
}

// A season's frame across ranks: each rank writes its tiles from its own copy (FrameWriter writes
// in place: it calls MPI), or rank 0 the frame gathered whole.
void writeFrameAcrossRanks(const dist::Communicator& comm, const dist::Decomposition& d, const GridSpec& whole, bool tilesOnRanks,
                           FrameWriter& frames, double day, SnowState& s) {
  throwIfStopRequested();
  if (tilesOnRanks) {
    dist::refreshHalos(comm, d, s);
    frames.write(day, s);
    if (comm.rank() == 0) progress().event("season", "frame", {{"day", jsonNumber(day)}});
    return;
  }
  SnowState frame = gatheredOnRankZero(comm, d, s, whole);
  if (comm.rank() != 0) return;
  frames.write(day, frame);
  progress().event("season", "frame", {{"day", jsonNumber(day)}});
}

}  // namespace

SeasonReport runSeasonAcrossRanks(const Scene& scene, BakeTerrain& terrain, std::unique_ptr<SnowBackend> local, SnowState& state,
                                  Precomputed& pre, uint8_t outputNeeds, SeasonConfig config, FrameWriter& frames, std::ostream& log) {
  const dist::Communicator comm = dist::Communicator::world();
  const GridSpec whole = terrain.info().spec;
  // The ranks but 0 (and 0 where every rank writes its tiles) hold their local grid of the state
  // since the inputs stage where the precompute is made in parts (initialStateCells); a local grid
  // is never the whole grid on more than one rank.
  const bool tilesOnRanks = ranksWriteTheirTiles(scene, whole);
  const bool alreadyLocal = pre.partsOnRanks && (state.spec.width != whole.width || state.spec.height != whole.height);
  const dist::Decomposition d = decompositionOf(scene, whole);
  const dist::CellRect cells = d.local(comm.rank());
  // Avalanches, skiers and bedforms run on a replica of the whole grid on every rank, their
  // runners on the whole state, which keeps its terrain and each day's static fields for them.
  const bool replicated = dist::seasonNeedsReplica(config);
  if (replicated && pre.partsOnRanks) throw std::logic_error("a season on the replica with a precompute made in parts");
  Precomputed mineOfPre;             // without a replica: the rank's cells of the exposure and the wind,
  Precomputed* ownPre = &mineOfPre;  // or the precompute's parts where they are those cells alone
  if (replicated) {
    config.eventTerrain = &state;
    if (config.updateStaticFields) config.updateStaticFields = wholeThenCutFill(config.updateStaticFields, state, cells);
  } else {
    config.skiTracks = nullptr;  // no skiers: the texture stays as the single process leaves it
    ownPre = &fillFromOwnCells(pre, mineOfPre, cells, scene.params, comm.rank() == 0, outputNeeds, config);
    if (comm.rank() != 0 || tilesOnRanks) {  // read by nothing on this rank now: the precompute's parts hold their cells of it
      terrain.terrain.heightsM = Grid<float>();
      terrain.terrain.valid = Grid<uint8_t>();
    }
  }
  config.lendFrames = false;  // each frame is gathered into a copy of its own
  if (const std::string why = dist::distributedSeasonRefusal(config, replicated); !why.empty())
    throw std::logic_error("a season across ranks with " + why + " passed acrossRanksRefusal");
  // A no-snow mask's snow leaves the whole grid here, its volume summed in the single process's
  // order; the ranks' seasons then find none on their no-snow cells, whose validity they clear.
  // A local state's are removed by its season, cell by cell alike (the volume is rank 0's to report).
  const bool noSnow = !alreadyLocal && state.noSnow.size() == whole.cellCount() && state.noSnow.size() > 0;
  const double noSnowRemovedM3 = noSnow ? removeSnowOfNoSnowCells(state) : 0.0;
  SnowState mine = alreadyLocal ? std::move(state) : dist::cutLocalState(state, cells);
  if (pre.partsOnRanks) {  // the day-0 static fields runPrecompute fills on a single process's state
    ownPre->temperatureForDay(0, mine, scene.params);
    ownPre->windForDay(0, mine);
    if (!ownPre->wind->varies() && !(outputNeeds & kNeedsWind)) ownPre->wind->releaseFields();  // as runGridBake does
  }
  // Every field is the ranks' now; rank 0 gathers the whole state at the frames and the end (the
  // whole wind's altitude is the terrain's, BakeTerrain). With a replica, the season's first upload
  // hands it the snow, and the replica's runners see the no-snow cells outside the terrain, as the
  // rank's season does.
  if (!replicated)
    state.releaseFields([](FieldRole) { return true; });
  else if (noSnow)
    leaveNoSnowCellsOutside(state);
  // Every rank is here or failed on its own before: agree before the first exchange.
  agreeBeforeExchanges(comm, true);
  inExchanges = true;
  startSeasonPeak();
  logTheRanksLayout(scene, comm, d, tilesOnRanks, log);
  SeasonReport report;
  {  // the backend and its scratch live for the season alone
    dist::DistributedBackend backend(std::move(local), comm, d);
    if (replicated) backend.replicateEvents(createCpuBackend(), state);
    progress().stage("season", 0.0);
    report = runSeason(
        backend, mine, config,
        [&](double f) {
          throwIfStopRequested();  // once a simulated day: MPI_Abort ends every rank with 130
          progress().stage("season", f);
        },
        [&](double day, SnowState& s) { writeFrameAcrossRanks(comm, d, whole, tilesOnRanks, frames, day, s); });
    frames.join();
    if (noSnow) report.noSnowRemovedM3 = noSnowRemovedM3;
    if (tilesOnRanks) {  // each rank writes the tiles of its local grid
      dist::refreshHalos(comm, d, mine);
      state = std::move(mine);
    } else if (SnowState final = gatheredOnRankZero(comm, d, mine, whole); comm.rank() == 0) {
      state = std::move(final);
    }
    // Ranks that write their tiles exchange each layer's range and then their lists of files
    // (mergeTheRanksFiles): a failure until then ends every rank at once.
    inExchanges = tilesOnRanks;
    progress().stage("season", 1.0);
    if (replicated)
      log << "season: avalanches, skiers and bedforms on every rank's replica of the whole grid, brought up to date "
          << backend.replicaGathers() << " times (" << fixed(static_cast<double>(backend.replicaBytesSent()) / (1024.0 * 1024.0), 1)
          << " MiB sent by rank 0)\n";
    logSeasonReport(report, scene, config, backend.name(), log);
  }
  mine = SnowState();
  mineOfPre = Precomputed();
  endSeasonPeak();
  return report;
}

int runBakeAcrossRanks(BakeOptions options, const std::function<std::ostream&()>& openLog,
                       const std::function<int(std::exception_ptr, std::ostream&)>& describe) {
  const dist::MpiSession mpi;
  const dist::Communicator comm = dist::Communicator::world();
  if (comm.size() != dist::launchedRanks())
    throw InputError("the launcher started " + std::to_string(dist::launchedRanks()) + " processes, but " +
                     (dist::Communicator::hasMpi() ? "MPI joined " + std::to_string(comm.size()) + " (under Slurm, srun --mpi=pmix; see docs/distributed.md)"
                                                   : std::string("this snowbake was built without MPI (docs/distributed.md)")));
  acrossRanks = true;
  seasonAgreed = false;
  peakWindows = false;
  std::ostream nowhere(nullptr);
  std::ostream* log = &nowhere;
  int status = 0;
  std::exception_ptr failure;
  std::ostringstream message;  // this rank's failure, said once it is known whether rank 0 failed too
  try {
    if (comm.rank() == 0) log = &openLog();
    runBake(options, *log);
  } catch (const OtherRankFailed& e) {
    status = e.status;  // the failing rank says why
  } catch (...) {
    failure = std::current_exception();
    if (comm.rank() != 0) message << "[rank " << comm.rank() << "] ";
    status = describe(failure, message);
    if (inExchanges) {  // the others wait in an exchange
      std::cerr << message.str();
      comm.abortAll(status);
    }
  }
  // A rank that failed before the season joins the others' agreement at its start.
  bool rank0Failed = comm.rank() == 0 && failure;
  if (failure && !seasonAgreed) rank0Failed = agreedStatuses(comm, status, true).front() != 0;
  // An input error (exit 2) is every rank's alike, as a rule: rank 0 says it, and the others only
  // when rank 0 did not fail.
  const bool inputError = status == 2;
  if (failure && (comm.rank() == 0 || !inputError || !rank0Failed)) std::cerr << message.str();
  // Rank 0 wrote the outputs while the others waited here: they end with the largest status. Each
  // rank's peak resident memory comes along for rank 0's log.
  const std::vector<double> all = comm.allGather({static_cast<double>(status), readProcessMemory().peakBytes,
                                                  peakWindows ? seasonPeakBytes : -1.0, peakWindows ? peakInWindow() : -1.0});
  const int mine = status;
  status = 0;
  constexpr int kEach = 4;  // status, peak, the season's peak, the peak after the season
  for (int r = 0; r < comm.size(); ++r) status = std::max(status, static_cast<int>(all[kEach * r]));
  if (comm.rank() == 0 && mine == 0 && status != 0) std::cerr << "snowbake: stopped: another rank failed (exit " << status << ")\n";
  if (comm.rank() == 0 && status == 0) {
    auto perRank = [&](int k) {
      for (int r = 0; r < comm.size(); ++r) *log << (r ? ", " : " ") << fixed(all[kEach * r + k] / (1024.0 * 1024.0), 0);
      *log << " MiB";
    };
    *log << "memory: peak resident per rank";
    perRank(1);
    *log << "\n";
    bool windows = true;  // every rank measured the season's (one kernel for all, as a rule)
    for (int r = 0; r < comm.size(); ++r) windows = windows && all[kEach * r + 2] >= 0.0;
    if (windows) {
      *log << "memory: peak resident per rank in the season";
      perRank(2);
      *log << "; after it";
      perRank(3);
      *log << " (the outputs)\n";
    }
  }
  acrossRanks = false;
  return status;
}

}  // namespace snow
