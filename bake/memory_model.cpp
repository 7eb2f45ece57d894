// The memory model (memory_model.h): every owner's bytes from the scene and the grid, the
// field sizes from the field table (core/snow_fields.h), the phases of a bake as mode_grid.cpp
// and mode_mesh.cpp run them. The few constants measured rather than counted say so, and how;
// tools/measure-memory.sh checks the whole model against measured peaks (docs/memory.md).
#include "memory_model.h"
#include "memory_trace.h"
#include "memory_vdb.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/errors.h"
#include "core/season.h"
#include "core/snow_fields.h"
#include "bakers/value_range.h"
#include "bakers/vdb_writer.h"
#include "precompute/exposure.h"
#include "scene/layers.h"

namespace snow {

namespace {

constexpr double kMiB = 1024.0 * 1024.0;
constexpr double kGiB = 1024.0 * kMiB;
// Measured: the resident set of the program and its libraries (TBB, Embree, OpenVDB, GDAL, OIIO)
// once a bake has touched them, on a 64 x 64 bake (tools/measure-memory.sh).
constexpr double kLibraryBytes = 140.0 * kMiB;
// Measured: bytes a cell the horizon sweep's per-thread line buffers hold beside the counted
// grids; Embree's terrain (a grid geometry: 12 bytes of vertex a cell and its BVH) a cell, and its
// BVH bytes per occluder triangle. Counted: the wind solver's W_z and W_sz in double (16) and
// free stream (8), beside the wind fields (its links and ground speeds are made as it needs them).
constexpr double kSweepScratchPerCell = 16.0;
constexpr double kWindSolverPerCell = 24.0;
constexpr double kEmbreeGridBytesPerCell = 28.0;
constexpr double kEmbreeBytesPerTriangle = 120.0;
// Mesh mode's snow body: three grids of float leaves (2 KiB and their masks) per leaf slot.
constexpr double kSnowBodyBytesPerLeafSlot = 3 * 2112.0;
// Mesh mode: bytes a lattice site holds (position, normal, coverage, deposit, neighbour links),
// and a triangle of the input mesh with its Embree BVH.
constexpr double kSiteBytes = 160.0;
constexpr double kMeshTriangleBytes = 200.0;
constexpr double kRecordBytes = 4096.0;
// Measured: bytes a cell the grid's snow-surface mesh holds at its peak, the triangulation and
// the file written as it is read from it (heaptrack, the default preset at 1024², day 10: buildRtin
// 21.7 MB and writeSurfaceMeshes 29.6 MB at their peaks for 1.05 M cells; docs/memory.md).
constexpr double kSurfaceMeshBytesPerCell = 50.0;

// Bytes a cell of the state's fields with the roles `pick` accepts, optional fields only when
// `present` says the scene makes them.
template <class Pick, class Present>
double fieldBytes(Pick pick, Present present) {
  double b = 0;
#define SNOW_FIELD_BYTES(member, view, Element, role, access, fill)                                   \
  if (pick(FieldRole::role) && (!optionalField(FieldRole::role) || present(#member))) b += sizeof(Element);
  SNOW_STATE_FIELDS(SNOW_FIELD_BYTES)
#undef SNOW_FIELD_BYTES
  return b;
}

double scratchBytes(bool withState, bool powderInRows) {
  double b = 0;
#define SNOW_SCRATCH_BYTES(view, Element, extent)                                      \
  if (madeWithState(ScratchExtent::extent) == withState)                               \
    b += sizeof(Element) * static_cast<double>(scratchCount(ScratchExtent::extent, 1, 0, powderInRows));
  SNOW_SCRATCH_FIELDS(SNOW_SCRATCH_BYTES)
#undef SNOW_SCRATCH_BYTES
  return b;
}

// Which optional fields the scene fills.
struct OptionalFields {
  const Scene& s;
  bool operator()(const std::string& m) const {
    const Multipliers& mu = s.multipliers;
    if (m == "snowfallFactor") return bool(mu.snowfall);
    if (m == "meltFactor") return bool(mu.melt);
    if (m == "windErosionFactor") return bool(mu.windErosion);
    if (m == "avalancheReleaseFactor") return bool(mu.avalancheRelease);
    if (m == "skierSpawnFactor") return bool(mu.skierSpawn);
    if (m == "noSnow") return bool(mu.noSnow);
    if (m == "bedformMask") return s.bedforms.enabled && bool(s.bedforms.mask);
    if (m == "bedformCohesion") return s.bedforms.enabled;
    return false;
  }
};

bool hasLayer(const Scene& s, const char* name) {
  return std::find(s.outputs.layers.begin(), s.outputs.layers.end(), name) != s.outputs.layers.end();
}

struct GridSizes {
  double cells, state, backend, layersOneDay;
};

// Pixels of a grid layer's files: outputs.resize, else the grid's cells.
double outputPixels(const OutputRequest& o, double cells) {
  return o.resizeWidth > 0 ? static_cast<double>(o.resizeWidth) * o.resizeHeight : cells;
}

// What writing one day's outputs holds beside the state: one layer at a time, or all of them
// for the multi-channel EXR, the encodings' integer copy, the day's wind and sun, displacement;
// the deliverables' own buffers: the layer resized with its valid mask (outputs.resize), the
// file being written cut from it (a tile, or the whole image copied untiled) with its mask, and
// the engine maps' weights and pixels.
std::vector<MemoryOwner> writerOwners(const Scene& s, double cells) {
  const OutputRequest& o = s.outputs;
  const uint8_t needs = layersNeeds(o.layers);
  std::vector<MemoryOwner> w;
  const double layers = static_cast<double>(o.layers.size());
  constexpr MemoryGroup W = MemoryGroup::Writers;
  const double px = outputPixels(o, cells);
  w.push_back({"layers being written", cells * 4.0 * (o.multichannelExr ? layers + 1 : 2.0), o.multichannelExr ? "outputs.multichannel_exr" : "outputs.layers", W});
  if (o.resizeWidth > 0) w.push_back({"resized layer and its mask", px * 5.0, "outputs.resize", W});
  const bool tiled = o.tiles.convention != TileConvention::None && o.tiles.sizePx > 0;
  w.push_back({tiled ? "tile being written" : "image being written", (tiled ? static_cast<double>(o.tiles.sizePx) * o.tiles.sizePx : px) * 5.0,
               tiled ? "outputs.tiles.size_px" : "outputs.layers", W});
  // [outputs.tiles] resize: a second set of rasters, the layer copied and resized for it with its
  // mask, and its own layers.exr channels.
  const double tileSetPx = tiled && o.tiles.resizeWidth > 0 ? static_cast<double>(o.tiles.resizeWidth) * o.tiles.resizeHeight : 0.0;
  if (tileSetPx > 0) {
    const double channels = o.multichannelExr ? 4.0 * layers : 0.0;
    w.push_back({"the tile set's resized layer", cells * 4.0 + tileSetPx * (5.0 + channels), "outputs.tiles.resize", W});
  }
  const double mapPx = std::max(px, tileSetPx);  // the engine maps and encodings at the larger set's size
  // The splat map: three weights, their mask and the RGBA pixels; the normal map: the surface,
  // its mask and the RGB pixels (one of them at a time).
  const double splat = hasLayer(s, "splat_map") ? mapPx * (3.0 * 4.0 + 1.0 + 4.0) : 0.0;
  const double normal = hasLayer(s, "snow_normal") ? mapPx * (4.0 + 1.0 + 3.0) : 0.0;
  if (splat + normal > 0) w.push_back({"engine map being written", std::max(splat, normal), "outputs.layers", W});
  if (!o.encodings.empty()) w.push_back({"encodings", std::max(cells, tileSetPx) * 2.0, "outputs.encodings", W});
  if (needs & kNeedsWind) w.push_back({"the day's wind", cells * 16.0, "outputs.layers", W});
  if (needs & kNeedsSun) w.push_back({"the day's sun", cells * 4.0, "outputs.layers", W});
  if (o.displacementWidth > 0)
    w.push_back({"displacement map", static_cast<double>(o.displacementWidth) * o.displacementHeight * 4.0 + cells * 4.0,
                 "outputs.displacement_size", W});
  return w;
}

// Encodings on a "season" range wait for the season's end on disk (OutputWriter's spill file):
// each day's layer (at the output size) and its mask, or the ski-track texture (`skiTextureBytes`,
// its own size); the outputs stage reads them back one at a time. The largest of them.
double seasonRangeReadBackBytes(const Scene& s, double cells, double skiTextureBytes) {
  const OutputRequest& o = s.outputs;
  if (std::none_of(o.encodings.begin(), o.encodings.end(), [](const std::string& e) { return e != "r32"; })) return 0.0;
  double largest = 0.0;
  for (const auto& name : o.layers)
    if (const LayerInfo* l = findLayer(name); l && l->kind == LayerKind::Float && rangeOf(o, *l).mode == RangeMode::Season) {
      const bool texture = l->needs & kNeedsSkiTracks;
      largest = std::max(largest, texture ? skiTextureBytes : outputPixels(o, cells) * 5.0);
      // [outputs.tiles] resize: the tile set's layers wait too.
      if (o.tiles.convention != TileConvention::None && o.tiles.resizeWidth > 0 && !texture)
        largest = std::max(largest, static_cast<double>(o.tiles.resizeWidth) * o.tiles.resizeHeight * 5.0);
    }
  return largest;
}

// A day's writers run one after another (OutputWriter::writeDay): the layers (with their
// encodings, displacement and multi-channel EXR), then the VDB, then the meshes; the day holds
// the largest of the three. The VDB holds the snow of `day`.
std::vector<MemoryOwner> dayWriters(const Scene& s, const GridSpec& spec, double cells, const SnowReach& reach, double day) {
  std::vector<MemoryOwner> layers = writerOwners(s, cells);
  double layerBytes = 0;
  for (const auto& o : layers) layerBytes += o.bytes;
  const double vdb = vdbWriterBytes(s, spec, reach, day);
  const double mesh = s.outputs.meshes.empty() ? 0.0 : cells * kSurfaceMeshBytesPerCell;
  // The VDB's voxels are the grid's cells unless the scene sets their size: then the grid sizes it.
  const char* vdbKey = s.outputs.vdbVoxelSizeM > 0 ? "outputs.vdb_voxel_size_m" : "terrain.size";
  if (vdb >= layerBytes && vdb >= mesh) return {{"VDB", vdb, vdbKey, MemoryGroup::Writers}};
  if (mesh >= layerBytes) return {{"snow-surface mesh", mesh, "outputs.meshes", MemoryGroup::Writers}};
  return layers;
}

}  // namespace

double wholeFilesOnRankZeroBytes(const Scene& s, double cells) {
  Scene whole = s;
  whole.outputs.tiles = OutputTiles{};
  double bytes = cells * 5.0;
  for (const MemoryOwner& o : writerOwners(whole, cells)) bytes += o.bytes;
  return bytes;
}

double wholeSkiLayersBeyondLocalBytes(const Scene& s, double wholeCells, double localCells) {
  const double texels = static_cast<double>(s.outputs.skiTrackFactor) * s.outputs.skiTrackFactor;
  double bytes = 0;
  // The texture, the layer made from it, its encoding's quantised copy and a second raster set's
  // copy at once; the route map's sort order and buffer beside it as it is made.
  if (hasLayer(s, "ski_tracks")) bytes += 4.0 * (wholeCells - localCells) * texels * 4.0;
  if (hasLayer(s, "ski_route_map")) bytes += wholeCells * 12.0;
  return bytes;
}

double MemoryPhase::bytes() const {
  double b = 0;
  for (const auto& o : owners) b += o.bytes;
  return b;
}

const MemoryOwner& MemoryPhase::largest() const {
  return *std::max_element(owners.begin(), owners.end(), [](const auto& a, const auto& b) { return a.bytes < b.bytes; });
}

const MemoryPhase& MemoryPrediction::peakPhase() const {
  return *std::max_element(phases.begin(), phases.end(), [](const auto& a, const auto& b) { return a.bytes() < b.bytes(); });
}

std::string MemoryPrediction::summary() const {
  const MemoryPhase& p = peakPhase();
  std::vector<MemoryOwner> owners = p.owners;
  std::sort(owners.begin(), owners.end(), [](const auto& a, const auto& b) { return a.bytes > b.bytes; });
  std::ostringstream o;
  o << std::fixed << std::setprecision(0) << "predicted peak " << peakBytes() / kMiB << " MiB, in the " << p.name << " (libraries "
    << libraryBytes / kMiB << " MiB";
  for (size_t i = 0; i < owners.size() && i < 3; ++i) o << ", " << owners[i].name << " " << owners[i].bytes / kMiB << " MiB";
  o << ")";
  return o.str();
}

const std::vector<MemoryGroupInfo>& memoryGroups() {
  static const std::vector<MemoryGroupInfo> table{
      {MemoryGroup::State, "state", "the terrain and the snow layers (host and backend copies), the mesh in mesh mode"},
      {MemoryGroup::StaticFields, "static fields", "exposure, temperature base and wind fields of the day (host and backend), occlusion fields"},
      {MemoryGroup::ExposureSamples, "exposure samples", "I_sky and each sample day's I_sun + I_ind, interpolated each day"},
      {MemoryGroup::WindFields, "wind fields", "each distinct wind state's field, wind-effect surface and loading"},
      {MemoryGroup::Scratch, "scratch", "the backend's working fields, the avalanche runner's, the skiers' route map, mesh mode's lattice"},
      {MemoryGroup::Records, "records", "scour, deposit, melt and avalanche-peak fields, skier and avalanche records, the ski-track texture"},
      {MemoryGroup::Writers, "writers", "the layers, encodings, displacement maps and VDB being written"},
      {MemoryGroup::FramesInFlight, "frames in flight", "a frame day's copy of the state written beside the season, frames held for season ranges"},
      {MemoryGroup::PrecomputeWork, "precompute working sets", "horizon angles or Embree's ray scene, the wind solver: freed before the season"},
  };
  return table;
}

const char* memoryGroupName(MemoryGroup g) {
  for (const auto& i : memoryGroups())
    if (i.group == g) return i.name;
  return "?";
}

std::vector<std::pair<MemoryGroup, double>> MemoryPrediction::peakByGroup() const {
  std::vector<std::pair<MemoryGroup, double>> out;
  for (const auto& i : memoryGroups()) {
    double b = 0;
    for (const auto& o : peakPhase().owners)
      if (o.group == i.group) b += o.bytes;
    out.emplace_back(i.group, b);
  }
  return out;
}

std::string memoryBreakdownText(const MemoryPrediction& p, double measured, const std::string& stage, double units,
                                const std::string& unit) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(0) << "memory: measured peak " << measured / kMiB << " MiB (VmHWM)"
    << (stage.empty() ? "" : ", reached by the end of the " + stage + " stage") << "; predicted " << p.peakBytes() / kMiB << " MiB in the "
    << p.peakPhase().name << " (" << std::showpos << std::setprecision(1) << 100.0 * (p.peakBytes() - measured) / std::max(measured, 1.0)
    << std::noshowpos << " %)\n" << std::setprecision(0);
  o << "  " << std::left << std::setw(26) << "libraries" << std::right << std::setw(8) << p.libraryBytes / kMiB << " MiB\n";
  for (const auto& [g, bytes] : p.peakByGroup())
    o << "  " << std::left << std::setw(26) << memoryGroupName(g) << std::right << std::setw(8) << bytes / kMiB << " MiB  "
      << std::setw(5) << bytes / std::max(units, 1.0) << " B/" << unit << "\n";
  o << "  measured above the libraries: " << std::setprecision(1) << (measured - p.libraryBytes) / std::max(units, 1.0) << " bytes a "
    << unit << "\n";
  return o.str();
}

std::string memoryBreakdownJson(const MemoryPrediction& p, double measured, const std::string& stage, double units,
                                const std::string& unit) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(1) << "{\"measured_peak_mib\": " << measured / kMiB << ", \"measured_peak_stage\": \"" << stage
    << "\", \"measured_bytes_per_" << unit << "_above_libraries\": " << (measured - p.libraryBytes) / std::max(units, 1.0)
    << ", \"predicted_peak_mib\": " << p.peakBytes() / kMiB << ", \"predicted_peak_phase\": \"" << p.peakPhase().name
    << "\", \"predicted_mib\": {\"libraries\": " << p.libraryBytes / kMiB;
  for (const auto& [g, bytes] : p.peakByGroup()) o << ", \"" << memoryGroupName(g) << "\": " << bytes / kMiB;
  o << "}}";
  return o.str();
}

std::string measuredMemoryBreakdown(const MemoryPrediction& p, double units, const std::string& unit, bool verbose, std::ostream& log) {
  const double measured = readProcessMemory().peakBytes;
  const std::string stage = stageOfPeak(stageMemory(), measured);
  if (verbose) log << memoryBreakdownText(p, measured, stage, units, unit);
  return memoryBreakdownJson(p, measured, stage, units, unit);
}

namespace {
// The distinct wind states of the keyframes (none in occlusion mode), and whether a calm keyframe
// is among them (then one state varies too).
struct WindStates {
  size_t count = 0;
  bool calmKeyframe = false;
};
WindStates windStatesOf(const Scene& s) {
  WindStates w;
  std::vector<std::pair<double, double>> seen;
  for (const auto& k : s.weather.keyframes) {
    w.calmKeyframe = w.calmKeyframe || k.state.windSpeedMps <= 0.0;
    if (k.state.windSpeedMps > 0.0 && std::find(seen.begin(), seen.end(), std::make_pair(k.state.windDirectionDeg, k.state.windSpeedMps)) == seen.end())
      seen.emplace_back(k.state.windDirectionDeg, k.state.windSpeedMps);
  }
  w.count = s.mode == SceneMode::Occlusion ? 0 : seen.size();
  return w;
}

MemoryOwner heldIf(bool held, MemoryOwner o) {
  if (!held) o.bytes = 0.0;
  return o;
}

// What a grid bake's phases hold, sized once from the scene and the grid; each phase below lists
// the ones it holds at once.
struct GridBakeOwners {
  double cells = 0;
  double state = 0;  // every field but the record fields (recordOwner's)
  double samples = 0;  // the exposure's sample days (0: no sun exposure)
  ExposureSettings es;
  bool sweep = false;  // the sun by the horizon sweep, else by Embree's rays
  double rayScene = 0;
  WindStates wind;
  bool windVaries = false;
  MemoryOwner terrain, stateOwner, staticOwner, recordOwner;
  // The exposure as computed (I_sky, I_sun and I_ind a sample day) and as kept (I_sun + I_ind:
  // Exposure::foldIndirect); the wind's fields.
  MemoryOwner computedExposure, exposure, windFields;
  // After the precompute a constant wind's fields are the state's copy unless a layer reads the
  // wind; after the season the exposure samples go unless a layer reads the sun, and the state's
  // static fields go (no writer reads them): bake/mode_grid.cpp.
  MemoryOwner windKept, exposureAfter;
  std::vector<MemoryOwner> writer, frameWriter;  // the season's end's writers, the latest frame's
  bool skiTracks = false;
  MemoryOwner skiTexture;
  // The layers whose encodings wait for a "season" range wait on disk; the outputs read them back
  // one at a time.
  double readBack = 0;
};

GridBakeOwners gridBakeOwners(const Scene& s, const GridSpec& spec, size_t occluderTriangles, const SnowReach& reach) {
  using G = MemoryGroup;
  GridBakeOwners o;
  const double cells = o.cells = static_cast<double>(spec.width) * spec.height;
  const OptionalFields present{s};
  auto bytesOf = [&](auto pick) { return cells * fieldBytes(pick, present); };
  o.state = bytesOf([](FieldRole r) { return r != FieldRole::Record; });
  o.terrain = {"terrain", cells * 5.0, "terrain.size", G::State};
  o.stateOwner = {"snow state", bytesOf([](FieldRole r) { return r != FieldRole::Static && r != FieldRole::Record; }), "terrain.size", G::State};
  o.staticOwner = {"snow state: static fields", bytesOf([](FieldRole r) { return r == FieldRole::Static; }), "terrain.size", G::StaticFields};
  // Of the record fields (all floats), only those the layers read (SeasonConfig::recordFields).
  const double keptRecords = std::popcount(recordFieldsToKeep(layersRecords(s.outputs.layers), s.outputs.avalancheMaps));
  o.recordOwner = {"snow state: record fields", cells * 4.0 * keptRecords, "outputs.layers", G::Records};
  o.es.quality = sunQuality(s.sunQuality);
  o.es.seasonDays = s.days;
  o.sweep = s.sunMethod == SunMethod::Horizon || (s.sunMethod == SunMethod::Auto && s.occluders.empty());
  const bool occlusion = s.mode == SceneMode::Occlusion;
  o.samples = (!occlusion && s.sunExposure) ? static_cast<double>(exposureSampleDays(o.es).size()) : 0.0;
  o.computedExposure = {"exposure samples", cells * 4.0 * (o.samples > 0 ? 1.0 + 2.0 * o.samples : 0.0), "precompute.sun_quality", G::ExposureSamples};
  o.exposure = {"exposure samples", cells * 4.0 * (o.samples > 0 ? 1.0 + o.samples : 0.0), "precompute.sun_quality", G::ExposureSamples};
  o.wind = windStatesOf(s);
  o.windFields = {"wind fields", cells * 20.0 * static_cast<double>(o.wind.count), "weather.keyframe", G::WindFields};
  const uint8_t needs = layersNeeds(s.outputs.layers);
  o.windVaries = o.wind.count > 1 || (o.wind.count > 0 && o.wind.calmKeyframe);
  o.windKept = heldIf(o.windVaries || (needs & kNeedsWind), o.windFields);
  o.exposureAfter = heldIf(needs & kNeedsSun, o.exposure);
  o.rayScene = cells * kEmbreeGridBytesPerCell + static_cast<double>(occluderTriangles) * kEmbreeBytesPerTriangle;
  o.writer = dayWriters(s, spec, cells, reach, s.days);
  double lastFrame = 0;
  for (double d : s.outputs.frameDays) lastFrame = std::max(lastFrame, std::min(d, s.days));
  o.frameWriter = dayWriters(s, spec, cells, reach, lastFrame);
  const double track = s.outputs.skiTrackFactor;
  o.skiTracks = hasLayer(s, "ski_tracks");
  o.skiTexture = {"ski-track texture", o.skiTracks ? cells * track * track * 4.0 : 0.0, "outputs.ski_track_factor", G::Records};
  o.readBack = seasonRangeReadBackBytes(s, cells, o.skiTexture.bytes);
  return o;
}

// The sun exposure, then the wind (the sun's working set freed between them); the record fields
// are made after both. The static fields are made by the precompute's fill of day 0: the exposure
// and the temperature base after the sun, the wind's after the wind (bake/stage_precompute.cpp).
void addPrecomputePhases(MemoryPrediction& p, const GridBakeOwners& o) {
  using G = MemoryGroup;
  const double cells = o.cells;
  MemoryPhase pre{"precompute: sun exposure", {o.terrain, o.stateOwner}};
  if (o.samples > 0) {
    // The sky's horizon grids (one an azimuth), or the shadows' sweep (three grids, the normals,
    // a bit a cell for each sun position above the horizon: precompute/horizon.h).
    const double sunPositions = o.samples * 24.0 / o.es.quality.hourStep * 0.5;
    if (o.sweep)
      pre.owners.push_back({"horizon angles", cells * (std::max(4.0 * o.es.quality.azimuths, 12.0 + 12.0 + sunPositions / 8.0) + kSweepScratchPerCell),
                            "precompute.sun_quality", G::PrecomputeWork});
    else
      pre.owners.push_back({"ray scene (Embree)", o.rayScene, "precompute.sun_method", G::PrecomputeWork});
    pre.owners.push_back(o.computedExposure);
  }
  p.phases.push_back(pre);
  if (o.wind.count > 0) {
    const MemoryOwner staticBeforeWind{"snow state: static fields", cells * 8.0, "terrain.size", G::StaticFields};
    MemoryPhase windPhase{"precompute: wind", {o.terrain, o.stateOwner, staticBeforeWind, o.computedExposure, o.windFields,
                                               {"wind solver", cells * kWindSolverPerCell, "weather.keyframe", G::PrecomputeWork}}};
    if (o.samples <= 0) windPhase.owners[3].bytes = 0.0;
    p.phases.push_back(windPhase);
  }
}

// Occlusion mode in place of the season: the rays' scene and the occlusion fields, then the outputs.
void addOcclusionPhases(MemoryPrediction& p, const GridBakeOwners& o) {
  using G = MemoryGroup;
  const double cells = o.cells;
  MemoryPhase occ{"occlusion", {o.terrain, o.stateOwner, o.staticOwner, o.recordOwner,
                                {"ray scene (Embree)", o.rayScene, "terrain.size", G::PrecomputeWork},
                                {"ray origins and normals", cells * 25.0, "terrain.size", G::Scratch},
                                {"occlusion fields", cells * 16.0, "terrain.size", G::StaticFields}}};
  p.phases.push_back(occ);
  MemoryPhase out{"outputs", {o.terrain, o.stateOwner, o.staticOwner, o.recordOwner, {"occlusion fields", cells * 16.0, "terrain.size", G::StaticFields}}};
  out.owners.insert(out.owners.end(), o.writer.begin(), o.writer.end());
  p.phases.push_back(out);
}

// The season, and its frames as `timing` writes them: beside it (one in flight), while it waits
// (FrameTiming::Paused) or after it (every frame's copy held through it). The backend holds the
// state's fields (the host keeps the terrain and, unless they are refilled daily, the static
// fields: SeasonRun::releaseHostCopies), its scratch, the avalanche runner's layers at release and
// scratch, the route map.
void addSeasonPhases(MemoryPrediction& p, const GridBakeOwners& o, const Scene& s, FrameTiming timing) {
  using G = MemoryGroup;
  const double cells = o.cells;
  const OptionalFields present{s};
  auto bytesOf = [&](auto pick) { return cells * fieldBytes(pick, present); };
  const bool staticOnHost = !((o.samples > 0 || o.windVaries) && !s.bedforms.enabled);
  // What the season holds whether it runs or waits for a frame.
  const std::vector<MemoryOwner> held{
      o.terrain,
      {"snow state: terrain on the host", bytesOf([](FieldRole r) { return r == FieldRole::Terrain || optionalField(r); }), "terrain.size", G::State},
      o.exposure,
      o.windKept,
      {"backend: state", bytesOf([](FieldRole r) { return r == FieldRole::Terrain || r == FieldRole::Evolved || r == FieldRole::ArtDirection; }), "terrain.size", G::State},
      {"backend: static fields", bytesOf([](FieldRole r) { return r == FieldRole::Static; }), "terrain.size", G::StaticFields},
      {"backend: record fields", o.recordOwner.bytes, o.recordOwner.key, G::Records}};
  MemoryPhase season{"season", held};
  season.owners.push_back({"backend scratch", cells * (scratchBytes(true, true) + 16.0), "terrain.size", G::Scratch});
  // The avalanche runner and the route map exist only where the season can have avalanches and skiers.
  const bool skiing = (s.params.skiersPerHour > 0.0 && s.params.skiHoursPerDay > 0.0) || !s.userSkiers.empty();
  if (s.params.avalancheRatePerKm2PerDay > 0.0 || !s.userAvalanches.empty() || (skiing && s.params.skiTriggerFactor > 0.0))
    season.owners.push_back({"avalanche runner", cells * (16.0 + 1.0 + scratchBytes(false, true)), "terrain.size", G::Scratch});
  if (skiing) season.owners.push_back({"ski route map", cells * 20.0, "parameters.skiers_per_hour", G::Scratch});
  if (staticOnHost) season.owners.push_back({"snow state: static fields on the host", o.staticOwner.bytes, "terrain.size", G::StaticFields});
  if (o.skiTracks) season.owners.push_back(o.skiTexture);
  // Each skier's record (its refined track, about 4 KiB) and each scene avalanche's.
  double skiers = s.params.skiersPerHour * s.params.skiHoursPerDay * s.days;
  for (const auto& e : s.userSkiers) skiers += e.count;
  const MemoryOwner records{"skier and avalanche records", (skiers + static_cast<double>(s.userAvalanches.size())) * kRecordBytes,
                            "parameters.skiers_per_hour", G::Records};
  season.owners.push_back(records);
  // A frame's copy of the state (the season's download) without the static fields the host
  // released, with the record fields the season keeps.
  const double frames = static_cast<double>(s.outputs.frameDays.size());
  const bool framesAfterSeason = frames > 0 && timing == FrameTiming::AfterSeason;
  const double copy = o.state + o.recordOwner.bytes - (staticOnHost ? 0.0 : o.staticOwner.bytes);
  const MemoryOwner heldCopies{"frames held: state copies", frames * copy, "outputs.frames_days", G::FramesInFlight};
  const MemoryOwner heldTextures{"frames held: ski-track texture copies", frames * o.skiTexture.bytes, "outputs.frames_days", G::FramesInFlight};
  if (framesAfterSeason) {
    // Every frame's copies held through the season, written once the backend is freed.
    season.owners.push_back(heldCopies);
    if (o.skiTracks) season.owners.push_back(heldTextures);
  } else if (frames > 0 && timing != FrameTiming::Paused) {
    // One frame in flight: its copy, two of the texture (the writer's and its layer), its writers.
    season.owners.push_back({"frame in flight: state copy", copy, "outputs.frames_days", G::FramesInFlight});
    if (o.skiTracks) season.owners.push_back({"frame in flight: ski-track texture copies", 2.0 * o.skiTexture.bytes, "outputs.ski_track_factor", G::FramesInFlight});
    for (const auto& w : o.frameWriter) season.owners.push_back({"frame in flight: " + w.name, w.bytes, w.key, G::Writers});
  }
  p.phases.push_back(season);
  if (frames > 0 && timing == FrameTiming::Paused) {
    // The season waiting: its scratch freed (the backend's, the avalanche runner's, the skiers'
    // but the host's route map), its fields lent to the writers. Counted with a copy read back, as
    // for a frame whose instant fell inside an avalanche (set aside on disk until it settled).
    MemoryPhase paused{"frame (the season paused)", held};
    paused.owners.push_back({"frame set aside: state copy", copy, "outputs.frames_days", G::FramesInFlight});
    if (skiing) paused.owners.push_back({"ski route map on the host", cells * 4.0, "parameters.skiers_per_hour", G::Scratch});
    if (staticOnHost) paused.owners.push_back({"snow state: static fields on the host", o.staticOwner.bytes, "terrain.size", G::StaticFields});
    if (o.skiTracks) paused.owners.push_back(o.skiTexture), paused.owners.push_back({"frame set aside: ski-track texture", o.skiTexture.bytes, "outputs.frames_days", G::FramesInFlight});
    paused.owners.push_back(records);
    paused.owners.insert(paused.owners.end(), o.frameWriter.begin(), o.frameWriter.end());
    p.phases.push_back(paused);
  }
  if (framesAfterSeason) {
    // The host's state whole again (the season's last download), the copies not yet written
    // (counted whole), the frame's writers.
    MemoryPhase after{"frames after the season", {o.terrain, o.stateOwner, o.recordOwner, o.exposureAfter, o.windKept, heldCopies}};
    if (o.skiTracks) after.owners.push_back(o.skiTexture), after.owners.push_back(heldTextures);
    after.owners.insert(after.owners.end(), o.frameWriter.begin(), o.frameWriter.end());
    p.phases.push_back(after);
  }
}

// The outputs: the backend is freed once the season ends, and the state's static fields.
void addOutputsPhase(MemoryPrediction& p, const GridBakeOwners& o) {
  using G = MemoryGroup;
  MemoryPhase out{"outputs", {o.terrain, o.stateOwner, o.recordOwner, o.exposureAfter, o.windKept}};
  if (o.skiTracks) out.owners.push_back({"ski-track texture and its layer", 2.0 * o.skiTexture.bytes, "outputs.ski_track_factor", G::Records});
  out.owners.insert(out.owners.end(), o.writer.begin(), o.writer.end());
  if (o.readBack > 0) out.owners.push_back({"a layer read back for its season range", o.readBack, "outputs.ranges", G::Writers});
  p.phases.push_back(out);
}
}  // namespace

// The bake's phases in order, each with the owners it holds at once (docs/memory.md).
MemoryPrediction predictGridBake(const Scene& s, const GridSpec& spec, size_t occluderTriangles, const SnowReach& reach,
                                 FrameTiming timing) {
  if (timing == FrameTiming::Auto) timing = frameTimingOf(s);
  const GridBakeOwners o = gridBakeOwners(s, spec, occluderTriangles, reach);
  MemoryPrediction p;
  p.libraryBytes = kLibraryBytes;
  addPrecomputePhases(p, o);
  if (s.mode == SceneMode::Occlusion) {
    addOcclusionPhases(p, o);
    return p;
  }
  addSeasonPhases(p, o, s, timing);
  addOutputsPhase(p, o);
  return p;
}

FrameTiming frameTimingOf(const Scene& s) {
  switch (s.frameWriting) {
    case FrameWriting::Beside: return FrameTiming::Beside;
    case FrameWriting::AfterSeason: return FrameTiming::AfterSeason;
    case FrameWriting::Paused: break;
  }
  return FrameTiming::Paused;
}

GridMemoryPlan planGridMemory(const Scene& s, const GridSpec& spec, size_t occluderTriangles, const SnowReach& reach, double budget,
                              FrameTiming timing) {
  GridMemoryPlan plan;
  plan.timing = timing == FrameTiming::Auto ? frameTimingOf(s) : timing;
  plan.prediction = predictGridBake(s, spec, occluderTriangles, reach, plan.timing);
  if (timing != FrameTiming::Auto || s.outputs.frameDays.empty() || plan.prediction.peakBytes() <= budget) return plan;
  // Over the budget as the scene asks: the other ways that fit, the leaner first.
  for (FrameTiming other : {FrameTiming::Paused, FrameTiming::AfterSeason}) {
    if (other == plan.timing) continue;
    MemoryPrediction p = predictGridBake(s, spec, occluderTriangles, reach, other);
    if (p.peakBytes() > budget) continue;
    plan.askedBytes = plan.prediction.peakBytes();
    plan.prediction = std::move(p);
    plan.timing = other;
    return plan;
  }
  return plan;  // refused as the scene asks
}

MemoryPrediction predictMeshBake(const Scene& s, size_t triangles, const double extentM[3]) {
  const FallenSnowSettings& pl = s.meshSnow.placement;
  const double area = std::max(extentM[0], 1e-6) * std::max(extentM[1], 1e-6);
  // Refinement splits some lattice cells in four: at most twice the sites in practice.
  const double sites = 2.0 * area / (pl.siteSpacingM * pl.siteSpacingM);
  const double voxel = s.meshSnow.body.voxelSizeM > 0 ? s.meshSnow.body.voxelSizeM : 0.5 * pl.siteSpacingM;
  const std::string voxelKey = s.meshSnow.body.voxelSizeM > 0 ? "mesh_snow.voxel_size_m" : "mesh_snow.site_spacing_m";
  const double columns = area / (voxel * voxel);
  const double leafLayers = std::ceil((pl.depthM + 6.0 * voxel) / voxel / 8.0) + 1.0;
  MemoryPrediction p;
  p.libraryBytes = kLibraryBytes;
  const MemoryOwner mesh{"mesh and its ray scene", static_cast<double>(triangles) * kMeshTriangleBytes, "terrain.file", MemoryGroup::State};
  const MemoryOwner lattice{"launch-site lattice", sites * kSiteBytes, "mesh_snow.site_spacing_m", MemoryGroup::Scratch};
  p.phases.push_back({"placement", {mesh, lattice}});
  p.phases.push_back({"snow body", {mesh, lattice, {"snow body voxels", columns / 64.0 * leafLayers * kSnowBodyBytesPerLeafSlot, voxelKey, MemoryGroup::Writers}}});
  return p;
}

double memoryBudgetBytes(const Scene& s) {
  if (s.maxMemoryGb) return *s.maxMemoryGb * kGiB;
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  double kib = 0;
  for (std::string unit; meminfo >> key >> kib >> unit;)
    if (key == "MemAvailable:") return 0.8 * kib * 1024.0;
  return 0.8 * 16.0 * kGiB;  // no /proc: assume a 16 GiB machine
}

namespace {
std::string keyWhere(const Scene& s, const std::string& givenKey) {
  // The grid's owners are sized by terrain.size for the builtin terrain, by the file otherwise.
  const std::string key = givenKey == "terrain.size" && !s.terrain.builtin ? "terrain.file" : givenKey;
  if (key == "terrain.file" && s.terrain.declaredAt == "--terrain") return "--terrain " + s.terrain.file;
  return s.keyLocation(key) + ": " + key;
}
}  // namespace

void refuseAboveBudget(const Scene& s, const MemoryPrediction& p, double budget) {
  if (p.peakBytes() <= budget) return;
  const MemoryPhase& phase = p.peakPhase();
  const MemoryOwner& big = phase.largest();
  std::ostringstream o;
  o << std::fixed << std::setprecision(2) << keyWhere(s, big.key) << ": the bake needs about " << p.peakBytes() / kGiB
    << " GiB at its peak (the " << phase.name << ": " << big.name << " " << big.bytes / kGiB << " GiB) and the budget is "
    << budget / kGiB << " GiB (" << (s.maxMemoryGb ? "run.max_memory_gb" : "80 % of the memory available") << "): ";
  if (big.key == "terrain.size" || big.key == "terrain.file" || big.key == "precompute.sun_quality")
    o << "bake a smaller grid (terrain.resample_cell_size_m, terrain.crop_m, terrain.size)";
  else if (big.key == "mesh_snow.site_spacing_m" || big.key == "mesh_snow.voxel_size_m" || big.key == "outputs.vdb_voxel_size_m")
    o << "raise " << big.key;
  else
    o << "lower " << big.key << " or bake a smaller grid";
  o << ", or raise run.max_memory_gb where the machine has the memory";
  throw InputError(o.str());
}

void refuseRanksAboveBudget(const Scene& s, const MemoryPrediction& zero, const RanksMemory& m, double budget) {
  if (m.hereBytes() <= budget) return;
  const MemoryOwner& big = zero.peakPhase().largest();
  std::ostringstream o;
  o << std::fixed << std::setprecision(2) << keyWhere(s, big.key) << ": across " << m.ranks << " ranks, the " << m.ranksHere
    << " on this machine need about " << m.hereBytes() / kGiB << " GiB at once (";
  const bool rankZeroApart = m.rankZeroHere && (m.rankZeroGathers || m.rankZeroBytes != m.otherBytes);
  if (rankZeroApart) o << "rank 0 about " << m.rankZeroBytes / kGiB << " GiB, which " << m.rankZeroHolds << "; ";
  o << (rankZeroApart ? "each other " : m.rankZeroGathers ? "each " : "each, writing its tiles, ") << "about " << m.otherBytes / kGiB << " GiB) and the budget is " << budget / kGiB
    << " GiB (" << (s.maxMemoryGb ? "run.max_memory_gb" : "80 % of the memory available")
    << "): run fewer ranks on each machine, bake a smaller grid (terrain.resample_cell_size_m, terrain.crop_m, terrain.size), or raise "
       "run.max_memory_gb where the machine has the memory";
  throw InputError(o.str());
}

void refuseBeyondTheModel(const Scene& s, const GridSpec& spec) {
  const OutputRequest& o = s.outputs;
  constexpr double kMaxPixels = 2147483647.0;  // 2^31 - 1: images and grids index with int
  if (static_cast<double>(o.displacementWidth) * o.displacementHeight > kMaxPixels)
    throw InputError(keyWhere(s, "outputs.displacement_size") + ": " + std::to_string(o.displacementWidth) + " x " +
                     std::to_string(o.displacementHeight) + " pixels is more than 2^31: lower it");
  if (hasLayer(s, "ski_tracks") && static_cast<double>(spec.width) * o.skiTrackFactor * spec.height * o.skiTrackFactor > kMaxPixels)
    throw InputError(keyWhere(s, "outputs.ski_track_factor") + ": a texture of " + std::to_string(spec.width * int64_t(o.skiTrackFactor)) +
                     " x " + std::to_string(spec.height * int64_t(o.skiTrackFactor)) + " texels is more than 2^31: lower it");
  if (o.vdb) {
    const double vs = vdbVoxelSizeM(o.vdbVoxelSizeM, spec);
    const double columns = spec.width * spec.cellSizeXM / vs, rows = spec.height * spec.cellSizeYM / vs;
    // OpenVDB's coordinates are 32-bit, and the writer visits every column of voxels.
    if (columns > 1e6 || rows > 1e6 || columns * rows > 4e9) {
      std::ostringstream m;
      m << keyWhere(s, "outputs.vdb_voxel_size_m") << ": voxels of " << vs << " m make " << std::fixed << std::setprecision(0) << columns
        << " x " << rows << " columns over the terrain (at most 10^6 a side and 4 x 10^9 in all): use larger voxels";
      throw InputError(m.str());
    }
  }
}

}  // namespace snow
