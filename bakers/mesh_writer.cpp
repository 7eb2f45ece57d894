#include "mesh_writer.h"

#include <bit>
#include <cmath>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <ostream>
#include <string_view>
#include <unordered_map>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/mesh_normals.h"
#include "rtin.h"

namespace snow {

std::string meshFormatDescription(const std::string& format) {
  if (format == "ply") return "PLY binary (little endian), positions, normals and UVs (s, t), metres, z up";
  if (format == "obj") return "Wavefront OBJ (no materials), positions, normals and UVs, metres, y up (x, z, -y)";
  if (format == "glb") return "binary glTF 2.0, positions, normals and UVs, metres, y up (x, z, -y)";
  if (format == "fbx") return "ASCII FBX 7.4, positions, normals and UVs, metres (UnitScaleFactor 100), y up (x, z, -y)";
  throw std::invalid_argument("mesh format '" + format + "' is not one of: ply, obj, glb, fbx");
}


namespace {

// (x, y, z) z up -> (x, z, -y) y up.
std::array<float, 3> yUp(const std::array<float, 3>& p) { return {p[0], p[2], -p[1]}; }

// A file's bytes (formatted text or binary records) put through a cursor into a fixed chunk
// that is written out whenever the next item might not fit: no capacity test per character, and
// no buffer the size of the file (a 4-million-triangle body is a 450 MB OBJ).
class ChunkStream {
 public:
  explicit ChunkStream(std::ostream& out) : out_(out), chunk_(kChunk), at_(chunk_.data()) {}
  // Makes room for `bytes` more characters (at most kRoom) before the cursor is used directly.
  char* room(size_t bytes) {
    if (static_cast<size_t>(chunk_.data() + chunk_.size() - at_) < bytes) flush();
    return at_;
  }
  void advanceTo(char* p) { at_ = p; }
  ChunkStream& operator<<(std::string_view s) {
    if (s.size() > kRoom) {
      flush();
      out_.write(s.data(), static_cast<std::streamsize>(s.size()));
      return *this;
    }
    std::memcpy(room(s.size()), s.data(), s.size());
    at_ += s.size();
    return *this;
  }
  ChunkStream& operator<<(char c) {
    *room(1) = c;
    ++at_;
    return *this;
  }
  // Shortest round-trip decimal.
  ChunkStream& operator<<(float v) {
    char* p = room(kNumberChars);
    at_ = std::to_chars(p, p + kNumberChars, v).ptr;
    return *this;
  }
  ChunkStream& operator<<(long long v) {
    char* p = room(kNumberChars);
    at_ = std::to_chars(p, p + kNumberChars, v).ptr;
    return *this;
  }
  void flush() {
    out_.write(chunk_.data(), at_ - chunk_.data());
    at_ = chunk_.data();
  }
  static constexpr size_t kNumberChars = 24, kRoom = 4096, kChunk = 1 << 20;

