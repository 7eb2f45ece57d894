// The tile sizes each [outputs.tiles] convention allows, for the scene check and the reference.
#pragma once
#include <string>
#include <vector>

#include "scene_enums.h"

namespace snow {

// Unreal: the landscape sizes its Landscape Technical Guide recommends (whole components,
// 2^n - 1 quads + 1 shared vertex); Unity: 2^n + 1 from 33 to 4097 (TerrainData.heightmapResolution).
// Grid: any size (empty list).
inline std::vector<int> allowedTileSizes(TileConvention c) {
  if (c == TileConvention::Unreal) return {127, 253, 505, 1009, 2017, 4033, 8129};
  if (c == TileConvention::Unity) return {33, 65, 129, 257, 513, 1025, 2049, 4097};
  return {};
}

inline std::string tileSizeList(TileConvention c) {
  std::string list;
  for (int s : allowedTileSizes(c)) list += (list.empty() ? "" : ", ") + std::to_string(s);
  return list;
}

}  // namespace snow
