// The memory model (memory_model.h): every owner's bytes from the scene and the grid, the
// field sizes from the field table (core/snow_fields.h), the phases of a bake as mode_grid.cpp
// and mode_mesh.cpp run them. The few constants measured rather than counted say so; their
// source is tools/measure-memory.sh (docs/memory.md).
#include "memory_model.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/errors.h"
#include "core/snow_fields.h"
#include "bakers/value_range.h"
#include "precompute/exposure.h"
#include "scene/layers.h"

namespace snow {

namespace {

constexpr double kMiB = 1024.0 * 1024.0;
constexpr double kGiB = 1024.0 * kMiB;
// Measured: the resident set of the program and its libraries (TBB, Embree, OpenVDB, GDAL, OIIO)
// once a bake has touched them, on a 64 x 64 bake (tools/measure-memory.sh).
constexpr double kLibraryBytes = 140.0 * kMiB;
// Measured: bytes a cell the horizon sweep's per-thread line buffers and the wind solver's
// temporaries hold beside the counted grids; Embree's terrain (a grid geometry: 12 bytes of
// vertex a cell and its BVH) a cell, and its BVH bytes per occluder triangle.
constexpr double kSweepScratchPerCell = 16.0;
constexpr double kWindSolverPerCell = 20.0;
constexpr double kEmbreeGridBytesPerCell = 28.0;
constexpr double kEmbreeBytesPerTriangle = 120.0;
// Snow assumed in a VDB column when the voxel count is predicted before the season: 3 m.
constexpr double kVdbDepthM = 3.0;
// OpenVDB: leaves of 8^3 voxels, six grids (level set, density, four layers) and the bool
// topology; a leaf of floats is 2 KiB plus its masks.
constexpr double kVdbLeafBytes = 2112.0;
constexpr int kVdbGrids = 4;  // level set + density + about two layers' leaves per column
// Mesh mode: bytes a lattice site holds (position, normal, coverage, deposit, neighbour links),
// and a triangle of the input mesh with its Embree BVH.
constexpr double kSiteBytes = 160.0;
constexpr double kMeshTriangleBytes = 200.0;
constexpr double kRecordBytes = 4096.0;

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
  uint8_t needs = 0;
  for (const auto& name : o.layers)
    if (const LayerInfo* l = findLayer(name)) needs |= l->needs;
  std::vector<MemoryOwner> w;
  const double layers = static_cast<double>(o.layers.size());
  const double px = outputPixels(o, cells);
  w.push_back({"layers being written", cells * 4.0 * (o.multichannelExr ? layers + 1 : 2.0), o.multichannelExr ? "outputs.multichannel_exr" : "outputs.layers"});
  if (o.resizeWidth > 0) w.push_back({"resized layer and its mask", px * 5.0, "outputs.resize"});
  const bool tiled = o.tiles.convention != TileConvention::None && o.tiles.sizePx > 0;
  w.push_back({tiled ? "tile being written" : "image being written", (tiled ? static_cast<double>(o.tiles.sizePx) * o.tiles.sizePx : px) * 5.0,
               tiled ? "outputs.tiles.size_px" : "outputs.layers"});
  // The splat map: three weights, their mask and the RGBA pixels; the normal map: the surface,
  // its mask and the RGB pixels (one of them at a time).
  const double splat = hasLayer(s, "splat_map") ? px * (3.0 * 4.0 + 1.0 + 4.0) : 0.0;
  const double normal = hasLayer(s, "snow_normal") ? px * (4.0 + 1.0 + 3.0) : 0.0;
  if (splat + normal > 0) w.push_back({"engine map being written", std::max(splat, normal), "outputs.layers"});
  if (!o.encodings.empty()) w.push_back({"encodings", cells * 2.0, "outputs.encodings"});
  if (needs & kNeedsWind) w.push_back({"the day's wind", cells * 16.0, "outputs.layers"});
  if (needs & kNeedsSun) w.push_back({"the day's sun", cells * 4.0, "outputs.layers"});
  if (o.displacementWidth > 0)
    w.push_back({"displacement map", static_cast<double>(o.displacementWidth) * o.displacementHeight * 4.0 + cells * 4.0,
                 "outputs.displacement_size"});
  return w;
}

// Encodings on a "season" range wait for the season's end: each day's layer (at the output size)
// and its mask are held until then, once for each encoding but r32 (floats need no range); the
// ski-track texture (`skiTextureBytes`, its own size) without a mask. The bytes of one day.
double seasonRangeBytesPerDay(const Scene& s, double cells, double skiTextureBytes) {
  const OutputRequest& o = s.outputs;
  const double encodings = static_cast<double>(std::count_if(o.encodings.begin(), o.encodings.end(), [](const std::string& e) { return e != "r32"; }));
  double perDay = 0.0;
  for (const auto& name : o.layers)
    if (const LayerInfo* l = findLayer(name); l && l->kind == LayerKind::Float && rangeOf(o, *l).mode == RangeMode::Season)
      perDay += (l->needs & kNeedsSkiTracks) ? skiTextureBytes : outputPixels(o, cells) * 5.0;
  return perDay * encodings;
}

double vdbBytes(const Scene& s, const GridSpec& spec) {
  if (!s.outputs.vdb) return 0;
  const double vs = s.outputs.vdbVoxelSizeM > 0 ? s.outputs.vdbVoxelSizeM : std::min(spec.cellSizeXM, spec.cellSizeYM);
  const double columns = (spec.width * spec.cellSizeXM / vs) * (spec.height * spec.cellSizeYM / vs);
  const double leafLayers = std::ceil(kVdbDepthM / vs / 8.0) + 1.0;
  return columns / 64.0 * leafLayers * kVdbLeafBytes * kVdbGrids;
}

}  // namespace

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