 private:
  std::ostream& out_;
  std::vector<char> chunk_;
  char* at_;
};

// Writes `path` atomically through a ChunkStream.
void writeChunked(const std::string& path, const std::function<void(ChunkStream&)>& body) {
  writeStreamAtomically(path, [&](std::ostream& file) {
    ChunkStream out(file);
    body(out);
    out.flush();
  });
}

// Binary glTF 2.0 written directly (assimp's exporter took seconds a million triangles): one
// mesh, one primitive, POSITION / NORMAL / TEXCOORD_0 (glTF's v runs down the image) and uint32
// indices, a plain snow material. Streamed: the buffer's layout is known before it is written.
template <class Mesh>
void writeGlb(ChunkStream& out, const Mesh& m) {
  const size_t n = m.vertices(), t = m.triangles();
  const bool uv = m.hasUvs();
  std::array<float, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  for (size_t k = 0; k < n; ++k) {
    const auto q = yUp(m.position(k));
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], q[c]), hi[c] = std::max(hi[c], q[c]);
  }
  // Positions, normals, UVs, indices: every piece a multiple of 4 bytes, so no padding between.
  const size_t normalOffset = n * 12, uvOffset = 2 * n * 12, indexOffset = uvOffset + (uv ? n * 8 : 0);
  const size_t binLength = indexOffset + t * 12;
  auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return std::string(buf);
  };
  std::string json = "{\"asset\":{\"version\":\"2.0\",\"generator\":\"snowbake\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
                     "\"nodes\":[{\"mesh\":0,\"name\":\"snow\"}],\"meshes\":[{\"name\":\"snow\",\"primitives\":[{\"attributes\":{"
                     "\"POSITION\":0,\"NORMAL\":1" + std::string(uv ? ",\"TEXCOORD_0\":2" : "") + "},\"indices\":" + (uv ? "3" : "2") +
                     ",\"mode\":4,\"material\":0}]}],\"materials\":[{\"name\":\"snow\",\"pbrMetallicRoughness\":{\"baseColorFactor\":"
                     "[0.95,0.96,0.98,1],\"metallicFactor\":0,\"roughnessFactor\":0.8}}],\"buffers\":[{\"byteLength\":" +
                     std::to_string(binLength) + "}],\"bufferViews\":[";
  auto view = [&](size_t offset, size_t length, int target) {
    return "{\"buffer\":0,\"byteOffset\":" + std::to_string(offset) + ",\"byteLength\":" + std::to_string(length) + ",\"target\":" +
           std::to_string(target) + "}";
  };
  // Appended piece by piece (GCC 12 warns falsely, -Wrestrict, on "," + std::string&&).
  json += view(0, n * 12, 34962);
  json += ',';
  json += view(normalOffset, n * 12, 34962);
  if (uv) {
    json += ',';
    json += view(uvOffset, n * 8, 34962);
  }
  json += ',';
  json += view(indexOffset, t * 12, 34963);
  json += "],\"accessors\":[";
  json += "{\"bufferView\":0,\"componentType\":5126,\"count\":" + std::to_string(n) + ",\"type\":\"VEC3\",\"min\":[" + num(lo[0]) + "," +
          num(lo[1]) + "," + num(lo[2]) + "],\"max\":[" + num(hi[0]) + "," + num(hi[1]) + "," + num(hi[2]) + "]},";
  json += "{\"bufferView\":1,\"componentType\":5126,\"count\":" + std::to_string(n) + ",\"type\":\"VEC3\"},";
  if (uv) json += "{\"bufferView\":2,\"componentType\":5126,\"count\":" + std::to_string(n) + ",\"type\":\"VEC2\"},";
  json += "{\"bufferView\":" + std::string(uv ? "3" : "2") + ",\"componentType\":5125,\"count\":" + std::to_string(3 * t) +
          ",\"type\":\"SCALAR\"}]}";
  while (json.size() % 4) json.push_back(' ');
  auto u32 = [&](uint32_t v) { out << std::string_view(reinterpret_cast<const char*>(&v), 4); };
  auto bytes = [&](const void* p, size_t size) { out << std::string_view(static_cast<const char*>(p), size); };
  u32(0x46546C67u);  // "glTF"
  u32(2);
  u32(static_cast<uint32_t>(12 + 8 + json.size() + 8 + binLength));
  u32(static_cast<uint32_t>(json.size()));
  u32(0x4E4F534Au);  // "JSON"
  out << json;
  u32(static_cast<uint32_t>(binLength));
  u32(0x004E4942u);  // "BIN"
  for (size_t k = 0; k < n; ++k) bytes(yUp(m.position(k)).data(), 12);
  for (size_t k = 0; k < n; ++k) bytes(yUp(m.normal(k)).data(), 12);
  if (uv)
    for (size_t k = 0; k < n; ++k) {
      const auto u = m.uv(k);
      const float q[2] = {u[0], 1.f - u[1]};
      bytes(q, 8);
    }
  for (size_t k = 0; k < t; ++k) bytes(m.triangle(k).data(), 12);
}

