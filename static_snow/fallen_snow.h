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
// Stability (thesis Ch. 8), stabilizeFallenSnow below: the placed snow is laid down in a few
// deposit rounds, each relaxed to its angle of repose on the sites' neighbourhood graph:
//  - Sites inside a closed solid (the first face straight above is an upward face, hit from behind:
//    the ground under a block) take no part. (A single upward sheet with nothing under it reads
//    as a solid's top too: give roofs an underside.)
//  - Neighbours: sites within 1.5 spacings (the coarser site's) in xy whose bases are joined by a
//    slope of at most connectAngleDeg and with nothing between them (a segment lifted half their
//    distance is clear): a roof and the ground below its edge, or the ground on either side of a
//    wall, are not neighbours.
//  - Each pass moves snow everywhere at once (the thesis's multi-pass "everything moves at once",
//    as a Jacobi step: outflows from the pass's snow tops, then a gather): site s sheds toward a
//    lower neighbour n the volume that brings their snow tops' slope down to an angle theta*
//    drawn from the transition curve (uniform over [AOR - w/2, AOR + w/2], seeded per round and
//    pair: the thesis's stochastic stability as a random threshold field each round settles
//    into; w = 0 is a sharp AOR), divided by its receivers + 1
//    (they may fill from elsewhere in the same pass), all outflows scaled to the snow there. In
//    double: the mass is kept to double rounding.
//  - Lattice directions with no neighbour: a stab from the base rising at the connect angle to
//    just past the footprint finds a wall (snow rests against it); otherwise an edge at the
//    height z_e of the surface at the footprint's edge: snow standing above it by more than the
//    repose slope (and above the snow where it would land: an edge buried in the snow below is no
//    edge) goes over and falls straight down from just past the footprint; where it lands
//    (a ray) it is spread over the sites near the landing point, in sight of it and lower than the
//    edge (a Gaussian, not
//    snapped to one site: the thesis's stalagmites). A fall that meets nothing leaves the world
//    (counted: placed = kept + left the world, to rounding).
//  - A round ends when no site shed more than stopFraction of the round's mean deposit in a
//    pass (the thesis's 0.5 %; a steady stream down a face counts as moving), or at
//    maxPassesPerRound (counted as unconverged).
//
// The snow body (the level set and its mesh) is built from this stage's output in
// bakers/mesh_snow_body.h, and `mode = "mesh"` bakes it. Not done (docs/models/snow-on-meshes.md):
// refinement beyond one level, wind in the stability phase.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "inputs/mesh.h"
#include "scene/mesh_snow_options.h"

namespace snow {


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
  double siteSpacingM = 0;  // the lattice's (level 0)
  double seconds = 0;
};

FallenSnow placeFallenSnow(const TriangleMesh& mesh, const FallenSnowSettings& settings);


struct FallenSnowStabilityReport {
  int rounds = 0, passes = 0;
  int unconvergedRounds = 0;        // rounds that hit maxPassesPerRound
  double lastMovedM = 0;            // the largest move of the last pass
  long long neighbourLinks = 0;     // directed
  long long buriedSites = 0;        // inside a closed solid (the first face above seen from behind): left out
  long long wallDirections = 0, dropDirections = 0, unlandedDrops = 0;
  double overEdgesM3 = 0;           // snow that went over a drop
  double leftTheWorldM3 = 0;        // of it, snow that landed on nothing
  double placedM3 = 0, finalM3 = 0; // placedM3 = finalM3 + leftTheWorldM3 to rounding
  double seconds = 0;
};

// Relaxes `snow` (from placeFallenSnow on `mesh`) to its angle of repose; sites' depthM updated.
FallenSnowStabilityReport stabilizeFallenSnow(const TriangleMesh& mesh, FallenSnow& snow, const FallenSnowStability& settings);


}  // namespace snow
