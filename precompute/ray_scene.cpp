#include "ray_scene.h"

#include <embree3/rtcore.h>
#include <pmmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace snow {

namespace {
void throwOnError(RTCDevice device, const char* what) {
  const RTCError e = rtcGetDeviceError(device);
  if (e != RTC_ERROR_NONE) throw std::runtime_error(std::string("Embree error ") + std::to_string(static_cast<int>(e)) + " in " + what);
}
// Embree wants flush-to-zero and denormals-are-zero in every tracing thread (its verbose mode
// warns without them; tracing is about 5-10 % faster).
void setFlushToZero() {
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}
}  // namespace

struct RayScene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

RayScene::RayScene(const Grid<float>& heights, const GridSpec& spec, const std::vector<TriangleMesh>& occluders, int tileVertices)
    : impl_(std::make_unique<Impl>()), spec_(spec), heights_(heights) {
  if (tileVertices < 2 || tileVertices > 32767) throw std::invalid_argument("RayScene: tile size must be 2..32767 vertices");
  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
  const int w = spec.width, h = spec.height;
  // Tiles share their border vertices, so the surface is continuous across them.
  const int step = tileVertices - 1;
  for (int j0 = 0; w > 0 && h > 0; j0 += step) {
    const int th = std::min(tileVertices, h - j0);
    for (int i0 = 0;; i0 += step) {
      const int tw = std::min(tileVertices, w - i0);
      RTCGeometry g = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_GRID);
      auto* v = static_cast<float*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), static_cast<size_t>(tw) * th));
      for (int j = 0; j < th; ++j)
        for (int i = 0; i < tw; ++i) {
          const auto p = cellPoint(i0 + i, j0 + j);
          float* q = v + 3 * (static_cast<size_t>(j) * tw + i);
          q[0] = p[0], q[1] = p[1], q[2] = p[2];
        }
      auto* grid = static_cast<RTCGrid*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_GRID, 0, RTC_FORMAT_GRID, sizeof(RTCGrid), 1));
      grid->startVertexID = 0;
      grid->stride = static_cast<unsigned>(tw);
      grid->width = static_cast<unsigned short>(tw);
      grid->height = static_cast<unsigned short>(th);
      rtcCommitGeometry(g);
      rtcAttachGeometry(impl_->scene, g);
      rtcReleaseGeometry(g);
      ++tiles_;
      if (i0 + tw >= w) break;
    }
    if (j0 + th >= h) break;
  }
  for (const TriangleMesh& m : occluders) {
    RTCGeometry g = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.positions.size()));
    for (size_t k = 0; k < m.positions.size(); ++k) v[3 * k] = m.positions[k][0], v[3 * k + 1] = m.positions[k][1], v[3 * k + 2] = m.positions[k][2];
    auto* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), m.triangles.size()));
    for (size_t k = 0; k < m.triangles.size(); ++k)
      idx[3 * k] = m.triangles[k][0], idx[3 * k + 1] = m.triangles[k][1], idx[3 * k + 2] = m.triangles[k][2];
    rtcCommitGeometry(g);
    rtcAttachGeometry(impl_->scene, g);
    rtcReleaseGeometry(g);
  }
  rtcCommitScene(impl_->scene);
  throwOnError(impl_->device, "scene build");
}

RayScene::~RayScene() = default;

std::array<float, 3> RayScene::cellPoint(int i, int j) const {
  return {static_cast<float>((i + 0.5) * spec_.cellSizeXM), static_cast<float>((spec_.height - j - 0.5) * spec_.cellSizeYM),
          heights_(i, j)};
}

bool RayScene::occluded(const std::array<float, 3>& o, const std::array<float, 3>& d, float tfar) const {
  setFlushToZero();
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray{};
  ray.org_x = o[0], ray.org_y = o[1], ray.org_z = o[2];
  ray.dir_x = d[0], ray.dir_y = d[1], ray.dir_z = d[2];
  ray.tnear = 0.f;
  ray.tfar = tfar;
  ray.mask = 0xffffffffu;
  ray.flags = 0;
  rtcOccluded1(impl_->scene, &context, &ray);
  return ray.tfar < 0.f;  // Embree sets tfar to -inf on a hit
}

void RayScene::occluded16(const bool valid[16], const std::array<float, 3> o[16], const std::array<float, 3> d[16], float tfar,
                          bool hit[16]) const {
  setFlushToZero();
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  alignas(64) RTCRay16 rays;
  alignas(64) int mask[16];
  for (int k = 0; k < 16; ++k) {
    mask[k] = valid[k] ? -1 : 0;
    // Embree reads every lane's ray, masked or not (its debug build asserts them valid): a masked
    // lane gets a finite ray, not the caller's unset origin.
    const std::array<float, 3> org = valid[k] ? o[k] : std::array<float, 3>{0.f, 0.f, 0.f};
    const std::array<float, 3> dir = valid[k] ? d[k] : std::array<float, 3>{0.f, 0.f, 1.f};
    rays.org_x[k] = org[0], rays.org_y[k] = org[1], rays.org_z[k] = org[2];
    rays.dir_x[k] = dir[0], rays.dir_y[k] = dir[1], rays.dir_z[k] = dir[2];
    rays.tnear[k] = 0.f;
    rays.tfar[k] = tfar;
    rays.mask[k] = 0xffffffffu;
    rays.flags[k] = 0;
    rays.time[k] = 0.f;
    rays.id[k] = static_cast<unsigned>(k);
  }
  rtcOccluded16(mask, impl_->scene, &context, &rays);
  for (int k = 0; k < 16; ++k) hit[k] = valid[k] && rays.tfar[k] < 0.f;
}

float RayScene::intersect(const std::array<float, 3>& o, const std::array<float, 3>& d, float tfar) const {
  float t = 0.f;
  int mesh = 0;
  unsigned triangle = 0;
  return intersectPrimitive(o, d, tfar, t, mesh, triangle) ? t : std::numeric_limits<float>::infinity();
}

bool RayScene::intersectPrimitive(const std::array<float, 3>& o, const std::array<float, 3>& d, float tfar, float& t, int& mesh,
                                  unsigned& triangle) const {
  setFlushToZero();
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh{};
  rh.ray.org_x = o[0], rh.ray.org_y = o[1], rh.ray.org_z = o[2];
  rh.ray.dir_x = d[0], rh.ray.dir_y = d[1], rh.ray.dir_z = d[2];
  rh.ray.tnear = 0.f;
  rh.ray.tfar = tfar;
  rh.ray.mask = 0xffffffffu;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  t = rh.ray.tfar;
  mesh = static_cast<int>(rh.hit.geomID) - tiles_;
  triangle = rh.hit.primID;
  return true;
}

}  // namespace snow