// Wavefront OBJ written directly (shortest round-trip decimal of each float), y up.
template <class Mesh>
void writeObj(ChunkStream& out, const Mesh& m) {
  const bool uv = m.hasUvs();
  const size_t n = m.vertices();
  out << "# snowbake snow mesh: metres, y up (x east, y altitude, z south)\no snow\n";
  for (size_t k = 0; k < n; ++k) {
    const auto q = yUp(m.position(k));
    out << "v " << q[0] << ' ' << q[1] << ' ' << q[2] << '\n';
  }
  if (uv)
    for (size_t k = 0; k < n; ++k) {
      const auto u = m.uv(k);
      out << "vt " << u[0] << ' ' << u[1] << '\n';
    }
  for (size_t k = 0; k < n; ++k) {
    const auto q = yUp(m.normal(k));
    out << "vn " << q[0] << ' ' << q[1] << ' ' << q[2] << '\n';
  }
  for (size_t k = 0; k < m.triangles(); ++k) {
    const std::array<uint32_t, 3> tri = m.triangle(k);
    // "f a/a/a b/b/b c/c/c" (or "a//a" without UVs): each index formatted once and copied.
    char* q = out.room(3 * (1 + 3 * 11 + 2) + 2);
    *q++ = 'f';
    for (uint32_t v : tri) {
      *q++ = ' ';
      char* const start = q;
      q = std::to_chars(q, q + 11, v + 1).ptr;
      const size_t digits = static_cast<size_t>(q - start);
      *q++ = '/';
      if (uv) {
        std::memcpy(q, start, digits);
        q += digits;
      }
      *q++ = '/';
      std::memcpy(q, start, digits);
      q += digits;
    }
    *q++ = '\n';
    out.advanceTo(q);
  }
}

// Binary PLY (little endian, z up) written directly (assimp's exporter took over a second a
// million triangles): x y z, nx ny nz and s t per vertex, faces as uchar-counted int lists, the
// header assimp writes and Blender, Houdini, MeshLab and assimp read.
template <class Mesh>
void writePly(ChunkStream& out, const Mesh& m) {
  const bool uv = m.hasUvs();
  out << "ply\nformat binary_little_endian 1.0\ncomment snowbake snow mesh: metres, z up (x east, y north)\nelement vertex "
      << static_cast<long long>(m.vertices())
      << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n";
  if (uv) out << "property float s\nproperty float t\n";
  out << "element face " << static_cast<long long>(m.triangles()) << "\nproperty list uchar int vertex_index\nend_header\n";
  // The floats' and ints' bytes are copied as they are: little-endian hosts only (x86-64, ARM64).
  static_assert(std::endian::native == std::endian::little, "the PLY writer copies little-endian bytes");
  const size_t vertexBytes = uv ? 32 : 24;
  for (size_t k = 0; k < m.vertices(); ++k) {
    char* q = out.room(vertexBytes);
    std::memcpy(q, m.position(k).data(), 12);
    std::memcpy(q + 12, m.normal(k).data(), 12);
    if (uv) std::memcpy(q + 24, m.uv(k).data(), 8);
    out.advanceTo(q + vertexBytes);
  }
  for (size_t k = 0; k < m.triangles(); ++k) {
    char* q = out.room(13);
    *q = 3;
    std::memcpy(q + 1, m.triangle(k).data(), 12);
    out.advanceTo(q + 13);
  }
}

