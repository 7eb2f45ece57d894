#include "mesh_tiles.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace snow {

namespace {

// A vertex of a clipped triangle: an input vertex, a border's crossing of an input edge, or a
// corner of two borders inside an input triangle; `key` names it the same in every tile.
struct ClipVertex {
  double x, y;
  std::tuple<int, uint32_t, uint32_t, int, int> key;  // (kind, a, b, axis or column line, line or row line)
  uint32_t edgeA = 0, edgeB = 0;                      // the input edge it lies on (kind 1), a == b: none
  bool onEdge(uint32_t a, uint32_t b) const { return edgeA != edgeB && edgeA == std::min(a, b) && edgeB == std::max(a, b); }
};

struct Attributes {
  std::array<float, 3> position, normal;
  std::array<float, 2> uv;
};

class TriangleClipper {
 public:
  TriangleClipper(const MeshData& m, uint32_t triangle) : m_(m), t_(m.triangles[triangle]), triangle_(triangle) {}

  // The triangle clipped to [x0, x1] x [y0, y1] (line indices name the borders for the keys).
  std::vector<ClipVertex> clip(double x0, double x1, double y0, double y1, int c0, int c1, int r0, int r1) const {
    std::vector<ClipVertex> poly;
    for (uint32_t v : t_) poly.push_back({m_.positions[v][0], m_.positions[v][1], {0, v, v, 0, 0}, v, v});
    poly = clipAgainst(poly, 0, x0, c0, true);
    poly = clipAgainst(poly, 0, x1, c1, false);
    poly = clipAgainst(poly, 1, y0, r0, true);
    poly = clipAgainst(poly, 1, y1, r1, false);
    return poly;
  }

  Attributes attributes(const ClipVertex& c) const {
    const auto kind = std::get<0>(c.key);
    if (kind == 0) return vertex(std::get<1>(c.key));
    if (kind == 1) return alongEdge(c);
    return inPlane(c.x, c.y);
  }

 private:
  // Sutherland-Hodgman against one axis-aligned line; `keepAbove`: keep coordinate >= value.
  std::vector<ClipVertex> clipAgainst(const std::vector<ClipVertex>& in, int axis, double value, int line, bool keepAbove) const {
    std::vector<ClipVertex> out;
    auto coord = [&](const ClipVertex& c) { return axis == 0 ? c.x : c.y; };
    auto inside = [&](const ClipVertex& c) { return keepAbove ? coord(c) >= value : coord(c) <= value; };
    for (size_t i = 0; i < in.size(); ++i) {
      const ClipVertex& p = in[i];
      const ClipVertex& q = in[(i + 1) % in.size()];
      if (inside(p)) out.push_back(p);
      if (inside(p) != inside(q)) out.push_back(crossing(p, q, axis, value, line));
    }
    return out;
  }

  // Where segment p-q crosses the line: on the input edge both lie on, or a corner in the plane.
  ClipVertex crossing(const ClipVertex& p, const ClipVertex& q, int axis, double value, int line) const {
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = std::min(t_[e], t_[(e + 1) % 3]), b = std::max(t_[e], t_[(e + 1) % 3]);
      const bool pOn = p.onEdge(a, b) || (std::get<0>(p.key) == 0 && (std::get<1>(p.key) == a || std::get<1>(p.key) == b));
      const bool qOn = q.onEdge(a, b) || (std::get<0>(q.key) == 0 && (std::get<1>(q.key) == a || std::get<1>(q.key) == b));
      if (!pOn || !qOn) continue;
      const auto& pa = m_.positions[a];
      const auto& pb = m_.positions[b];
      const double t = (value - pa[axis]) / (static_cast<double>(pb[axis]) - pa[axis]);
      ClipVertex c{pa[0] + t * (static_cast<double>(pb[0]) - pa[0]), pa[1] + t * (static_cast<double>(pb[1]) - pa[1]), {1, a, b, axis, line}, a, b};
      (axis == 0 ? c.x : c.y) = value;
      return c;
    }
    // Along a border already cut: a corner of two borders (the other one's value is p's).
    ClipVertex c{axis == 0 ? value : p.x, axis == 0 ? p.y : value, {}, 0, 0};
    // Corners come from the row lines' cuts of a segment on a column line: p is that line's
    // crossing of an edge (the line in the key's last slot) or an earlier corner on it.
    const int column = std::get<0>(p.key) == 1 ? std::get<4>(p.key) : std::get<3>(p.key);
    c.key = {2, triangle_, 0, column, line};
    return c;
  }

