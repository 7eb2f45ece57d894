#include "rtin.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace snow {

namespace {

// Calls f(x, y, interpolated) for every grid point inside or on triangle (a, b, c) (integer
// vertices), with the planar interpolation of `field` there.
template <class F>
void forEachPoint(int ax, int ay, int bx, int by, int cx, int cy, F&& f) {
  const int x0 = std::min({ax, bx, cx}), x1 = std::max({ax, bx, cx});
  const int y0 = std::min({ay, by, cy}), y1 = std::max({ay, by, cy});
  const long det = static_cast<long>(bx - ax) * (cy - ay) - static_cast<long>(cx - ax) * (by - ay);
  if (det == 0) return;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      // Barycentric weights times det (exact in integers).
      const long wb = static_cast<long>(x - ax) * (cy - ay) - static_cast<long>(cx - ax) * (y - ay);
      const long wc = static_cast<long>(bx - ax) * (y - ay) - static_cast<long>(x - ax) * (by - ay);
      const long wa = det - wb - wc;
      if (det > 0 ? (wa < 0 || wb < 0 || wc < 0) : (wa > 0 || wb > 0 || wc > 0)) continue;
      f(x, y, static_cast<double>(wa) / det, static_cast<double>(wb) / det, static_cast<double>(wc) / det);
    }
}

}  // namespace

RtinMesh buildRtin(const std::vector<const Grid<float>*>& fields, const Grid<uint8_t>& valid, double maxErrorM) {
  const int w = valid.width(), h = valid.height();
  if (w < 2 || h < 2) throw std::invalid_argument("buildRtin: the grid needs at least 2 x 2 points");
  if (!(maxErrorM >= 0.0)) throw std::invalid_argument("buildRtin: the error bound must be 0 or more");
  int tile = 1;
  while (tile + 1 < std::max(w, h)) tile *= 2;
  const int size = tile + 1;
  auto inside = [&](int x, int y) { return x < w && y < h && valid(x, y); };
  std::vector<float> errors(static_cast<size_t>(size) * size, 0.f);
  const float inf = std::numeric_limits<float>::infinity();

  // Every triangle of the implicit binary tree, finest level first (Martini's enumeration).
  const long long numSmallest = static_cast<long long>(tile) * tile;
  const long long numTriangles = numSmallest * 2 - 2;
  const long long lastLevel = numTriangles - numSmallest;
  for (long long i = numTriangles - 1; i >= 0; --i) {
    long long id = i + 2;
    int ax = 0, ay = 0, bx = 0, by = 0, cx = 0, cy = 0;
    if (id & 1) bx = by = cx = tile;
    else ax = ay = cy = tile;
    while ((id >>= 1) > 1) {
      const int mx = (ax + bx) >> 1, my = (ay + by) >> 1;
      if (id & 1) bx = ax, by = ay, ax = cx, ay = cy;
      else ax = bx, ay = by, bx = cx, by = cy;
      cx = mx, cy = my;
    }
    const size_t middle = static_cast<size_t>((ay + by) >> 1) * size + ((ax + bx) >> 1);
    float e = errors[middle];
    if (e != inf) {
      // The true error of this triangle: every grid point in it, every field.
      bool bad = !inside(ax, ay) || !inside(bx, by) || !inside(cx, cy);
      double worst = 0.0;
      if (!bad)
        forEachPoint(ax, ay, bx, by, cx, cy, [&](int x, int y, double wa, double wb, double wc) {
          if (bad) return;
          if (!inside(x, y)) {
            bad = true;
            return;
          }
          for (const Grid<float>* f : fields) {
            const double interp = wa * (*f)(ax, ay) + wb * (*f)(bx, by) + wc * (*f)(cx, cy);
            worst = std::max(worst, std::abs(interp - static_cast<double>((*f)(x, y))));
          }
        });
      e = bad ? inf : std::max(e, static_cast<float>(worst));
    }
    if (i < lastLevel && e != inf) {
      const size_t left = static_cast<size_t>((ay + cy) >> 1) * size + ((ax + cx) >> 1);
      const size_t right = static_cast<size_t>((by + cy) >> 1) * size + ((bx + cx) >> 1);
      e = std::max({e, errors[left], errors[right]});
    }
    errors[middle] = e;
  }

  RtinMesh mesh;
  mesh.width = w, mesh.height = h, mesh.maxErrorM = maxErrorM;
  // Emit: split while the hypotenuse midpoint's error is over the bound (explicit stack). Twice:
  // first counting the triangles, so the list is made at its size (grown by doubling it held up
  // to twice its bytes, and three times while it moved).
  struct Tri { int ax, ay, bx, by, cx, cy; };
  auto emit = [&](auto&& keep) {
    std::vector<Tri> stack{{tile, tile, 0, 0, 0, tile}, {0, 0, tile, tile, tile, 0}};
    while (!stack.empty()) {
      const Tri t = stack.back();
      stack.pop_back();
      const int mx = (t.ax + t.bx) >> 1, my = (t.ay + t.by) >> 1;
      if (std::abs(t.ax - t.cx) + std::abs(t.ay - t.cy) > 1 && errors[static_cast<size_t>(my) * size + mx] > maxErrorM) {
        stack.push_back({t.bx, t.by, t.cx, t.cy, mx, my});
        stack.push_back({t.cx, t.cy, t.ax, t.ay, mx, my});
        continue;
      }
      if (inside(t.ax, t.ay) && inside(t.bx, t.by) && inside(t.cx, t.cy)) keep(t);
    }
  };
  size_t count = 0;
  emit([&](const Tri&) { ++count; });
  mesh.triangles.reserve(count);
  emit([&](const Tri& t) {
    // Counter-clockwise seen from above: rows run south, so flip when (x, y) order is clockwise.
    const long cross = static_cast<long>(t.bx - t.ax) * (t.cy - t.ay) - static_cast<long>(t.cx - t.ax) * (t.by - t.ay);
    const uint32_t a = mesh.point(t.ax, t.ay), b = mesh.point(t.bx, t.by), c = mesh.point(t.cx, t.cy);
    if (cross < 0) mesh.triangles.push_back({a, b, c});
    else mesh.triangles.push_back({a, c, b});
  });
  errors = std::vector<float>();  // before the sort
  // A fixed order whatever the traversal: by the first vertex's (x, y), then the rest's (the
  // column-by-column numbers sort as (x, y) pairs).
  std::sort(mesh.triangles.begin(), mesh.triangles.end());
  return mesh;
}

double rtinMaxVerticalError(const RtinMesh& mesh, const Grid<float>& field) {
  double worst = 0.0;
  for (const auto& t : mesh.triangles) {
    const int ax = mesh.x(t[0]), ay = mesh.y(t[0]), bx = mesh.x(t[1]), by = mesh.y(t[1]), cx = mesh.x(t[2]), cy = mesh.y(t[2]);
    forEachPoint(ax, ay, bx, by, cx, cy, [&](int x, int y, double wa, double wb, double wc) {
      const double interp = wa * field(ax, ay) + wb * field(bx, by) + wc * field(cx, cy);
      worst = std::max(worst, std::abs(interp - field(x, y)));
    });
  }
  return worst;
}

}  // namespace snow