// ASCII FBX 7.4 written directly (assimp's writer took 25 s a million triangles and its binary
// one writes unreadable files): one mesh geometry with per-vertex normals and UVs, one model, one
// material; y up, metres (UnitScaleFactor 100: FBX counts in centimetres).
template <class Mesh>
void writeFbx(ChunkStream& out, const Mesh& m) {
  const size_t n = m.vertices();
  auto num = [&](float v) { out << v; };
  auto integer = [&](long long v) { out << v; };
  out << "; FBX 7.4.0 project file\n; snowbake snow mesh: metres, y up (x east, y altitude, z south)\n"
         "FBXHeaderExtension:  {\n\tFBXHeaderVersion: 1003\n\tFBXVersion: 7400\n\tCreator: \"snowbake\"\n}\n"
         "GlobalSettings:  {\n\tVersion: 1000\n\tProperties70:  {\n"
         "\t\tP: \"UpAxis\", \"int\", \"Integer\", \"\",1\n\t\tP: \"UpAxisSign\", \"int\", \"Integer\", \"\",1\n"
         "\t\tP: \"FrontAxis\", \"int\", \"Integer\", \"\",2\n\t\tP: \"FrontAxisSign\", \"int\", \"Integer\", \"\",1\n"
         "\t\tP: \"CoordAxis\", \"int\", \"Integer\", \"\",0\n\t\tP: \"CoordAxisSign\", \"int\", \"Integer\", \"\",1\n"
         "\t\tP: \"UnitScaleFactor\", \"double\", \"Number\", \"\",100\n\t\tP: \"OriginalUnitScaleFactor\", \"double\", \"Number\", \"\",100\n"
         "\t}\n}\n"
         "Definitions:  {\n\tVersion: 100\n\tCount: 3\n\tObjectType: \"Model\" {\n\t\tCount: 1\n\t}\n"
         "\tObjectType: \"Geometry\" {\n\t\tCount: 1\n\t}\n\tObjectType: \"Material\" {\n\t\tCount: 1\n\t}\n}\n"
         "Objects:  {\n\tGeometry: 1000, \"Geometry::snow\", \"Mesh\" {\n\t\tVertices: *";
  integer(static_cast<long long>(3 * n));
  out << " {\n\t\t\ta: ";
  bool first = true;
  for (size_t k = 0; k < n; ++k)
    for (float c : yUp(m.position(k))) {
      if (!first) out << ',';
      first = false;
      num(c);
    }
  out << "\n\t\t}\n\t\tPolygonVertexIndex: *";
  integer(static_cast<long long>(3 * m.triangles()));
  out << " {\n\t\t\ta: ";
  first = true;
  for (size_t k = 0; k < m.triangles(); ++k) {
    const std::array<uint32_t, 3> t = m.triangle(k);
    if (!first) out << ',';
    first = false;
    integer(t[0]);
    out << ',';
    integer(t[1]);
    out << ',';
    integer(-static_cast<long long>(t[2]) - 1);  // the last index of a polygon, negated minus one
  }
  out << "\n\t\t}\n\t\tGeometryVersion: 124\n\t\tLayerElementNormal: 0 {\n\t\t\tVersion: 101\n\t\t\tName: \"\"\n"
         "\t\t\tMappingInformationType: \"ByVertice\"\n\t\t\tReferenceInformationType: \"Direct\"\n\t\t\tNormals: *";
  integer(static_cast<long long>(3 * n));
  out << " {\n\t\t\t\ta: ";
  first = true;
  for (size_t k = 0; k < n; ++k)
    for (float c : yUp(m.normal(k))) {
      if (!first) out << ',';
      first = false;
      num(c);
    }
  out << "\n\t\t\t}\n\t\t}\n";
  const bool uv = m.hasUvs();
  if (uv) {
    out << "\t\tLayerElementUV: 0 {\n\t\t\tVersion: 101\n\t\t\tName: \"UVMap\"\n\t\t\tMappingInformationType: \"ByVertice\"\n"
           "\t\t\tReferenceInformationType: \"Direct\"\n\t\t\tUV: *";
    integer(static_cast<long long>(2 * n));
    out << " {\n\t\t\t\ta: ";
    first = true;
    for (size_t k = 0; k < n; ++k)
      for (float c : m.uv(k)) {
        if (!first) out << ',';
        first = false;
        num(c);
      }
    out << "\n\t\t\t}\n\t\t}\n";
  }
  out << "\t\tLayer: 0 {\n\t\t\tVersion: 100\n\t\t\tLayerElement:  {\n\t\t\t\tType: \"LayerElementNormal\"\n\t\t\t\tTypedIndex: 0\n\t\t\t}\n";
  if (uv) out << "\t\t\tLayerElement:  {\n\t\t\t\tType: \"LayerElementUV\"\n\t\t\t\tTypedIndex: 0\n\t\t\t}\n";
  out << "\t\t}\n\t}\n"
         "\tModel: 2000, \"Model::snow\", \"Mesh\" {\n\t\tVersion: 232\n\t\tProperties70:  {\n\t\t}\n\t\tShading: T\n"
         "\t\tCulling: \"CullingOff\"\n\t}\n"
         "\tMaterial: 3000, \"Material::snow\", \"\" {\n\t\tVersion: 102\n\t\tShadingModel: \"lambert\"\n\t\tMultiLayer: 0\n"
         "\t\tProperties70:  {\n\t\t\tP: \"DiffuseColor\", \"Color\", \"\", \"A\",0.95,0.96,0.98\n\t\t}\n\t}\n}\n"
         "Connections:  {\n\tC: \"OO\",2000,0\n\tC: \"OO\",1000,2000\n\tC: \"OO\",3000,2000\n}\n";
}

}  // namespace

