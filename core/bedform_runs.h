// Wind bedforms on the host: the scene-level parameters' validation, the test windows, and the
// measurements the tests and the benchmark make of a bedform field (repose, migration, bodies,
// face slopes). The model, BedformParameters and makeBedformArgs: phenomena/bedforms.h.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "grid.h"
#include "phenomena/bedforms.h"
#include "snow_state.h"

namespace snow {

// Empty when the parameters are usable on the grid `spec` (its smaller cell side, and an even
// width and height when periodic), else the problem in words (naming the scene key).
std::string validateBedformParameters(const BedformParameters& p, const GridSpec& spec);

// A flat test window: w x h cells of `cellM`, powder `meanDepthM` plus uniform noise of +-noiseM
// (seeded), a uniform wind, a constant temperature (sea-level T0 = 0 gives T = temperatureC).
SnowState makeBedformWindow(int w, int h, double cellM, double meanDepthM, double noiseM, float windXMps,
                            float windYMps, float temperatureC, uint64_t seed);

// The documented barchan set (docs/models/bedforms.md), shared by the tests, the benchmark and the GPU tests: the default
// parameters on a periodic (tileable) window without sintering, and an n x n window of 0.5 m
// cells holding 5 cm of powder with +-1 slab of noise (seed 3) under a steady 10 m/s westerly at
// -10 degC.
BedformParameters periodicBedformParameters();
SnowState makeBarchanWindow(int n);

// Largest excess of a 4-neighbour surface step over tan(repose) x spacing, among steps whose
// higher cell holds at least one slab of powder (bare steps are the bed's own): <= 0 means at rest.
double maxReposeExcessM(const SnowState& s, double tanRepose, double slabM, bool periodic);

// Shift (cells along +x, periodic) that best maps field a onto field b (cross-correlation of
// the anomalies), searched in [-maxShift, maxShift].
int migrationShiftCells(const Grid<float>& a, const Grid<float>& b, int maxShift);

// Mean windward (surface rising downwind, +x) and lee (falling) slopes, over cells deeper than
// minDepthM whose slope along x exceeds minSlope; and how many of each are steeper than
// steepSlope (slip faces: a form's steep face is its lee when steepLeeCells dominates).
struct FaceSlopes {
  double windward = 0, lee = 0;
  long long windwardCells = 0, leeCells = 0;
  long long steepWindwardCells = 0, steepLeeCells = 0;
};
FaceSlopes faceSlopesAlongX(const Grid<float>& depth, double cellM, double minSlope, double minDepthM = 0.0,
                            double steepSlope = 1e30);

// Connected bodies (4-neighbour, periodic) of depth above thresholdM, for wind along +x:
// length (along x) and width (along y) in metres, height above the threshold's floor (max
// depth), and the horns' lead: how far the body's most downwind flank row (a quarter of its width
// or more from the crest's row) reaches past the crest's rows, in metres (positive: a horn
// points downwind, as a barchan's; a dome's flanks stay behind its front).
struct BedformBody {
  double lengthM = 0, widthM = 0, heightM = 0, hornLeadM = 0;
  long long cells = 0;
};
std::vector<BedformBody> findBedformBodies(const Grid<float>& depth, double cellM, double thresholdM);

// The forms of a field with the wind along +x, as the tests and the benchmark count them: bodies
// of the 3 x 3-smoothed (periodic) depth above 0.1 m (or 1.5 slabs, if more: the loose slabs
// between the forms are not a form) that are at least 3 m wide and 40 cells
// (narrower ones are streaks and embryos whose horns a 0.5 m grid cannot show); how many have a
// horn leading the crest downwind, how many the centre leading, how many fall in Filhol & Sturm's
// snow-barchan range (3-20 m long, 0.1-0.5 m tall, one slab of tolerance), their mean length and
// height; and, on the unsmoothed field deeper than that, the faces steeper than 0.7 tan(repose).
struct BarchanCensus {
  int bodies = 0, hornsDownwind = 0, centreLeading = 0, inSnowRange = 0;
  double meanLengthM = 0, meanHeightM = 0;
  FaceSlopes faces;
};
BarchanCensus barchanCensus(const Grid<float>& depth, double cellM, double tanRepose, double slabM);

}  // namespace snow
