// Occlusion mode: the static snow cover of Foldes & Benes 2007 ("Occlusion-Based Snow
// Accumulation Simulation"), the quick option (no season) and the baseline the model paper
// compared against.
//
// Two occlusion passes per point (terrain cell or mesh vertex), with Embree ray queries:
//   a  ambient occlusion value, as the paper defines it: the cosine-weighted fraction of the
//      hemisphere around the normal that is open to the sky (1 = not occluded, 0 = fully
//      occluded). `aoRays` rays per point from a stratified cosine-weighted pattern (Malley's
//      method on a Hammersley set), turned by a per-point hash so neighbours do not share their
//      error; rays longer than `aoRadiusM` count as open (0: unlimited, the paper's whole-scene
//      rendering).
//      Relation to the season's sky term (exposure.h): for a horizontal cell with unlimited
//      radius, a is the sky-view factor (1/N) sum_i cos^2(phi_i) of the horizon angles, so
//      I_sky = k_sky pi a there (tested); a also follows the normal's tilt, I_sky does not.
//   v  sun visibility: the fraction of the day's sun trajectory that sees the point, over
//      `sunPositions` sun positions at the middle of equal slices of the daylight hours of the
//      chosen day, each weighted by the clear-sky luminance of the paper's Eqs. 2-3 at the sun
//      (gamma = 0, Theta = z0) times the zenith luminance L_z(z0, turbidity) (Preetham, Shirley
//      and Smits 1999, appendix A.2). A point facing away from the sun does not see it.
// Snow (paper Eq. 1 and §3.2, cos(theta) = n_z, clamped at 0 for overhangs):
//   accumulation = s_max max(0, tau_ambient - a) cos(theta)
//   dissipation  = s_max max(0, v - tau_sun)     cos(theta)
//   snow         = max(0, accumulation - dissipation)
// So an open flat plane (a = 1) holds s_max (tau_ambient - 1) before the sun; points at or above
// tau_ambient hold none; pits and ditches (small a) hold more; a point the sun sees for more than
// tau_sun of the (luminance-weighted) day loses snow; tau_sun >= 1 turns dissipation off.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/grid.h"
#include "inputs/mesh.h"
#include "precompute/ray_scene.h"

namespace snow {

struct OcclusionSettings {
  double sMaxM = 1.0;         // s_max: the snow layer's height scale, metres
  double tauAmbient = 1.25;   // tau: Eq. 1's threshold on the ambient occlusion value
  double tauSun = 0.75;       // tau_sun: threshold on the day's weighted sun visibility
  int sunPositions = 10;      // the paper: "typically ten samples from the sun trajectory"
  int aoRays = 64;            // per point
  double aoRadiusM = 0.0;     // 0: unlimited
  double latitudeDeg = 45.0;
  double dayOfYear = 1.0;     // the day whose sun trajectory dissipates the snow
  double turbidity = 3.0;     // clear sky (2: very clear, 6: hazy)
};

// Rays per point for the sun-exposure quality levels: draft 64, production 256, reference 1024.
int occlusionRaysForQuality(const std::string& quality);

// Eq. 2 divided by L_z: the clear-sky luminance at a sky point Theta from the zenith and gamma
// from the sun, the sun z0 from the zenith (radians).
double clearSkyRelativeLuminance(double thetaRad, double gammaRad, double z0Rad);
// Eq. 3 as printed: the angle between the sun and a sky point; alpha = 90 deg at the sun's azimuth.
double skyAngleToSun(double z0Rad, double thetaRad, double alphaRad);
// Zenith luminance of a clear sky, kcd/m^2 (Preetham et al. 1999, A.2).
double zenithLuminanceKcd(double z0Rad, double turbidity);

struct SunSample {
  std::array<float, 3> direction{0, 0, 1};  // toward the sun: x east, y north, z up
  double solarHour = 12.0, elevationDeg = 0.0, azimuthDeg = 0.0;
  double weight = 0.0;  // normalised: the samples' weights sum to 1
};
// The day's sun positions above the horizon; empty in a polar night.
std::vector<SunSample> sunTrajectory(double latitudeDeg, double dayOfYear, int positions, double turbidity);

struct OcclusionSnow {
  std::vector<float> ambient;        // a
  std::vector<float> sunVisibility;  // v
  std::vector<float> accumulationM;  // Eq. 1
  std::vector<float> dissipationM;
  std::vector<float> snowM;
  std::vector<SunSample> sun;
  double aoSeconds = 0.0, sunSeconds = 0.0;
  unsigned long long aoRayCount = 0, sunRayCount = 0;
};

// Points with unit normals (x east, y north, z up). Rays start `originOffsetM` along the normal.
// `active` (may be empty) leaves inactive points at zero. Same results whatever the thread count.
OcclusionSnow computeOcclusionSnow(const RayScene& scene, const std::vector<std::array<float, 3>>& points,
                                   const std::vector<std::array<float, 3>>& normals, const std::vector<uint8_t>& active,
                                   float originOffsetM, const OcclusionSettings& settings);

// Per terrain cell (NODATA cells stay zero): points at the cell vertices, normals of terrainNormals.
OcclusionSnow computeOcclusionSnowOnTerrain(const RayScene& scene, const Grid<float>& heights, const Grid<uint8_t>& valid,
                                            const GridSpec& spec, const OcclusionSettings& settings);

// Per vertex of a mesh (the scene should hold the mesh): area-weighted vertex normals
// (core/mesh_normals.h).
OcclusionSnow computeOcclusionSnowOnMesh(const RayScene& scene, const TriangleMesh& mesh, const OcclusionSettings& settings);

}  // namespace snow
