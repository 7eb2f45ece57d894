// Shared by snow placement and stability (fallen_snow_placement.cpp, fallen_snow_stability.cpp).
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

namespace snow {

// Just above a surface point at height z: 0.1 mm, or 8 float steps where those are larger (a
// mesh at 4000 m has 0.24 mm steps: a 0.1 mm lift rounded back onto the face, and every flake
// hit its own site's face).
inline float lifted(float z) { return z + std::max(1e-4f, 8.f * std::abs(z) * std::numeric_limits<float>::epsilon()); }


}  // namespace snow
