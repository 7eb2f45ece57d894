// A scene as snowbake understood it: what the scene file (TOML) and the command line asked for,
// validated and in world units. The keys, their bindings to these members and their documentation
// are one table (scene_schema.cpp); scene_file.cpp loads and checks; docs/scene.md is generated
// from the table (snowbake help scene --markdown).
#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/bedform_runs.h"
#include "core/default_terrain.h"
#include "core/parameters.h"
#include "core/weather.h"
#include "mesh_snow_options.h"
#include "raster_ref.h"
#include "scene_enums.h"
#include "terrain_source.h"

namespace snow {

// [outputs.ranges]: how a layer's 16- and 8-bit encodings map values to pixels (docs/outputs.md).
enum class RangeMode : uint8_t { Own, Season, Fixed };
struct LayerRange {
  RangeMode mode = RangeMode::Own;
  double lo = 0.0, hi = 1.0;  // Fixed: in the layer's unit
};
// [outputs.tiles]: every raster output cut into equal tiles (bakers/raster_tiles.h).
struct OutputTiles {
  TileConvention convention = TileConvention::None;
  int sizePx = 0;     // pixels a side (Unreal's list, 2^n + 1 for Unity, any for grid)
  int overlapPx = 1;  // rows and columns neighbours share (Unreal and Unity: 1)
  // resize: the tiles are cut from the layers at this size, written beside the whole files (0: none)
  int resizeWidth = 0, resizeHeight = 0;
};

struct OutputRequest {
  std::vector<std::string> layers{"compacted", "stable", "unstable", "powder", "depth"};
  ImageFormat format = ImageFormat::Exr;  // 32-bit float, one channel, metres
  std::vector<double> frameDays;   // also write the layers at these days (0 = season start)
  std::vector<std::string> encodings;  // also each layer as png16 / png8 / r16, normalised to its range
  bool multichannelExr = false;        // also all layers as the channels of one EXR (layers.exr)
  int displacementWidth = 0, displacementHeight = 0;  // displacement maps at this size (0: none)
  bool vdb = false;                    // the snow body as an OpenVDB file (snow.vdb)
  int skiTrackFactor = 8;              // the ski-track texture's cells per simulation cell, each way
  std::vector<std::string> meshes;     // meshes in these formats: ply / obj / glb / fbx
  std::vector<std::string> meshParts{"surface"};  // surface (snow_surface.EXT) and/or body (snow_body.EXT)
  double meshMaxErrorM = 0.1;          // the adaptive triangulation's vertical error bound
  double meshTileSizeM = 0.0;          // split the surface mesh into square tiles of this size (0: one file)
  double vdbVoxelSizeM = 0.0;          // 0: the grid's smaller cell size
  int compressionLevel = 1;            // PNG zlib and EXR zip level, 0 (none) to 9 (bakers/grid_writer.h)
  bool avalancheMaps = false;      // each avalanche's release zone, scour and deposit
  double avalancheFrameIntervalS = 0.0;  // frames of each avalanche's motion (0: none)
  std::array<double, 2> coverageDepthsM{0.02, 0.15};  // snow_coverage: 0 up to the first depth, 1 from the second
  std::map<std::string, LayerRange> ranges;  // [outputs.ranges] as given; other layers take their kind's default
  OutputTiles tiles;                         // [outputs.tiles]
  int resizeWidth = 0, resizeHeight = 0;     // outputs.resize: the grid layers at this size (0: the grid's)
  std::string normalMapConvention = "opengl";  // snow_normal: opengl (G = +v, north) or directx (G flipped)
};

// mode = "occlusion": Foldes & Benes 2007 (static_snow/occlusion.h), no season.
struct OcclusionParameters {
  double sMaxM = 1.0;
  double tauAmbient = 1.25;
  double tauSun = 0.75;
  int sunPositions = 10;
  int aoRays = 0;                 // 0: by precompute.sun_quality (64 / 256 / 1024)
  double aoRadiusM = 0.0;         // 0: unlimited
  std::optional<double> day;      // season day of the sun trajectory; default the season's middle
  double turbidity = 3.0;
};

// Art direction (docs/models/art-direction.md): painted rasters that set the starting snow, steer the
// season, and edit it on given days.
struct InitialSnowLayer {
  enum class Kind { None, Constant, Raster, Mask };
  Kind kind = Kind::None;
  double depthM = 0.0;  // Constant; Mask: the depth where the mask is 1
  RasterRef raster;     // Raster: depths in metres; Mask: the mask
};

struct EditSpec {
  double day = 0;
  EditOp op = EditOp::Add;
  std::string layer;   // compacted | stable | unstable | powder
  std::string to;      // move: the layer that receives
  std::optional<double> depthM;
  std::optional<RasterRef> mask;  // none: everywhere
  std::string declaredAt;
};

struct Multipliers {
  std::optional<RasterRef> snowfall, melt, windErosion, avalancheRelease, skierSpawn;
  std::optional<RasterRef> noSnow;  // a mask: cells >= 0.5 stay bare
  // The factor rasters, each a float a cell once placed (the no-snow mask is thresholded to bytes).
  static constexpr std::optional<RasterRef> Multipliers::* kFactors[] = {
      &Multipliers::snowfall, &Multipliers::melt, &Multipliers::windErosion, &Multipliers::avalancheRelease, &Multipliers::skierSpawn};
  int factorCount() const {
    int n = 0;
    for (auto factor : kFactors) n += (this->*factor).has_value();
    return n;
  }
  bool any() const { return factorCount() > 0 || noSnow; }
};

// [bedforms]: the slab-saltation bedform model (core/phenomena/bedforms.h) in the season, over the
// whole terrain or inside `mask` (cells >= 0.5), in place of the layered wind transport there.
struct BedformScene {
  bool enabled = false;
  BedformParameters params;
  std::optional<RasterRef> mask;
};

// mode = "mesh": Fearing's snow on the mesh itself ([mesh_snow]; docs/models/snow-on-meshes.md).
struct MeshSnowScene {
  bool onOccluders = false;  // season mode with [mesh_snow]: snow on the [[occluders]] meshes too
  FallenSnowSettings placement;
  FallenSnowStability stability;
  MeshSnowBodyOptions body;
};

struct Scene {
  std::string sourceName;   // the scene file path, or "preset:default"
  std::string baseDir;      // folder relative terrain paths are resolved against
  std::string name = "snowbake scene";
  SceneMode mode = SceneMode::Season;
  OcclusionParameters occlusion;
  MeshSnowScene meshSnow;
  TerrainSource terrain;
  std::vector<OccluderSource> occluders;
  std::optional<double> latitudeDeg;  // site latitude; defaults to the DEM's when it has one
  std::optional<double> longitudeDeg;
  int startYear = 2025, startMonth = 11, startDay = 1;
  double days = 120.0;
  WeatherTimeline weather;
  std::vector<SnowfallPeriod> userSnowfalls;
  // Avalanches asked for in [[events]] (type = "avalanche"): a day and a rupture point, in metres
  // east and south of the grid's north-west corner (position_m) or in the DEM's own projected
  // metres (map_position, easting and northing).
  struct AvalancheEvent {
    double day = 0;
    double xM = 0, yM = 0;
    bool mapCoordinates = false;
    int line = 0;  // where it was given, for messages
    int count = 1;  // skiers: how many, one after the other
    std::optional<RasterRef> mask;  // avalanche: release every unstable cell in it; skier: start cells drawn from it
  };
  std::vector<AvalancheEvent> userAvalanches;
  std::vector<AvalancheEvent> userSkiers;  // [[events]] type = "skier": start point, day, count
  ModelParameters params;
  std::map<std::string, RasterRef> masks;        // [masks.NAME]
  std::array<InitialSnowLayer, 4> initialSnow;   // [initial_snow], by SnowLayer
  Multipliers multipliers;                       // [multipliers]
  std::vector<EditSpec> edits;                   // [[edits]], in day order
  BedformScene bedforms;                         // [bedforms]
  OutputRequest outputs;
  bool sunExposure = true;             // precompute.sun: false skips the sun (temperature from altitude alone)
  std::string sunQuality = "draft";    // precompute.sun_quality: draft | production | reference
  SunMethod sunMethod = SunMethod::Auto;  // precompute.sun_method: auto = horizon sweep unless occluders
  uint64_t seed = 1;
  BackendChoice backend = BackendChoice::Auto;
  int threads = 0;               // 0 = all cores
  std::optional<double> maxMemoryGb;  // run.max_memory_gb; none: 80 % of MemAvailable (bake/memory_model.h)
  FrameWriting frameWriting = FrameWriting::Paused;  // run.frame_writing
  std::map<std::string, std::string> keyLocations;  // "scene.toml:12" of every key given, by dotted path, for messages
  std::string canonicalToml;     // the merged, validated document (hashed into the manifest)

