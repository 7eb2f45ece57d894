// Where a terrain comes from and how to read it: what the scene's [terrain] table (or --terrain)
// says. Documented in docs/terrain.md.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/default_terrain.h"
#include "scene_enums.h"

namespace snow {

struct TerrainSource {
  std::string file;          // path (resolved against the scene file's folder); empty for builtin
  bool builtin = false;      // the embedded ridged-noise range
  DefaultTerrainOptions builtinOptions;
  std::string declaredAt;    // "scene.toml:4" for error messages

  // "auto" picks by extension: .r16/.r32/.raw raw, .png/.exr heightmap, .obj/.gltf/.glb/.fbx/.ply
  // mesh, anything else a DEM through GDAL (a .tif with heightmap keys is read as a heightmap).
  TerrainFormat format = TerrainFormat::Auto;
  TerrainCoordinates coordinates = TerrainCoordinates::Auto;  // DEMs without a coordinate system
  bool fillNodata = false;            // fill NODATA holes instead of masking them out
  std::optional<double> cellSizeM;    // heightmaps, raw files and meshes (and builtin)
  std::optional<std::array<double, 2>> heightRangeM;  // pixel value 0..1 -> [min, max] metres
  std::optional<double> heightScaleM;   // height = offset + scale * value
  std::optional<double> heightOffsetM;
  int rawWidth = 0, rawHeight = 0;      // raw files
  ByteOrder byteOrder = ByteOrder::Little;  // raw files
  UpAxis upAxis = UpAxis::Z;            // meshes (glTF is y-up)
  // A window [west, north, east, south] in metres east and south of the grid's north-west corner:
  // the cells whose centres lie inside it (applied before resampling).
  std::optional<std::array<double, 4>> cropM;
  // Heights allowed after scale and offset, metres (the Earth's surface with a margin): a file
  // outside them is refused as hostile or in other units.
  std::array<double, 2> heightLimitsM{-12000.0, 10000.0};
  int band = 0;  // which band (DEMs) or channel (heightmaps), from 1; 0: the file must have one
  std::optional<double> resampleCellSizeM;        // bake at another cell size ...
  std::optional<std::array<int, 2>> resampleSize; // ... or another grid size [width, height]

  bool hasHeightmapKeys() const { return heightRangeM || heightScaleM || heightOffsetM; }
};

// A mesh that blocks the sun (rocks, buildings, trees), placed in the terrain's local frame:
// x east from the west edge, y north from the south edge, z altitude, metres.
struct OccluderSource {
  std::string file;
  UpAxis upAxis = UpAxis::Z;
  std::array<double, 3> offsetM{0.0, 0.0, 0.0};
  double scale = 1.0;
  std::string declaredAt;
};

}  // namespace snow
