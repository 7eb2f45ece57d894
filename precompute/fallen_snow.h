// Snow on any mesh, placement stage (Fearing 2000, thesis Ch. 7): where a storm's snow lands on
// arbitrary geometry -- under overhangs, on ledges, roofs and rails -- with mass conserved.
//
// Launch sites: the points of a square lattice (spacing siteSpacingM, in the world's xy) on
// every upward-facing triangle above them (a lattice point under an overhang has a site on the
// ground and one on the overhang's top: snow grows along +z, thesis §4.1); each site stands for
// the lattice cell's footprint, siteSpacingM². Downward and vertical faces get no site (they keep
// no snow, §6.2.3) but block flakes like every face.
// Flakes: from each site, flakesPerSite flakes traced upward along a random walk ("flutter",
// §7.5.1): each step rises swirlHeightM and moves sideways r ~ N(flutterMeanM, flutterSigmaM)
// (truncated at +-3 sigma, at least 0) in a uniform direction; a step that hits any face is
// blocked (the flake brings nothing); a flake that rises skyClearanceM above the mesh's top
// reaches the sky (the thesis's world box: every flake flutters on its way up, even from the top).
// Sky buckets: squares of skyCellM (a multiple of the site spacing, aligned with the lattice)
// over the world's xy bounds. Each bucket's snow, depthM x its area (x the sky mask), is shared
// among the flakes that reached it in proportion to their weight (footprint / flakes a site), so
// the mass is exactly the sky's over every bucket some flake reached (the thesis's normalisation:
// snow under an overhang is taken from above it, not created). A flake leaving the world's xy
// bounds brings nothing. A site's depth is the snow it received over its footprint (vertical).
//
// Adaptive sampling: where neighbouring sites' coverage differs (an overhang's shadow edge),
// the lattice cells are split into quarters (one level) and the flakes traced again.
//
// Not here yet (README "Snow on meshes"): deeper refinement levels, the stability stage
// (angle-of-repose relaxation, snow falling over edges), the snow body (SDF, meshing) and the
// bake mode.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "mesh.h"

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

struct SnowSite {
  std::array<float, 3> position{};  // on the face, metres (x east, y north, z up)
  uint32_t face = 0;
  int level = 0;                     // 0: the lattice; 1: a refined cell's quarter
  int column = 0, row = 0;           // cell on its level's lattice (row 0 at the north)
  float footprintM2 = 0;             // horizontal area it stands for
  float depthM = 0;                  // vertical snow depth received
  int flakesReached = 0;             // of flakesPerSite
};

struct FallenSnow {
  std::vector<SnowSite> sites;
  int columns = 0, rows = 0;             // lattice
  int bucketColumns = 0, bucketRows = 0; // sky buckets
  double originX = 0, originY = 0;       // the world's north-west corner (x min, y max)
  double skyMassM3 = 0;     // snow of the buckets some flake reached
  double placedM3 = 0;      // snow on the sites (equals skyMassM3 up to rounding)
  long long flakes = 0, blocked = 0, leftTheWorld = 0;
  int emptyBuckets = 0;     // buckets no flake reached (their snow falls past the geometry)
  int refinedCells = 0;     // lattice cells split by the adaptive sampling
  double seconds = 0;
};

FallenSnow placeFallenSnow(const TriangleMesh& mesh, const FallenSnowSettings& settings);

}  // namespace snow
