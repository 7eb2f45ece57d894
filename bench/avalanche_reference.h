// The avalanche reference cases (../shared/data/avaframe/<case>/, AvaFrame com1DFA runs): one
// masked release of the case's release thickness as cold dry unstable snow, run to rest, and
// the scores AvaFrame's AIMEC analysis uses, for ours and the reference alike:
//   runout   the farthest footprint cell (peak flowing thickness > 0.1 m) projected on the path
//            (path_ab.csv, from the top), as arc length;
//   error    (ours - reference) / (reference runout - the release top's arc length);
//   alpha    the travel angle atan(fall / distance) from the release's highest cell to the runout
//            point on the path (distance along the path);
//   IoU      intersection over union of the two footprints on the DEM's grid (the reference's
//            peak thickness sampled at each DEM cell centre through both georeferences);
//   speed    the peak speed's maximum against reference_pfv's.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "core/grid.h"
#include "core/parameters.h"

namespace snow {

// A one-band raster with its georeference: cell (i, j) covers [originX + i cellX, + cellX) x
// (originY - (j + 1) cellY, originY - j cellY] (north-up).
struct GeoRaster {
  int width = 0, height = 0;
  double originX = 0, originY = 0, cellX = 1, cellY = 1;
  std::vector<float> values;  // NODATA read as 0
  // The value of the cell holding world point (wx, wy); 0 outside.
  float sampleAt(double wx, double wy) const;
};

// Reads band 1 of a GDAL raster; InputError naming the file when it cannot.
GeoRaster readGeoRaster(const std::string& path);

struct AvalancheReferenceCase {
  std::string name;
  GridSpec spec;                 // the DEM's grid (spec.originX/Y: its north-west corner)
  double geoCellX = 0, geoCellY = 0;
  Grid<float> bedrockM;
  Grid<uint8_t> valid;
  Grid<float> releaseM;          // release thickness on the DEM's grid
  Grid<float> referencePftM;     // com1DFA's peak flow thickness, sampled at the DEM's cell centres
  double referencePeakSpeedMps = 0;  // max of reference_pfv over its own grid
  std::vector<std::pair<double, double>> pathXY;  // world coordinates, from the top
};

// The case folder's DEM, release, reference and path, on the DEM's grid. InputError when a file
// is missing. A resolution study's grid with `cellScale` k > 1: k times coarser (each k x k block
// of cells averaged, valid where all are); k < -1: |k| times finer (the DEM bilinear at the fine
// cells' centres, the release each fine cell its coarse cell's). The reference is sampled at the
// grid's cell centres either way, and the name says the cell size (avaKot_2.5m).
AvalancheReferenceCase loadAvalancheReferenceCase(const std::string& folder, int cellScale = 1);

struct AvalancheReferenceScores {
  std::string name;
  double runoutM = 0, referenceRunoutM = 0, releaseTopS = 0;
  double runoutError = 0;            // share of the reference's path length from the release top
  double alphaDeg = 0, referenceAlphaDeg = 0;
  double iou = 0;
  double peakSpeedMps = 0, referencePeakSpeedMps = 0;
  int footprintCells = 0, referenceFootprintCells = 0;
  double simulatedS = 0, seconds = 0, massError = 0;
  std::string why;                   // why the run stopped
  Grid<float> peakThicknessM;        // ours, for the picture
};

// Runs the case's release with `p` on the CPU backend and scores it.
AvalancheReferenceScores runAvalancheReferenceCase(const AvalancheReferenceCase& c, const ModelParameters& p);

// The four cases' names, in the order the stage and tests run them.
const std::vector<std::string>& avalancheReferenceCaseNames();

}  // namespace snow