namespace {

// What the writers read of a MeshData: its arrays, and its own normals in place where it has
// them (a copy is the mesh's size again).
struct MeshDataReader {
  const MeshData& m;
  std::vector<std::array<float, 3>> computed;
  size_t vertices() const { return m.positions.size(); }
  size_t triangles() const { return m.triangles.size(); }
  bool hasUvs() const { return m.uvs.size() == m.positions.size(); }
  const std::array<float, 3>& position(size_t k) const { return m.positions[k]; }
  const std::array<float, 3>& normal(size_t k) const { return m.normals.size() == m.positions.size() ? m.normals[k] : computed[k]; }
  const std::array<float, 2>& uv(size_t k) const { return m.uvs[k]; }
  const std::array<uint32_t, 3>& triangle(size_t k) const { return m.triangles[k]; }
};

void checkFormat(const std::string& format) {
  if (format != "ply" && format != "obj" && format != "glb" && format != "fbx")
    throw std::invalid_argument("mesh format '" + format + "' is not one of: ply, obj, glb, fbx");
}

template <class Mesh>
void writeFormat(const std::string& path, const std::string& format, const Mesh& m) {
  checkFormat(format);
  if (m.vertices() == 0 || m.triangles() == 0) throw std::runtime_error(path + ": no triangles to write (no valid cells?)");
  if (format == "glb") return writeChunked(path, [&](ChunkStream& out) { writeGlb(out, m); });
  if (format == "obj") return writeChunked(path, [&](ChunkStream& out) { writeObj(out, m); });
  if (format == "fbx") return writeChunked(path, [&](ChunkStream& out) { writeFbx(out, m); });
  writeChunked(path, [&](ChunkStream& out) { writePly(out, m); });
}

}  // namespace

void writeMesh(const std::string& path, const std::string& format, const MeshData& m) {
  checkFormat(format);
  if (m.positions.empty() || m.triangles.empty()) throw std::runtime_error(path + ": no triangles to write (no valid cells?)");
  MeshDataReader reader{m, {}};
  if (m.normals.size() != m.positions.size()) reader.computed = areaWeightedNormals(m.positions, m.triangles);
  writeFormat(path, format, reader);
}

namespace {

// Vertices of the grid points a triangulation uses, numbered in row order.
struct GridVertices {
  std::vector<uint32_t> index;   // per grid point (the triangulation's numbers), UINT32_MAX when unused
  std::vector<uint32_t> points;  // the vertices' grid points (the triangulation's numbers)
};

// `triangles`' elements through `get` (a triangle or a pointer to one): no list of pointers to
// every triangle is made; the points are counted before they are listed (no growth slack).
template <class Triangles, class Get>
GridVertices usedPoints(const RtinMesh& t, const Triangles& triangles, Get get) {
  GridVertices g;
  g.index.assign(static_cast<size_t>(t.width) * t.height, UINT32_MAX);
  size_t used = 0;
  for (const auto& tri : triangles)
    for (uint32_t p : get(tri)) {
      uint32_t& i = g.index[p];
      used += i == UINT32_MAX;
      i = 0;
    }
  g.points.reserve(used);
  for (int y = 0; y < t.height; ++y)
    for (int x = 0; x < t.width; ++x) {
      const uint32_t p = t.point(x, y);
      uint32_t& i = g.index[p];
      if (i == UINT32_MAX) continue;
      i = static_cast<uint32_t>(g.points.size());
      g.points.push_back(p);
    }
  return g;
}

std::array<float, 3> pointAt(const GridSpec& spec, int x, int y, float z) {
  return {static_cast<float>((x + 0.5) * spec.cellSizeXM), static_cast<float>((spec.height - y - 0.5) * spec.cellSizeYM), z};
}
std::array<float, 2> uvAt(const GridSpec& spec, int x, int y) {
  return {static_cast<float>((x + 0.5) / spec.width), static_cast<float>(1.0 - (y + 0.5) / spec.height)};
}

// The surface mesh of surfaceMesh() read as it is written: positions, UVs and indices computed
// from the triangulation and the grid, so that only the vertex numbering (4 bytes a grid point
// and a vertex) and the normals' sums (24 bytes a vertex) are held beside the triangulation.
struct GridSurfaceReader {
  const RtinMesh& t;
  const Grid<float>& altitude;
  const GridSpec& spec;
  GridVertices g;
  std::vector<std::array<double, 3>> normalSums;

