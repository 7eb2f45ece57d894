// Triangle meshes written by our own code (fast and byte-reproducible; assimp reads every format
// back in the tests): the snow surface of a height field and the snow
// body alone (closed), both from an adaptive triangulation with a vertical error bound (rtin.h),
// or a displaced input mesh. Formats and their axes:
//   "ply"  binary little-endian PLY, z up (as the simulation: x east, y north, z altitude; what
//          Blender's PLY importer keeps)
//   "obj"  Wavefront OBJ without materials, y up ((x, y, z) -> (x, z, -y)): the convention OBJ
//          importers assume (Blender, Maya, Houdini, Unreal)
//   "glb"  binary glTF 2.0, y up as the glTF specification requires ((x, y, z) -> (x, z, -y))
//   "fbx"  ASCII FBX 7.4, y up ((x, y, z) -> (x, z, -y)), metres (UnitScaleFactor 100). ASCII
//          because the binary FBX writer of Debian's assimp 5.2 writes files no reader opens
//          (assimp issue #4686); the FBX SDK (Unreal, Unity, Maya) reads ASCII FBX, Blender's
//          importer does not (use glb).
// Positions in metres; per-vertex normals; UVs (when given) in the maps' frame: u east, v north,
// (0, 0) at the grid's south-west corner, texel centres at ((i + 0.5) / W, 1 - (j + 0.5) / H).
// Written atomically.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/grid.h"

namespace snow {

struct MeshData {
  std::vector<std::array<float, 3>> positions;  // x east, y north, z up, metres
  std::vector<std::array<float, 3>> normals;    // unit, per vertex (empty: computed, area-weighted)
  std::vector<std::array<float, 2>> uvs;        // per vertex, or empty
  std::vector<std::array<uint32_t, 3>> triangles;
};

std::string meshFormatDescription(const std::string& format);

// Writes `path` (its extension should match the format). Throws std::runtime_error on failure.
void writeMesh(const std::string& path, const std::string& format, const MeshData& mesh);

struct RtinMesh;

// The surface `altitude` (e.g. bedrock + snow depth) over the triangulation's triangles: a vertex
// per grid point used, at ((i + 0.5) dx, (H - j - 0.5) dy, altitude), with UVs.
MeshData surfaceMesh(const RtinMesh& triangulation, const Grid<float>& altitude, const GridSpec& spec);

struct MeshCounts {
  size_t vertices = 0, triangles = 0;
};

// The same files as writeMesh(path, format, surfaceMesh(...)) for each (path, format), written as
// the mesh is read from the triangulation: its positions, UVs and indices are never held (a
// quarter of surfaceMesh's bytes beside the triangulation). Returns the mesh's counts.
MeshCounts writeSurfaceMeshes(const std::vector<std::pair<std::string, std::string>>& pathsAndFormats, const RtinMesh& triangulation,
                              const Grid<float>& altitude, const GridSpec& spec);

// The snow body alone, closed: its top (bedrock + depth) over the triangles that hold snow, its
// bottom on the bedrock (facing down), side walls where it meets the grid's edge; where the snow
// ends inside the terrain, top and bottom meet in one vertex. The snow is taken as 0 at grid
// points next to NODATA (the body tapers there), so every edge is shared by exactly two
// triangles. Empty when there is no snow.
MeshData snowBodyMesh(const RtinMesh& triangulation, const Grid<float>& bedrock, const Grid<float>& depth, const Grid<uint8_t>& valid,
                      const GridSpec& spec);

// One tile of a mesh cut into tiles (mesh_tiles.h): `column`/`row` from the west and the north.
struct MeshTile {
  int column = 0, row = 0;
  MeshData mesh;
};

}  // namespace snow