  int startDayOfYear() const;
  // Where `dottedKey` was given ("scene.toml:12"), else the scene's source name (a default).
  std::string keyLocation(const std::string& dottedKey) const;
};

// Loads and validates a scene file. `overrides` are "dotted.key=VALUE" strings from --set,
// applied before validation with the same rules. `terrainFile` (--terrain) replaces the whole
// [terrain] table by `file = terrainFile` (relative to the working folder) before the --set
// overrides, so the scene's builtin keys (size, cell_size_m...) go with it. Throws InputError
// naming the file (or the --set argument), the line and the key.
Scene loadSceneFile(const std::string& path, const std::vector<std::string>& overrides = {},
                    const std::optional<std::string>& terrainFile = std::nullopt);
// Same, from text: `sourceName` names it in messages, `baseDir` resolves relative paths.
Scene loadSceneText(const std::string& text, const std::string& sourceName, const std::string& baseDir,
                    const std::vector<std::string>& overrides = {}, const std::optional<std::string>& terrainFile = std::nullopt);
// "preset:NAME" or a path.
// The scene as scene.resolved.toml writes it (scene_resolved.cpp): canonicalToml with every
// omitted key at its default and every path absolute; loading it gives the same bake.
std::string resolvedSceneToml(const Scene& scene);
Scene loadScene(const std::string& pathOrPreset, const std::vector<std::string>& overrides = {},
                const std::optional<std::string>& terrainFile = std::nullopt);

}  // namespace snow