MemoryPrediction predictGridBake(const Scene& s, const GridSpec& spec, size_t occluderTriangles) {
  const double cells = static_cast<double>(spec.width) * spec.height;
  const OptionalFields present{s};
  const bool occlusion = s.mode == SceneMode::Occlusion;
  const double state = cells * fieldBytes([](FieldRole) { return true; }, present);
  const double backend = cells * fieldBytes([](FieldRole r) { return heldByBackend(r); }, present);
  const MemoryOwner terrain{"terrain", cells * 5.0, "terrain.size"};
  const MemoryOwner stateOwner{"snow state", state, "terrain.size"};
  MemoryPrediction p;
  p.libraryBytes = kLibraryBytes;

  // Precompute: the horizons of every azimuth (or Embree's BVH), the exposure samples, the wind.
  ExposureSettings es;
  es.quality = sunQuality(s.sunQuality);
  es.seasonDays = s.days;
  const bool sweep = s.sunMethod == SunMethod::Horizon || (s.sunMethod == SunMethod::Auto && s.occluders.empty());
  const double samples = (!occlusion && s.sunExposure) ? static_cast<double>(exposureSampleDays(es).size()) : 0.0;
  const MemoryOwner exposure{"exposure samples", cells * 4.0 * (samples > 0 ? 1.0 + 2.0 * samples : 0.0), "precompute.sun_quality"};
  size_t windStates = 0;
  {
    std::vector<std::pair<double, double>> seen;
    for (const auto& k : s.weather.keyframes)
      if (k.state.windSpeedMps > 0.0 && std::find(seen.begin(), seen.end(), std::make_pair(k.state.windDirectionDeg, k.state.windSpeedMps)) == seen.end())
        seen.emplace_back(k.state.windDirectionDeg, k.state.windSpeedMps);
    windStates = occlusion ? 0 : seen.size();
  }
  const MemoryOwner wind{"wind fields", cells * 20.0 * static_cast<double>(windStates), "weather.keyframe"};
  const double rayScene = cells * kEmbreeGridBytesPerCell + static_cast<double>(occluderTriangles) * kEmbreeBytesPerTriangle;
  MemoryPhase pre{"precompute", {terrain, stateOwner}};
  if (samples > 0) {
    if (sweep)
      pre.owners.push_back({"horizon angles", cells * (4.0 * 5.0 * es.quality.azimuths + 12.0 + kSweepScratchPerCell), "precompute.sun_quality"});
    else
      pre.owners.push_back({"ray scene (Embree)", rayScene, "precompute.sun_method"});
    pre.owners.push_back(exposure);
  }
  if (windStates > 0) pre.owners.push_back({"wind solver", cells * kWindSolverPerCell + wind.bytes, "weather.keyframe"});
  p.phases.push_back(pre);

  std::vector<MemoryOwner> writer = writerOwners(s, cells);
  const double track = s.outputs.skiTrackFactor;
  const bool skiTracks = hasLayer(s, "ski_tracks");
  const MemoryOwner skiTexture{"ski-track texture", skiTracks ? cells * track * track * 4.0 : 0.0, "outputs.ski_track_factor"};
  // The frames (and, once written, the season's end) whose encodings wait for a "season" range.
  const double heldPerDay = seasonRangeBytesPerDay(s, cells, skiTexture.bytes);
  if (occlusion) {
    MemoryPhase occ{"occlusion", {terrain, stateOwner,
                                  {"ray scene (Embree)", rayScene, "terrain.size"},
                                  {"ray origins and normals", cells * 25.0, "terrain.size"},
                                  {"occlusion fields", cells * 16.0, "terrain.size"}}};
    p.phases.push_back(occ);
    MemoryPhase out{"outputs", {terrain, stateOwner, {"occlusion fields", cells * 16.0, "terrain.size"}}};
    out.owners.insert(out.owners.end(), writer.begin(), writer.end());
    if (s.outputs.vdb) out.owners.push_back({"VDB", vdbBytes(s, spec), "outputs.vdb_voxel_size_m"});
    p.phases.push_back(out);
    return p;
  }

  // The season: the state, the backend's copies and scratch, the avalanche runner's two copies
  // of the state and its scratch, the route map, a frame in flight.
  MemoryPhase season{"season", {terrain, stateOwner, exposure, wind,
                                {"backend fields", backend, "terrain.size"},
                                {"backend scratch", cells * (scratchBytes(true, true) + 16.0), "terrain.size"},
                                {"avalanche runner", 2.0 * state + cells * (scratchBytes(false, true) + 28.0), "terrain.size"},
                                {"ski route map", cells * 28.0, "parameters.skiers_per_hour"}}};
  if (skiTracks) season.owners.push_back(skiTexture);
  {
    // Each skier's record (its refined track, about 4 KiB) and each scene avalanche's.
    double skiers = s.params.skiersPerHour * s.params.skiHoursPerDay * s.days;
    for (const auto& e : s.userSkiers) skiers += e.count;
    season.owners.push_back({"skier and avalanche records", (skiers + static_cast<double>(s.userAvalanches.size())) * kRecordBytes,
                             "parameters.skiers_per_hour"});
  }
  if (!s.outputs.frameDays.empty()) {
    // Two copies of the state (the season's snapshot and the writer's), and of the texture the
    // writer's copy and the ski_tracks layer computed from it.
    season.owners.push_back({"frame in flight: state copies", 2.0 * state, "outputs.frames_days"});
    if (skiTracks) season.owners.push_back({"frame in flight: ski-track texture copies", 2.0 * skiTexture.bytes, "outputs.ski_track_factor"});
    for (const auto& w : writer) season.owners.push_back({"frame in flight: " + w.name, w.bytes, w.key});
    season.owners.push_back({"frames held for their season range", heldPerDay * static_cast<double>(s.outputs.frameDays.size()), "outputs.ranges"});
  }
  p.phases.push_back(season);

  MemoryPhase out{"outputs", {terrain, stateOwner, exposure, wind, {"backend fields", backend, "terrain.size"}}};
  if (skiTracks) out.owners.push_back({"ski-track texture and its layer", 2.0 * skiTexture.bytes, "outputs.ski_track_factor"});
  out.owners.insert(out.owners.end(), writer.begin(), writer.end());
  out.owners.push_back({"days held for their season range", heldPerDay * static_cast<double>(s.outputs.frameDays.size() + 1), "outputs.ranges"});
  if (s.outputs.vdb) out.owners.push_back({"VDB", vdbBytes(s, spec), "outputs.vdb_voxel_size_m"});
  p.phases.push_back(out);
  return p;
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
  const MemoryOwner mesh{"mesh and its ray scene", static_cast<double>(triangles) * kMeshTriangleBytes, "terrain.file"};
  p.phases.push_back({"placement", {mesh, {"launch-site lattice", sites * kSiteBytes, "mesh_snow.site_spacing_m"}}});
  p.phases.push_back({"snow body", {mesh, {"launch-site lattice", sites * kSiteBytes, "mesh_snow.site_spacing_m"},
                                    {"snow body voxels", columns / 64.0 * leafLayers * kVdbLeafBytes * 3.0, voxelKey}}});
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
  const auto it = s.keyLocations.find(key);
  return (it != s.keyLocations.end() ? it->second : s.sourceName) + ": " + key;
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
    const double vs = o.vdbVoxelSizeM > 0 ? o.vdbVoxelSizeM : std::min(spec.cellSizeXM, spec.cellSizeYM);
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
