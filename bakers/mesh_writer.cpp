#include "mesh_writer.h"

#include <assimp/Exporter.hpp>
#include <assimp/material.h>
#include <assimp/scene.h>

#include <cmath>
#include <stdexcept>

#include "core/atomic_file.h"

namespace snow {

const std::vector<std::string>& meshFormats() {
  static const std::vector<std::string> f{"ply", "obj", "glb"};
  return f;
}

std::string meshFormatDescription(const std::string& format) {
  if (format == "ply") return "PLY binary (little endian), positions and normals, metres, z up";
  if (format == "obj") return "Wavefront OBJ (no materials), positions and normals, metres, y up (x, z, -y)";
  if (format == "glb") return "binary glTF 2.0, positions and normals, metres, y up (x, z, -y)";
  throw std::invalid_argument("mesh format '" + format + "' is not one of: ply, obj, glb");
}

namespace {

std::vector<std::array<float, 3>> areaWeightedNormals(const MeshData& m) {
  std::vector<std::array<double, 3>> sum(m.positions.size(), {0.0, 0.0, 0.0});
  for (const auto& t : m.triangles) {
    const auto &a = m.positions[t[0]], &b = m.positions[t[1]], &c = m.positions[t[2]];
    const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
    const double v[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
    const double cr[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    for (int k = 0; k < 3; ++k)
      for (int c2 = 0; c2 < 3; ++c2) sum[t[k]][c2] += cr[c2];
  }
  std::vector<std::array<float, 3>> out(sum.size(), {0.f, 0.f, 1.f});
  for (size_t k = 0; k < sum.size(); ++k) {
    const double len = std::sqrt(sum[k][0] * sum[k][0] + sum[k][1] * sum[k][1] + sum[k][2] * sum[k][2]);
    if (len > 0.0) out[k] = {float(sum[k][0] / len), float(sum[k][1] / len), float(sum[k][2] / len)};
  }
  return out;
}

}  // namespace

void writeMesh(const std::string& path, const std::string& format, const MeshData& m) {
  const char* id = format == "ply" ? "plyb" : format == "obj" ? "objnomtl" : format == "glb" ? "glb2" : nullptr;
  if (!id) throw std::invalid_argument("mesh format '" + format + "' is not one of: ply, obj, glb");
  if (m.positions.empty() || m.triangles.empty()) throw std::runtime_error(path + ": no triangles to write (no valid cells?)");
  const bool yUp = format != "ply";
  const std::vector<std::array<float, 3>> normals = m.normals.size() == m.positions.size() ? m.normals : areaWeightedNormals(m);
  auto axes = [&](const std::array<float, 3>& p) { return yUp ? aiVector3D(p[0], p[2], -p[1]) : aiVector3D(p[0], p[1], p[2]); };

  aiScene scene;  // owns everything below; freed by its destructor
  scene.mRootNode = new aiNode();
  scene.mRootNode->mName = aiString("snow");
  scene.mMaterials = new aiMaterial*[1]{new aiMaterial()};
  scene.mNumMaterials = 1;
  aiString materialName("snow");
  scene.mMaterials[0]->AddProperty(&materialName, AI_MATKEY_NAME);
  auto* mesh = new aiMesh();
  scene.mMeshes = new aiMesh*[1]{mesh};
  scene.mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};
  scene.mRootNode->mNumMeshes = 1;
  mesh->mName = aiString("snow");
  mesh->mMaterialIndex = 0;
  mesh->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  mesh->mNumVertices = static_cast<unsigned>(m.positions.size());
  mesh->mVertices = new aiVector3D[m.positions.size()];
  mesh->mNormals = new aiVector3D[m.positions.size()];
  for (size_t k = 0; k < m.positions.size(); ++k) {
    mesh->mVertices[k] = axes(m.positions[k]);
    mesh->mNormals[k] = axes(normals[k]);
  }
  mesh->mNumFaces = static_cast<unsigned>(m.triangles.size());
  mesh->mFaces = new aiFace[m.triangles.size()];
  for (size_t k = 0; k < m.triangles.size(); ++k) {
    aiFace& f = mesh->mFaces[k];
    f.mNumIndices = 3;
    f.mIndices = new unsigned[3]{m.triangles[k][0], m.triangles[k][1], m.triangles[k][2]};
  }
  Assimp::Exporter exporter;
  const aiExportDataBlob* blob = exporter.ExportToBlob(&scene, id, 0u);
  if (!blob) throw std::runtime_error(path + ": assimp could not export " + format + ": " + exporter.GetErrorString());
  writeTextAtomically(path, std::string(static_cast<const char*>(blob->data), blob->size));
}

MeshData heightfieldMesh(const Grid<float>& altitude, const Grid<uint8_t>& valid, const GridSpec& spec) {
  MeshData m;
  const int w = spec.width, h = spec.height;
  std::vector<uint32_t> index(static_cast<size_t>(w) * h, UINT32_MAX);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      if (!valid(i, j)) continue;
      index[static_cast<size_t>(j) * w + i] = static_cast<uint32_t>(m.positions.size());
      m.positions.push_back({float((i + 0.5) * spec.cellSizeXM), float((h - j - 0.5) * spec.cellSizeYM), altitude(i, j)});
    }
  auto at = [&](int i, int j) { return index[static_cast<size_t>(j) * w + i]; };
  for (int j = 0; j + 1 < h; ++j)
    for (int i = 0; i + 1 < w; ++i) {
      // Rows run south, so (i, j+1) is south of (i, j): counter-clockwise seen from above.
      const uint32_t nw = at(i, j), ne = at(i + 1, j), sw = at(i, j + 1), se = at(i + 1, j + 1);
      if (nw != UINT32_MAX && sw != UINT32_MAX && se != UINT32_MAX) m.triangles.push_back({nw, sw, se});
      if (nw != UINT32_MAX && se != UINT32_MAX && ne != UINT32_MAX) m.triangles.push_back({nw, se, ne});
    }
  m.normals = areaWeightedNormals(m);
  return m;
}

}  // namespace snow
