// The surface slope, shared by the phenomena that read |grad A| (A = B + C + S + U + P, the snow
// surface): snowfall's shares, the stability change's slope factor, the bedforms' domain.
//
// Model: the gradient by central differences that never reads NODATA cells (one-sided next to a
// hole or the grid edge, zero when both sides are out).
// Writes: the scratch field surfaceSlope (SurfaceSlopeKernel), a snapshot taken before a per-cell
// pass that changes A, so that pass never reads a neighbour another thread is writing.
// Mass: changes no snow. Row path for the TBB executor: surface_slope_rows.h.
#pragma once
#include "../hd.h"
#include "../snow_state.h"

namespace snow {

SNOW_HD SNOW_INLINE void surfaceGradient(const SnowFieldsView& v, int x, int y, float& gx, float& gy) {
  const int i = v.index(x, y);
  const float a = v.surface(i);
  const bool left = v.isValid(x - 1, y), right = v.isValid(x + 1, y);
  const bool up = v.isValid(x, y - 1), down = v.isValid(x, y + 1);
  const float aL = left ? v.surface(i - 1) : a, aR = right ? v.surface(i + 1) : a;
  const float aU = up ? v.surface(i - v.width) : a, aD = down ? v.surface(i + v.width) : a;
  const int nx = (left ? 1 : 0) + (right ? 1 : 0), ny = (up ? 1 : 0) + (down ? 1 : 0);
  gx = nx > 0 ? (aR - aL) / (static_cast<float>(nx) * v.cellSizeXM) : 0.f;
  gy = ny > 0 ? (aD - aU) / (static_cast<float>(ny) * v.cellSizeYM) : 0.f;
}

SNOW_HD SNOW_INLINE float surfaceSlope(const SnowFieldsView& v, int x, int y) {
  float gx, gy;
  surfaceGradient(v, x, y, gx, gy);
  return sqrtf(gx * gx + gy * gy);
}

// Snapshot of the surface slope for the per-cell kernels that read it (snowfall).
struct SurfaceSlopeKernel {
  SnowFieldsView v;
  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    v.surfaceSlope[i] = v.valid[i] ? surfaceSlope(v, x, y) : 0.f;
  }
};

}  // namespace snow
