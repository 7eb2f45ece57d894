// The project's own small interface to ray queries (Embree 3 behind it, in ray_scene.cpp only,
// so a move to Embree 4 changes one file). The terrain is Embree GRID geometry (little memory,
// fast build), split into tiles of at most 32767 vertices a side; occluder meshes are triangles.
//
// Frame: x east from the west edge, y north from the south edge, z altitude, metres. Cell (i, j)
// (row j from the north) has its vertex at ((i + 0.5) dx, (H - j - 0.5) dy, height).
#pragma once
#include <array>
#include <memory>
#include <vector>

#include "core/grid.h"
#include "inputs/mesh.h"

namespace snow {

class RayScene {
 public:
  // An empty grid (width or height 0) gives a scene of the meshes alone.
  // `tileVertices` limits the grid tiles' side (Embree's limit is 32767); tests use small tiles.
  RayScene(const Grid<float>& heights, const GridSpec& spec, const std::vector<TriangleMesh>& occluders = {},
           int tileVertices = 32767);
  ~RayScene();
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  // True when the segment origin + t dir, 0 < t < tfar, hits anything.
  bool occluded(const std::array<float, 3>& origin, const std::array<float, 3>& direction, float tfar) const;
  // 16 rays at once (coherent packets); `valid[k]` false skips ray k. Writes hit[k].
  void occluded16(const bool valid[16], const std::array<float, 3> origins[16], const std::array<float, 3> directions[16],
                  float tfar, bool hit[16]) const;
  // Distance to the first hit, or +infinity.
  float intersect(const std::array<float, 3>& origin, const std::array<float, 3>& direction, float tfar) const;

  // The first hit, with what it hit: `mesh` the occluder's index (-1 for the terrain) and its
  // triangle. False on a miss.
  bool intersectPrimitive(const std::array<float, 3>& origin, const std::array<float, 3>& direction, float tfar, float& t, int& mesh,
                          unsigned& triangle) const;

  std::array<float, 3> cellPoint(int i, int j) const;  // the terrain vertex of cell (i, j)
  int tileCount() const { return tiles_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  GridSpec spec_;
  const Grid<float>& heights_;
  int tiles_ = 0;
};

}  // namespace snow
