// Triangle meshes out through assimp's exporters: the snow surface of a height field (a regular
// triangulation of the valid cells) or a displaced input mesh. Formats and their axes:
//   "ply"  binary little-endian PLY, z up (as the simulation: x east, y north, z altitude; what
//          Blender's PLY importer keeps)
//   "obj"  Wavefront OBJ without materials, y up ((x, y, z) -> (x, z, -y)): the convention OBJ
//          importers assume (Blender, Maya, Houdini, Unreal)
//   "glb"  binary glTF 2.0, y up as the glTF specification requires ((x, y, z) -> (x, z, -y))
// Positions in metres; per-vertex normals. Written atomically.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/grid.h"

namespace snow {

struct MeshData {
  std::vector<std::array<float, 3>> positions;  // x east, y north, z up, metres
  std::vector<std::array<float, 3>> normals;    // unit, per vertex (empty: computed, area-weighted)
  std::vector<std::array<uint32_t, 3>> triangles;
};

const std::vector<std::string>& meshFormats();  // ply, obj, glb
std::string meshFormatDescription(const std::string& format);

// Writes `path` (its extension should match the format). Throws std::runtime_error on failure.
void writeMesh(const std::string& path, const std::string& format, const MeshData& mesh);

// The surface `altitude` (e.g. bedrock + snow depth) of the valid cells, a vertex per cell at
// ((i + 0.5) dx, (H - j - 0.5) dy, altitude), two triangles per 2 x 2 block of valid cells.
MeshData heightfieldMesh(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec);

}  // namespace snow
