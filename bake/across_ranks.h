// A bake across the ranks of a launch (mpirun -np N snowbake bake ..., srun; docs/distributed.md).
// Every rank loads the scene and the terrain and makes its local grid's part of the precompute
// (the whole grid's where the season runs on the replica or rank 0's layers read it); the season
// runs decomposed (each rank its subdomain, halos exchanged, every sum in the single process's
// order; avalanches, skiers and bedforms on every rank's replica of the whole grid); rank 0
// gathers the state at the frames and the season's end and writes every output and the manifest,
// or, where every output is one the ranks can make from their cells, each rank writes the tiles
// that start in its subdomain and rank 0 the whole files, one at a time from the ranks' cells,
// and the manifest (tiles_on_ranks.h): the single process's bytes.
//
// Failures: the ranks work alone but for the wind's solve and the season, and they agree on the
// exit status before each wind state's cache read and solve, at the season's start and at the
// end (the largest of theirs), so a bad input ends every rank with exit 2 and one message (rank
// 0's; another rank's own when rank 0 did not fail); a failure while the others wait in an
// exchange (the season, and the tiles' outputs until their files are merged) ends every rank at
// once with its status (MPI_Abort).
#pragma once
#include <cstdint>
#include <exception>
#include <functional>
#include <optional>
#include <ostream>
#include <string>

#include "bake.h"
#include "memory_model.h"
#include "core/grid_window.h"
#include "core/snow_state.h"
#include "scene/scene.h"

namespace snow {

struct BakeTerrain;
struct OutputSink;
struct OutputSources;
struct Precomputed;
struct PrecomputeParts;
struct SeasonConfig;
struct SeasonReport;
class FrameWriter;
class SnowBackend;

// Why `scene` cannot be baked across ranks yet, naming the key and where it was given (or the
// scene, for a default); empty when it can.
std::string acrossRanksRefusal(const Scene& scene);

// Whether this process is one of several ranks of a launch that runs a bake across ranks (after
// the launch's MPI is initialised: runBakeAcrossRanks).
bool bakingAcrossRanks();
// Whether this process writes the bake's files: alone, or rank 0 of a bake across ranks.
bool writesOutputs();

// Refuses (InputError) a grid that `ranks` subdomains cannot split: each needs the season's halo.
void checkRanksSuitTheGrid(const Scene& scene, const GridSpec& spec);

// The parts of the precompute this rank makes on its local grid alone (none when not across
// ranks): the exposure, but on rank 0 where a layer in `outputNeeds` reads the sun; the wind on
// every rank alike (its solve exchanges), unless a layer reads the wind. Where the season runs on
// the replica, which reads the whole grid's, only the exposure's and the wind's shares, gathered
// whole on every rank (PrecomputeParts::exposureShare, windShare).
PrecomputeParts rankPrecomputeParts(const Scene& scene, const GridSpec& spec, uint8_t outputNeeds);

// Across ranks, the peak each rank of this machine is predicted to hold (memory_model.h): rank 0
// as one process on the whole grid (`onWhole`: it gathers and writes the whole grid's outputs);
// each other rank the whole terrain and art direction's whole-grid rasters and edit weights beside
// one process's peak on the largest local grid (`predictOn`: an upper bound, since it writes no
// outputs); where each rank writes its tiles, rank 0 as the others (with a no-snow mask, its whole
// initial state besides), their resampled images their tiles' window of the whole image
// (sceneOfTheRanksTiles); with the replica, every rank one process's peak on the whole grid and on its local
// grid. nullopt when not across ranks, or where the grid cannot be split (checkRanksSuitTheGrid
// says why).
std::optional<RanksMemory> ranksMemory(const Scene& scene, const GridSpec& whole, const MemoryPrediction& onWhole,
                                       const std::function<MemoryPrediction(const Scene&, const GridSpec&)>& predictOn);


// The cells of the whole grid this rank's initial state is made on (initialState; art direction
// fills it there): its local grid where it keeps that alone from the precompute on, the precompute
// made in parts (the ranks but 0, and rank 0 where every rank writes its tiles and no no-snow mask
// asks it to sum the snow the mask removes over the whole grid); else the whole grid. From there
// on nothing but the season reads the state, and rank 0 gathers the season's into its whole state
// where it gathers the whole grid for the outputs.
CellRect initialStateCells(const Scene& scene, const GridSpec& whole, const PrecomputeParts& parts);

// Whether each rank writes the tiles that start in its subdomain (tiles_on_ranks.h): across
// ranks, with outputs each rank can make from its local grid, on a grid that splits into bands of
// whole tiles (any grid without [outputs.tiles]; rank 0 then writes every file, each gathered from
// the ranks). Then every rank keeps its local grid alone and none gathers the whole grid's state.
bool ranksWriteTheirTiles(const Scene& scene, const GridSpec& spec);
// Where they do, points `sources` at this rank's tiles (else leaves them as they are), and the
// sun's and wind's layers at the rank's local grid of the precompute: `pre`, made in the rank's
// parts, or (a season on the replica keeps the whole grid's) its window, kept in `local`.
void shareTheRanksTiles(OutputSources& sources, const Scene& scene, const GridSpec& spec, const Precomputed& pre, Precomputed& local);
// Where each rank writes its tiles, `whole` (a layer's grid over the whole terrain, as the skiers'
// route map) cut to this rank's local grid, which its tiles read; else `whole` as it is.
Grid<float> theRanksWindow(Grid<float> whole, const Scene& scene, const GridSpec& spec);
// Every rank's files merged into rank 0's `files`, in the single process's order, where each rank
// writes its tiles: from the season's end until this returns, the ranks exchange (each layer's
// range, then the lists of files), so a failure on one rank ends every rank at once.
void mergeTheRanksFiles(OutputSink& files);

// The season across the ranks on the terrain's whole grid (rank 0's `state` holds it, and every
// rank's where the precompute was not made in parts; the others' their local grid): on rank 0,
// `state` is then the gathered final state and each frame day went to `frames`. Without
// avalanches, skiers or bedforms each rank fills its static fields from its own cells of `pre`
// (its day-0 fields too where the precompute made parts, Precomputed::partsOnRanks) and frees the
// whole state and the whole `pre` (rank 0 keeps what the layers in `outputNeeds` read), and the
// ranks but 0 free the terrain's grids; with them, every rank keeps the whole state for the
// replica (the terrain, the last day's static fields, its no-snow cells outside the terrain).
// `local` is the rank's CPU backend.
SeasonReport runSeasonAcrossRanks(const Scene& scene, BakeTerrain& terrain, std::unique_ptr<SnowBackend> local, SnowState& state,
                                  Precomputed& pre, uint8_t outputNeeds, SeasonConfig config, FrameWriter& frames, std::ostream& log);

// runBake on every rank of the launch, rank 0 logging to openLog() (opened once the ranks have
// joined, so its failure is every rank's); `describe` writes a failure's message to the stream
// and returns its exit status. Returns the status all ranks share.
int runBakeAcrossRanks(BakeOptions options, const std::function<std::ostream&()>& openLog,
                       const std::function<int(std::exception_ptr, std::ostream&)>& describe);

}  // namespace snow
