// Per-vertex normals of a triangle mesh: the area-weighted sum of its triangles' normals (their
// cross products, summed in double), normalised; (0, 0, 1) where a vertex has no area around it.
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace snow {

inline std::vector<std::array<float, 3>> areaWeightedNormals(const std::vector<std::array<float, 3>>& positions,
                                                             const std::vector<std::array<uint32_t, 3>>& triangles) {
  std::vector<std::array<double, 3>> sum(positions.size(), {0.0, 0.0, 0.0});
  for (const auto& t : triangles) {
    const auto &a = positions[t[0]], &b = positions[t[1]], &c = positions[t[2]];
    const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
    const double v[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
    const double cross[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};  // 2 x area
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) sum[t[k]][i] += cross[i];
  }
  std::vector<std::array<float, 3>> out(sum.size(), {0.f, 0.f, 1.f});
  for (size_t k = 0; k < sum.size(); ++k) {
    const double len = std::sqrt(sum[k][0] * sum[k][0] + sum[k][1] * sum[k][1] + sum[k][2] * sum[k][2]);
    if (len > 0.0) out[k] = {float(sum[k][0] / len), float(sum[k][1] / len), float(sum[k][2] / len)};
  }
  return out;
}

}  // namespace snow