  Attributes vertex(uint32_t v) const {
    Attributes a{m_.positions[v], m_.normals.size() > v ? m_.normals[v] : std::array<float, 3>{0, 0, 1},
                 m_.uvs.size() > v ? m_.uvs[v] : std::array<float, 2>{0, 0}};
    return a;
  }
  static Attributes mix(const std::array<Attributes, 3>& v, const std::array<double, 3>& w, double x, double y) {
    Attributes r{};
    for (int k = 0; k < 3; ++k) {
      r.position[k] = static_cast<float>(w[0] * v[0].position[k] + w[1] * v[1].position[k] + w[2] * v[2].position[k]);
      r.normal[k] = static_cast<float>(w[0] * v[0].normal[k] + w[1] * v[1].normal[k] + w[2] * v[2].normal[k]);
    }
    for (int k = 0; k < 2; ++k) r.uv[k] = static_cast<float>(w[0] * v[0].uv[k] + w[1] * v[1].uv[k] + w[2] * v[2].uv[k]);
    const double n = std::sqrt(r.normal[0] * r.normal[0] + r.normal[1] * r.normal[1] + r.normal[2] * r.normal[2]);
    for (float& c : r.normal) c = static_cast<float>(n > 0 ? c / n : 0);
    r.position[0] = static_cast<float>(x), r.position[1] = static_cast<float>(y);
    return r;
  }
  Attributes alongEdge(const ClipVertex& c) const {
    const uint32_t a = std::get<1>(c.key), b = std::get<2>(c.key);
    const int axis = std::get<3>(c.key);
    const double value = axis == 0 ? c.x : c.y;
    const double t = (value - m_.positions[a][axis]) / (static_cast<double>(m_.positions[b][axis]) - m_.positions[a][axis]);
    return mix({vertex(a), vertex(b), vertex(b)}, {1 - t, t, 0}, c.x, c.y);
  }
  Attributes inPlane(double x, double y) const {
    const auto &p0 = m_.positions[t_[0]], &p1 = m_.positions[t_[1]], &p2 = m_.positions[t_[2]];
    const double d = (static_cast<double>(p1[1]) - p2[1]) * (p0[0] - p2[0]) + (static_cast<double>(p2[0]) - p1[0]) * (p0[1] - p2[1]);
    const double w0 = ((static_cast<double>(p1[1]) - p2[1]) * (x - p2[0]) + (static_cast<double>(p2[0]) - p1[0]) * (y - p2[1])) / d;
    const double w1 = ((static_cast<double>(p2[1]) - p0[1]) * (x - p2[0]) + (static_cast<double>(p0[0]) - p2[0]) * (y - p2[1])) / d;
    return mix({vertex(t_[0]), vertex(t_[1]), vertex(t_[2])}, {w0, w1, 1 - w0 - w1}, x, y);
  }

  const MeshData& m_;
  const std::array<uint32_t, 3>& t_;
  uint32_t triangle_;
};

}  // namespace

std::vector<MeshTile> cutIntoTiles(const MeshData& mesh, const GridSpec& spec, int tileCells) {
  if (tileCells < 1) throw std::invalid_argument("cutIntoTiles: a tile needs at least one cell");
  const double tw = tileCells * spec.cellSizeXM, th = tileCells * spec.cellSizeYM, top = spec.height * spec.cellSizeYM;
  std::map<std::pair<int, int>, MeshTile> tiles;  // (row, column)
  // A vertex is its position in the plane: one vertex a tile for each (x, y), and one set of
  // attributes for every tile (the first computed, in triangle order), so a corner two triangles
  // reach or an edge's crossing met from both sides is the same vertex bit for bit.
  using Where = std::pair<float, float>;
  std::map<std::pair<int, int>, std::map<Where, uint32_t>> local;
  std::map<Where, Attributes> shared;
  for (uint32_t k = 0; k < mesh.triangles.size(); ++k) {
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (uint32_t v : mesh.triangles[k])
      for (int a = 0; a < 2; ++a) lo[a] = std::min<double>(lo[a], mesh.positions[v][a]), hi[a] = std::max<double>(hi[a], mesh.positions[v][a]);
    const TriangleClipper clipper(mesh, k);
    for (int row = static_cast<int>(std::floor((top - hi[1]) / th)); row <= static_cast<int>(std::floor((top - lo[1]) / th)); ++row)
      for (int col = static_cast<int>(std::floor(lo[0] / tw)); col <= static_cast<int>(std::floor(hi[0] / tw)); ++col) {
        // Column lines are numbered by their index, row lines by theirs (+1 for the south edge of row r).
        const auto poly = clipper.clip(col * tw, (col + 1) * tw, top - (row + 1) * th, top - row * th, col, col + 1, row + 1, row);
        if (poly.size() < 3) continue;
        MeshTile& t = tiles[{row, col}];
        t.row = row, t.column = col;
        auto& ids = local[{row, col}];
        std::vector<uint32_t> index;
        for (const ClipVertex& c : poly) {
          const Where at{static_cast<float>(c.x), static_cast<float>(c.y)};
          auto [it, fresh] = ids.emplace(at, static_cast<uint32_t>(t.mesh.positions.size()));
          if (fresh) {
            const Attributes& a = shared.try_emplace(at, clipper.attributes(c)).first->second;
            t.mesh.positions.push_back(a.position);
            if (!mesh.normals.empty()) t.mesh.normals.push_back(a.normal);
            if (!mesh.uvs.empty()) t.mesh.uvs.push_back(a.uv);
          }
          index.push_back(it->second);
        }
        for (size_t i = 1; i + 1 < index.size(); ++i)  // the clipped triangle is convex: a fan
          if (index[0] != index[i] && index[i] != index[i + 1] && index[0] != index[i + 1]) t.mesh.triangles.push_back({index[0], index[i], index[i + 1]});
      }
  }
  std::vector<MeshTile> out;
  for (auto& [rc, t] : tiles)
    if (!t.mesh.triangles.empty()) out.push_back(std::move(t));
  return out;
}

}  // namespace snow