  GridSurfaceReader(const RtinMesh& tri, const Grid<float>& alt, const GridSpec& sp)
      : t(tri), altitude(alt), spec(sp), g(usedPoints(tri, tri.triangles, [](const std::array<uint32_t, 3>& v) -> const auto& { return v; })) {
    normalSums = areaWeightedNormalSums(
        vertices(), triangles(), [&](size_t k) { return position(k); }, [&](size_t k) { return triangle(k); });
  }
  size_t vertices() const { return g.points.size(); }
  size_t triangles() const { return t.triangles.size(); }
  bool hasUvs() const { return true; }
  std::array<float, 3> position(size_t k) const {
    const int x = t.x(g.points[k]), y = t.y(g.points[k]);
    return pointAt(spec, x, y, altitude(x, y));
  }
  std::array<float, 3> normal(size_t k) const { return normalFromSum(normalSums[k]); }
  std::array<float, 2> uv(size_t k) const { return uvAt(spec, t.x(g.points[k]), t.y(g.points[k])); }
  std::array<uint32_t, 3> triangle(size_t k) const {
    const auto& v = t.triangles[k];
    return {g.index[v[0]], g.index[v[1]], g.index[v[2]]};
  }
};

}  // namespace

MeshData surfaceMesh(const RtinMesh& t, const Grid<float>& altitude, const GridSpec& spec) {
  MeshData m;
  {
    // The arrays sized once (the triangulation says how many), the points freed before the normals.
    GridVertices g = usedPoints(t, t.triangles, [](const std::array<uint32_t, 3>& v) -> const auto& { return v; });
    m.positions.reserve(g.points.size());
    m.uvs.reserve(g.points.size());
    for (uint32_t p : g.points) {
      const int x = t.x(p), y = t.y(p);
      m.positions.push_back(pointAt(spec, x, y, altitude(x, y)));
      m.uvs.push_back(uvAt(spec, x, y));
    }
    g.points = {};
    m.triangles.reserve(t.triangles.size());
    for (const auto& tri : t.triangles) m.triangles.push_back({g.index[tri[0]], g.index[tri[1]], g.index[tri[2]]});
  }
  m.normals = areaWeightedNormals(m.positions, m.triangles);
  return m;
}

MeshCounts writeSurfaceMeshes(const std::vector<std::pair<std::string, std::string>>& pathsAndFormats, const RtinMesh& triangulation,
                              const Grid<float>& altitude, const GridSpec& spec) {
  for (const auto& pf : pathsAndFormats) checkFormat(pf.second);
  const GridSurfaceReader reader(triangulation, altitude, spec);
  for (const auto& [path, format] : pathsAndFormats) writeFormat(path, format, reader);
  return {reader.vertices(), reader.triangles()};
}

