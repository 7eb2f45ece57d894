// Triangle meshes read through assimp (OBJ, glTF/GLB, FBX, PLY, ...), in metres, z up: terrain
// meshes to rasterise, and occluders for the sun-exposure precompute.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "scene/terrain_source.h"

namespace snow {

struct TriangleMesh {
  std::vector<std::array<float, 3>> positions;  // x east, y north, z up, metres
  std::vector<std::array<uint32_t, 3>> triangles;
  std::string source;
  std::string importer;
  std::array<float, 3> boundsMin{0, 0, 0}, boundsMax{0, 0, 0};
};

// Reads every mesh of the file with node transforms applied; y-up files are turned z-up
// ((x, y, z) -> (x, -z, y)); then scaled and offset. Throws InputError naming the file.
TriangleMesh loadTriangleMesh(const std::string& path, UpAxis upAxis, double scale = 1.0,
                              const std::array<double, 3>& offsetM = {0.0, 0.0, 0.0});

std::vector<TriangleMesh> loadOccluders(const std::vector<OccluderSource>& occluders);

}  // namespace snow
