#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

#include "core/errors.h"
#include "mesh.h"
#include "terrain_loader.h"

namespace snow {

TriangleMesh loadTriangleMesh(const std::string& path, UpAxis upAxis, double scale,
                              const std::array<double, 3>& offsetM) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path + ": mesh file does not exist");
  if (std::filesystem::file_size(path, ec) == 0) throw InputError(path + ": mesh file is empty");
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_PreTransformVertices |
                                                     aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->mRootNode)
    throw InputError(path + ": cannot read as a mesh: " + importer.GetErrorString());
  TriangleMesh mesh;
  mesh.source = path;
  mesh.importer = "assimp";
  const bool yUp = upAxis == UpAxis::Y;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D p = am->mVertices[v];
      const double x = p.x, y = yUp ? -p.z : p.y, z = yUp ? p.y : p.z;
      const std::array<float, 3> q{static_cast<float>(x * scale + offsetM[0]), static_cast<float>(y * scale + offsetM[1]),
                                   static_cast<float>(z * scale + offsetM[2])};
      if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2]))
        throw InputError(path + ": vertex " + std::to_string(v) + " of mesh " + std::to_string(m) + " is not finite");
      mesh.positions.push_back(q);
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;
      mesh.triangles.push_back({base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
    }
  }
  if (mesh.triangles.empty()) throw InputError(path + ": has no triangles");
  mesh.boundsMin = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                    std::numeric_limits<float>::infinity()};
  mesh.boundsMax = {-mesh.boundsMin[0], -mesh.boundsMin[1], -mesh.boundsMin[2]};
  for (const auto& p : mesh.positions)
    for (int k = 0; k < 3; ++k) {
      mesh.boundsMin[k] = std::min(mesh.boundsMin[k], p[k]);
      mesh.boundsMax[k] = std::max(mesh.boundsMax[k], p[k]);
    }
  return mesh;
}

std::vector<TriangleMesh> loadOccluders(const std::vector<OccluderSource>& occluders) {
  std::vector<TriangleMesh> meshes;
  for (const auto& o : occluders) meshes.push_back(loadTriangleMesh(o.file, o.upAxis, o.scale, o.offsetM));
  return meshes;
}

// The topmost surface of a mesh sampled at cell centres: for every triangle, the cells whose
// centre falls inside its xy projection get its plane's height there, keeping the highest.
// Cells no triangle covers are NODATA. The grid covers the mesh's xy bounds.
Terrain loadMeshTerrain(const TerrainSource& src) {
  const std::string& path = src.file;
  if (!src.cellSizeM) throw InputError(path + ": a mesh terrain needs terrain.cell_size_m (the raster's cell size in metres)");
  const double cell = *src.cellSizeM;
  const TriangleMesh mesh = loadTriangleMesh(path, src.upAxis);
  const double minX = mesh.boundsMin[0], maxX = mesh.boundsMax[0], minY = mesh.boundsMin[1], maxY = mesh.boundsMax[1];
  const int64_t w = static_cast<int64_t>(std::ceil((maxX - minX) / cell - 1e-9));
  const int64_t h = static_cast<int64_t>(std::ceil((maxY - minY) / cell - 1e-9));
  checkGridSize(path, w, h);
  Terrain t;
  t.heightsM.resize(static_cast<int>(w), static_cast<int>(h), -std::numeric_limits<float>::infinity());
  t.valid.resize(static_cast<int>(w), static_cast<int>(h), 0);
  for (const auto& tri : mesh.triangles) {
    const auto& a = mesh.positions[tri[0]];
    const auto& b = mesh.positions[tri[1]];
    const auto& c = mesh.positions[tri[2]];
    const double det = (static_cast<double>(b[1]) - c[1]) * (static_cast<double>(a[0]) - c[0]) +
                       (static_cast<double>(c[0]) - b[0]) * (static_cast<double>(a[1]) - c[1]);
    if (std::abs(det) < 1e-12) continue;  // vertical or degenerate: no top surface
    const double tMinX = std::min({a[0], b[0], c[0]}), tMaxX = std::max({a[0], b[0], c[0]});
    const double tMinY = std::min({a[1], b[1], c[1]}), tMaxY = std::max({a[1], b[1], c[1]});
    // Columns whose centre minX + (i + 0.5) cell lies in [tMinX, tMaxX]; rows count from the north.
    const int i0 = std::max<int>(0, static_cast<int>(std::ceil((tMinX - minX) / cell - 0.5)));
    const int i1 = std::min<int>(static_cast<int>(w) - 1, static_cast<int>(std::floor((tMaxX - minX) / cell - 0.5)));
    const int j0 = std::max<int>(0, static_cast<int>(std::ceil((maxY - tMaxY) / cell - 0.5)));
    const int j1 = std::min<int>(static_cast<int>(h) - 1, static_cast<int>(std::floor((maxY - tMinY) / cell - 0.5)));
    for (int j = j0; j <= j1; ++j) {
      const double py = maxY - (j + 0.5) * cell;
      for (int i = i0; i <= i1; ++i) {
        const double px = minX + (i + 0.5) * cell;
        const double l1 = ((static_cast<double>(b[1]) - c[1]) * (px - c[0]) + (static_cast<double>(c[0]) - b[0]) * (py - c[1])) / det;
        const double l2 = ((static_cast<double>(c[1]) - a[1]) * (px - c[0]) + (static_cast<double>(a[0]) - c[0]) * (py - c[1])) / det;
        const double l3 = 1.0 - l1 - l2;
        const double eps = -1e-9;
        if (l1 < eps || l2 < eps || l3 < eps) continue;
        const float z = static_cast<float>(l1 * a[2] + l2 * b[2] + l3 * c[2]);
        if (z > t.heightsM(i, j)) {
          t.heightsM(i, j) = z;
          t.valid(i, j) = 1;
        }
      }
    }
  }
  t.info.source = path;
  t.info.format = "mesh";
  t.info.driver = "assimp, " + std::to_string(mesh.triangles.size()) + " triangles, " + enumName(src.upAxis) + "-up";
  t.info.spec.width = static_cast<int>(w);
  t.info.spec.height = static_cast<int>(h);
  t.info.spec.cellSizeXM = t.info.spec.cellSizeYM = cell;
  t.info.spec.originX = minX;
  t.info.spec.originY = maxY;
  t.info.nativeCellSizeX = t.info.nativeCellSizeY = cell;
  t.info.nativeUnit = "metre (terrain.cell_size_m)";
  t.info.nativeWidth = static_cast<int>(w);
  t.info.nativeHeight = static_cast<int>(h);
  t.info.coordinateSystem = "mesh units taken as metres";
  t.info.coordinateDecision = "mesh rasterised at cell centres, topmost surface; cells with no surface are NODATA";
  updateTerrainStatistics(t);
  return t;
}

}  // namespace snow
