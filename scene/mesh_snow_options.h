// The settings of Fearing's snow on meshes (mode = "mesh", [mesh_snow]): placement, stability and
// the snow body, as the scene gives them. The models are static_snow/fallen_snow.h; the body is
// built by bakers/mesh_snow_body.h.
#pragma once
#include <cstdint>
#include <vector>

namespace snow {

struct FallenSnowSettings {
  double depthM = 0.3;           // snowfall depth on open flat ground (m of snow)
  double siteSpacingM = 0.05;    // launch-site lattice
  int skyCellSites = 2;          // sky bucket side in sites (bucket = skyCellSites x siteSpacingM)
  int flakesPerSite = 4;
  double flutterMeanM = 0.0;     // lateral step per swirl (thesis: 1-7 cm)
  double flutterSigmaM = 0.0;
  double swirlHeightM = 0.1;     // vertical step per swirl
  double skyClearanceM = 0.5;    // the sky plane this far above the mesh's top (the world box's top)
  uint64_t seed = 1;
  // Adaptive sampling: lattice cells where a site's coverage (the share of its flakes that
  // reached the sky) differs from a neighbour's by more than this are split into four sites of
  // half the spacing, and every flake is traced again (1 or more: no refinement).
  double maxCoverageDiff = 0.25;
  // Optional sky mask (precipitation map): one factor per sky bucket, rows from the north
  // (empty: 1 everywhere).
  std::vector<float> skyMask;
};

struct FallenSnowStability {
  double reposeAngleDeg = 38.0;      // AOR (Kuroiwa, thesis Tab. 2.5: 40-50 degrees for dry pulverised snow)
  double transitionWidthDeg = 10.0;  // w: stable below AOR - w/2, unstable above AOR + w/2, linear between
  int depositRounds = 4;             // the storm laid down in this many equal rounds
  double stopFraction = 0.005;       // a round ends when no site moved more than this share of its mean deposit in a pass
  int maxPassesPerRound = 20000;
  double connectAngleDeg = 80.0;     // steepest base-to-base slope that still joins two sites
  double landingSpreadSpacings = 1.0;  // sigma of the landing splat, in lattice spacings
  uint64_t seed = 1;
};

// The snow body's settings (built by bakers/mesh_snow_body.h).
struct MeshSnowBodyOptions {
  double voxelSizeM = 0.0;     // 0: half the site spacing
  double adaptivity = 0.0;     // OpenVDB volume-to-mesh adaptivity in [0, 1] (0: uniform)
  int smoothingSteps = 2;      // mean-curvature smoothing passes of the level set
  double densityKgPerM3 = 150.0;  // for the fog volume (fresh snow on props)
};

}  // namespace snow
