// The snow body of snow on a mesh (static_snow/fallen_snow.h) as a volume and a mesh: every site
// holding snow stands for a column over its footprint (a square of its spacing) from just inside
// the surface it sits on up to its snow top; the columns' voxels (centres inside a column) are
// the snow. OpenVDB turns them into a narrow-band level set (snow_sdf, in metres, smoothed by a
// few passes of mean-curvature flow: the columns' steps are a site spacing wide), a fog volume (density, kg/m^3 of
// the given snow density inside), and a closed triangle mesh (volume-to-mesh at the zero
// crossing, optionally adaptive). The column goes down into the surface by the surface's drop
// across half a footprint plus one voxel, so the body meets sloped faces without a gap. Frame and
// units: the input mesh's (x, y, z, z up, metres).
#pragma once
#include <cstddef>
#include <string>

#include "mesh_writer.h"
#include "static_snow/fallen_snow.h"

namespace snow {

// MeshSnowBodyOptions: scene/mesh_snow_options.h (the scene file sets them).

struct MeshSnowBody {
  MeshData mesh;               // closed, outward-facing triangles
  double voxelSizeM = 0;
  size_t snowVoxels = 0;       // voxels whose centre lies in a column
  double columnsM3 = 0;        // the sites' snow volume (the columns above the surface)
  double seconds = 0;
};

// Builds the body; writes `vdbPath` (snow_sdf and density) when it is not empty.
MeshSnowBody buildMeshSnowBody(const FallenSnow& snow, const TriangleMesh& mesh, const MeshSnowBodyOptions& options,
                               const std::string& vdbPath = "");

}  // namespace snow