MeshData snowBodyMesh(const RtinMesh& t, const Grid<float>& bedrock, const Grid<float>& depth, const Grid<uint8_t>& valid,
                      const GridSpec& spec) {
  const int w = t.width, h = t.height;
  // The body's depth: 0 next to NODATA, so the body's rim inside the terrain closes on itself.
  auto bodyDepth = [&](int x, int y) -> float {
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if (nx >= 0 && ny >= 0 && nx < w && ny < h && !valid(nx, ny)) return 0.f;
      }
    return std::max(0.f, depth(x, y));
  };
  auto pointDepth = [&](uint32_t p) { return bodyDepth(t.x(p), t.y(p)); };
  // Triangles holding snow at a vertex.
  std::vector<const std::array<uint32_t, 3>*> kept;
  for (const auto& tri : t.triangles)
    if (pointDepth(tri[0]) > 0.f || pointDepth(tri[1]) > 0.f || pointDepth(tri[2]) > 0.f) kept.push_back(&tri);
  MeshData m;
  if (kept.empty()) return m;
  // Top vertex per grid point used (row order), and a bottom one where the snow is deeper than 0.
  const GridVertices g = usedPoints(t, kept, [](const std::array<uint32_t, 3>* tri) -> const auto& { return *tri; });
  std::vector<uint32_t> top(g.points.size()), bottom(g.points.size());
  for (size_t k = 0; k < g.points.size(); ++k) {
    const int x = t.x(g.points[k]), y = t.y(g.points[k]);
    const float d = bodyDepth(x, y), b = bedrock(x, y);
    top[k] = bottom[k] = static_cast<uint32_t>(m.positions.size());
    m.positions.push_back(pointAt(spec, x, y, b + d));
    m.uvs.push_back(uvAt(spec, x, y));
    if (d > 0.f) {
      bottom[k] = static_cast<uint32_t>(m.positions.size());
      m.positions.push_back(pointAt(spec, x, y, b));
      m.uvs.push_back(uvAt(spec, x, y));
    }
  }
  auto vid = [&](uint32_t p, int which) {
    const uint32_t k = g.index[p];
    return which == 0 ? top[k] : bottom[k];
  };
  // Undirected edges of the kept triangles (grid point keys, with the triangle's edge number),
  // sorted: a rim edge is one whose key pair appears once.
  auto key = [&](uint32_t p) { return static_cast<uint64_t>(p); };
  struct Edge {
    uint64_t a, b;
    size_t id;  // 3 * kept triangle + edge
  };
  std::vector<Edge> edges;
  edges.reserve(kept.size() * 3);
  for (size_t t = 0; t < kept.size(); ++t) {
    const auto& q = *kept[t];
    m.triangles.push_back({vid(q[0], 0), vid(q[1], 0), vid(q[2], 0)});  // top, facing up
    m.triangles.push_back({vid(q[0], 1), vid(q[2], 1), vid(q[1], 1)});  // bottom, facing down
    for (int k = 0; k < 3; ++k) {
      const uint64_t a = key(q[k]), b = key(q[(k + 1) % 3]);
      edges.push_back({std::min(a, b), std::max(a, b), 3 * t + k});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });
  std::vector<uint8_t> rim(edges.size(), 0);
  for (size_t e = 0; e < edges.size();) {
    size_t end = e + 1;
    while (end < edges.size() && edges[end].a == edges[e].a && edges[end].b == edges[e].b) ++end;
    if (end - e == 1) rim[edges[e].id] = 1;
    e = end;
  }
  // Walls along rim edges where the snow has depth: (a_top, a_bottom, b_bottom), (a_top, b_bottom, b_top).
  for (size_t t = 0; t < kept.size(); ++t) {
    const auto& q = *kept[t];
    for (int k = 0; k < 3; ++k) {
      const uint32_t pa = q[k], pb = q[(k + 1) % 3];
      if (!rim[3 * t + k]) continue;
      const uint32_t at = vid(pa, 0), ab = vid(pa, 1), bt = vid(pb, 0), bb = vid(pb, 1);
      if (at != ab) m.triangles.push_back({at, ab, bb});
      if (bt != bb) m.triangles.push_back({at, bb, bt});
    }
  }
  m.normals = areaWeightedNormals(m.positions, m.triangles);
  return m;
}

}  // namespace snow
