// Per-vertex normals of a triangle mesh: the area-weighted sum of its triangles' normals (their
// cross products, summed in double), normalised; (0, 0, 1) where a vertex has no area around it.
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace snow {

// The unnormalised sums, of `vertices` vertices and `triangles` triangles read through
// position(k) and triangle(k): for a mesh computed as it is written (no array of its positions).
template <class Position, class Triangle>
std::vector<std::array<double, 3>> areaWeightedNormalSums(size_t vertices, size_t triangles, Position position, Triangle triangle) {
  std::vector<std::array<double, 3>> sum(vertices, {0.0, 0.0, 0.0});
  for (size_t k = 0; k < triangles; ++k) {
    const std::array<uint32_t, 3> t = triangle(k);
    const std::array<float, 3> a = position(t[0]), b = position(t[1]), c = position(t[2]);
    const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
    const double v[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
    const double cross[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};  // 2 x area
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) sum[t[j]][i] += cross[i];
  }
  return sum;
}

// A vertex's unit normal from its sum.
inline std::array<float, 3> normalFromSum(const std::array<double, 3>& s) {
  const double len = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
  if (len > 0.0) return {float(s[0] / len), float(s[1] / len), float(s[2] / len)};
  return {0.f, 0.f, 1.f};
}

inline std::vector<std::array<float, 3>> areaWeightedNormals(const std::vector<std::array<float, 3>>& positions,
                                                             const std::vector<std::array<uint32_t, 3>>& triangles) {
  const std::vector<std::array<double, 3>> sum = areaWeightedNormalSums(
      positions.size(), triangles.size(), [&](size_t k) { return positions[k]; }, [&](size_t k) { return triangles[k]; });
  std::vector<std::array<float, 3>> out(sum.size());
  for (size_t k = 0; k < sum.size(); ++k) out[k] = normalFromSum(sum[k]);
  return out;
}

}  // namespace snow
