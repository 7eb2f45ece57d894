#include "mesh_snow_body.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetFilter.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/TopologyToLevelSet.h>
#include <openvdb/tools/ValueTransformer.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/util.h"
#include "vdb_file.h"

namespace snow {

MeshSnowBody buildMeshSnowBody(const FallenSnow& snow, const TriangleMesh& mesh, const MeshSnowBodyOptions& o, const std::string& vdbPath) {
  const auto t0 = WallClock::now();
  openvdb::initialize();
  if (!(snow.siteSpacingM > 0.0)) throw std::runtime_error(mesh.source + ": snow body: no placed snow");
  const double v = o.voxelSizeM > 0.0 ? o.voxelSizeM : 0.5 * snow.siteSpacingM;
  if (!(o.adaptivity >= 0.0 && o.adaptivity <= 1.0) || o.smoothingSteps < 0 || !(o.densityKgPerM3 > 0.0))
    throw std::runtime_error(mesh.source + ": snow body: adaptivity in [0, 1], smoothing steps >= 0, density > 0");
  MeshSnowBody body;
  body.voxelSizeM = v;
  auto topology = openvdb::BoolGrid::create(false);
  auto acc = topology->getAccessor();
  for (const SnowSite& site : snow.sites) {
    if (!(site.depthM > 0.f)) continue;
    const double h = snow.siteSpacingM / (1 << site.level), hw = 0.5 * h;
    body.columnsM3 += static_cast<double>(site.depthM) * site.footprintM2;
    // The face's slope: the column reaches down by the face's drop across half a footprint's
    // diagonal, and one voxel more.
    const auto& tri = mesh.triangles[site.face];
    const auto &a = mesh.positions[tri[0]], &b = mesh.positions[tri[1]], &c = mesh.positions[tri[2]];
    const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2], wx = c[0] - a[0], wy = c[1] - a[1], wz = c[2] - a[2];
    const double nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
    const double tanSlope = nz > 0.0 ? std::sqrt(nx * nx + ny * ny) / nz : 0.0;
    const double x = site.position[0], y = site.position[1], zb = site.position[2];
    const double bottom = zb - hw * std::sqrt(2.0) * std::min(tanSlope, 10.0) - v, top = zb + site.depthM;
    // Voxel centres ((index + 1/2) x v) in [lo, hi); a bound on a centre counts on the low side,
    // whatever the rounding of the division.
    auto first = [&](double lo) { return static_cast<int>(std::ceil(lo / v - 0.5 - 1e-6)); };
    const int i0 = first(x - hw), i1 = first(x + hw) - 1, j0 = first(y - hw), j1 = first(y + hw) - 1;
    const int k0 = first(bottom), k1 = first(top) - 1;
    for (int k = k0; k <= k1; ++k)
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) acc.setValueOn(openvdb::Coord(i, j, k), true);
  }
  body.snowVoxels = topology->activeVoxelCount();
  // Voxel (i, j, k) is the cube [i v, (i + 1) v) x ...: its centre at (index + 1/2) v.
  const auto transform = openvdb::math::Transform::createLinearTransform(v);
  transform->postTranslate(openvdb::Vec3d(0.5 * v, 0.5 * v, 0.5 * v));
  topology->setTransform(transform);  // so the level set's distances are in metres
  openvdb::FloatGrid::Ptr sdf = body.snowVoxels > 0 ? openvdb::tools::topologyToLevelSet(*topology, 3, 0, 0, 0)
                                                    : openvdb::createLevelSet<openvdb::FloatGrid>(v, 3.0);
  // Smoothing by mean-curvature flow: the columns' steps round off, flat snow does not move
  // (topologyToLevelSet's own smoothing dilated the body by about half a voxel, measured).
  if (body.snowVoxels > 0 && o.smoothingSteps > 0) {
    openvdb::tools::LevelSetFilter<openvdb::FloatGrid> filter(*sdf);
    for (int k = 0; k < o.smoothingSteps; ++k) filter.meanCurvature();
  }
  sdf->setTransform(transform);
  sdf->setName("snow_sdf");
  sdf->setGridClass(openvdb::GRID_LEVEL_SET);
  if (body.snowVoxels > 0) {
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*sdf, points, triangles, quads, 0.0, o.adaptivity);
    body.mesh.positions.reserve(points.size());
    for (const auto& p : points) body.mesh.positions.push_back({p[0], p[1], p[2]});
    // OpenVDB's faces wind clockwise seen from outside (negative inside): flipped to the usual
    // counter-clockwise, outward normals.
    for (const auto& t : triangles) body.mesh.triangles.push_back({t[0], t[2], t[1]});
    for (const auto& q : quads) {
      body.mesh.triangles.push_back({q[0], q[2], q[1]});
      body.mesh.triangles.push_back({q[0], q[3], q[2]});
    }
  }
  if (!vdbPath.empty()) {
    openvdb::FloatGrid::Ptr fog = sdf->deepCopy();
    openvdb::tools::sdfToFogVolume(*fog);
    openvdb::tools::foreach(fog->beginValueOn(), [&](const openvdb::FloatGrid::ValueOnIter& it) {
      it.setValue(it.getValue() * static_cast<float>(o.densityKgPerM3));
    });
    fog->setName("density");
    fog->setGridClass(openvdb::GRID_FOG_VOLUME);
    fog->insertMeta("unit", openvdb::StringMetadata("kg/m^3"));
    openvdb::GridPtrVec grids{sdf, fog};
    writeVdbGridsAtomically(vdbPath, grids);
  }
  body.seconds = elapsedSeconds(t0);
  return body;
}

}  // namespace snow
