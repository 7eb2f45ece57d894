// DIR/manifest.json: every file a bake wrote, with its content, unit, range and grid, and what
// produced it (program version, scene, seed, input hashes). No time stamps or timings: the same
// bake gives the same bytes.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "core/grid.h"
#include "static_snow/fallen_snow.h"

namespace snow {

struct ManifestFile {
  std::string path{};    // relative to the output folder
  std::string content{}; // e.g. "snow layer: powder"
  std::string unit{};    // e.g. "m"
  std::string format{};  // e.g. "OpenEXR, 1 channel float32, linear"
  double day = -1.0;     // season day of the frame; -1 for the end of the season
  float minValue = 0.f, maxValue = 0.f;
  int width = 0, height = 0;  // 0: the grid's
  // Quantised encodings (png16, png8, r16): value = lo + (hi - lo) p / (2^bits - 1), NODATA cells
  // written as `nodataPixel`; rangeMode "fixed", "season" or "own" (empty: not quantised).
  std::string rangeMode{};
  double rangeLo = 0, rangeHi = 0;
  int nodataPixel = 0;
  // [outputs.tiles]: which tile of the output this file is, its first pixel in the untiled image,
  // and its georeference (its north-west corner in the terrain's coordinates, and a pixel's size).
  std::string tileConvention{};  // empty: not a tile
  int tileColumn = 0, tileRow = 0, tileX = 0, tileY = 0;
  double tileOriginX = 0, tileOriginY = 0, pixelSizeX = 0, pixelSizeY = 0;
  // Not written: the writer's count when it listed the file, the order in which a bake across
  // ranks merges the files its ranks wrote (OutputWriter::writesTile).
  long long listing = -1;
};

struct ManifestSkier {
  double day = 0;
  int x = 0, y = 0;
  bool user = false;
  int cells = 0;
  double lengthM = 0, dropM = 0;
  bool triggered = false;
  std::string why;
};

struct ManifestPhenomenon {
  std::string name;
  unsigned long long starts = 0, steps = 0, stops = 0, skippedSteps = 0;
};

struct ManifestAvalanche {
  double day = 0;
  int x = 0, y = 0;
  bool user = false, released = false;
  std::string why;
  int releaseCells = 0, footprintCells = 0, steps = 0;
  double releasedM3 = 0, depositM3 = 0, runoutM = 0, fallHeightM = 0, simulatedS = 0;
  double ruptureSlopeDeg = 0;
};

// mode = "occlusion": the settings the snow cover came from.
struct ManifestOcclusion {
  double sMaxM = 0, tauAmbient = 0, tauSun = 0, aoRadiusM = 0, day = 0, dayOfYear = 0, turbidity = 0;
  int aoRays = 0;
  std::vector<std::pair<double, double>> sunHoursAndWeights;  // solar hour, normalised luminance weight
  std::string meshSource;  // the input mesh whose vertices carry the snow (mesh terrains), or empty
};

// Art direction: a raster the scene painted with, and a timeline edit.
struct ManifestRaster {
  std::string role;        // e.g. "initial_snow.unstable", "multipliers.no_snow", "edits[2].mask"
  std::string source;      // the [masks] name and file, or the file
  std::string hash;        // FNV-1a 64 of the file's bytes
  std::string reader, placement, description;
  int width = 0, height = 0;  // the file's pixels
  double coverage = 1, minValue = 0, maxValue = 0, meanValue = 0;  // on the grid, valid cells
};
struct ManifestEdit {
  double day = 0;
  std::string op, layer, to, mask;  // mask empty: everywhere
  double depthM = -1;               // -1: none (move the whole layer)
  double volumeM3 = 0;              // snow the edit added (negative: removed)
  std::string label;
};

struct Manifest {
  std::string mode = "season";
  std::vector<std::pair<std::string, double>> parameters;  // every model parameter as used (key, value)
  ManifestOcclusion occlusion;
  std::string programVersion;
  std::string sceneSource;
  std::string sceneName;
  std::string sceneHash;
  std::string terrainSource;
  std::string terrainHash;
  std::string coordinateSystem;
  unsigned long long seed = 0;
  std::string backend;
  GridSpec grid;
  double latitudeDeg = 0.0;
  double seasonDays = 0.0;
  std::string seasonStartDate;
  unsigned long long events = 0;
  double snowfallAddedM3 = 0, meltRemovedM3 = 0, finalSnowM3 = 0, initialSnowM3 = 0;
  std::vector<ManifestPhenomenon> phenomena;
  std::vector<ManifestAvalanche> avalanches;
  std::vector<ManifestSkier> skiers;
  std::vector<ManifestRaster> artRasters;
  std::vector<ManifestEdit> edits;
  double editsNetM3 = 0, noSnowRemovedM3 = 0;
  std::vector<ManifestFile> files;
  // How it was run: the command line (empty when a library called it) and every input file's hash.
  std::vector<std::string> commandLine;
  std::vector<std::pair<std::string, std::string>> inputHashes;  // path, FNV-1a 64
  // The memory breakdown, one JSON object (bake/memory_model.h): written on one line of its own,
  // the only line that differs between two runs of a bake (the measured peak varies).
  std::string memoryJson;
};

std::string manifestToJson(const Manifest& manifest);

// mode = "mesh": the snow on a mesh, its settings and what each stage did.
struct MeshSnowFile {
  std::string path, content, unit, format;
};
struct MeshSnowManifest {
  std::string programVersion, sceneSource, sceneName, sceneHash, meshSource, meshHash;
  size_t triangles = 0;
  float boundsMin[3] = {0, 0, 0}, boundsMax[3] = {0, 0, 0};
  unsigned long long seed = 0;
  FallenSnowSettings placement;
  FallenSnowStability stability;
  size_t sites = 0;
  double skyM3 = 0, placedM3 = 0;
  FallenSnowStabilityReport stabilityReport;
  double voxelSizeM = 0;
  size_t bodyTriangles = 0;
  std::vector<MeshSnowFile> files;
  std::vector<std::string> commandLine;  // as Manifest's
  std::string memoryJson;                // as Manifest's, bytes per launch site
};
std::string meshSnowManifestToJson(const MeshSnowManifest& manifest);

}  // namespace snow
