// The output layers: one row per layer (its name in [outputs].layers, unit, what it holds, the
// modes that make it and how it is computed). The scene validator, the writers, the manifest and
// the generated reference all read this table; a new layer is one row and its compute function.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/grid.h"
#include "core/parameters.h"
#include "core/snow_state.h"
#include "scene.h"

namespace snow {

// Bit flags: which modes can make a layer.
enum LayerModes : uint8_t { kSeasonMode = 1, kOcclusionMode = 2, kGridModes = kSeasonMode | kOcclusionMode };
// Bit flags: what a layer is computed from beyond the snow state's fields, so a writer fetches
// the day's wind or sun only when a layer of that day needs it.
enum LayerNeeds : uint8_t {
  kNeedsState = 0,
  kNeedsWind = 1,
  kNeedsSun = 2,
  kNeedsSkiTracks = 4,
  kNeedsRouteMap = 8,
  kNeedsOcclusion = 16,
};

// mode = "occlusion"'s four fields (Foldes & Benes 2007), one value a cell.
struct OcclusionGrids {
  Grid<float> ambient, sunVisibility, accumulationM, dissipationM;
};

// Everything a layer of one output day can be computed from; pointers a row does not need may be null.
struct LayerInputs {
  const SnowState* state = nullptr;
  const ModelParameters* params = nullptr;
  const OutputRequest* outputs = nullptr;      // the scene's [outputs] (layers with settings of their own)
  const Grid<float>* windXMps = nullptr;       // kNeedsWind: the day's wind field and wind-effect surface
  const Grid<float>* windYMps = nullptr;
  const Grid<float>* windEffectZM = nullptr;
  const Grid<float>* sunHours = nullptr;       // kNeedsSun: the day's exposure I (hours)
  double seaLevelTemperatureC = 0.0;           // kNeedsSun: the day's T0
  const Grid<float>* skiDepth = nullptr;       // kNeedsSkiTracks: the ski-track texture (its own size)
  const Grid<float>* routeMap = nullptr;       // kNeedsRouteMap: empty when there are no skiers
  const OcclusionGrids* occlusion = nullptr;   // kNeedsOcclusion
};

enum class LayerKind : uint8_t {
  Float,    // one float a cell: a float image, plus every requested encoding and the multi-channel EXR
  Preview,  // an RGB picture of the day (PNG), drawn by the writer
};

struct LayerInfo {
  const char* name;
  const char* unit;     // as in the manifest: m, 1, h, degC, m/s, deg, sRGB
  const char* content;  // what the layer holds, as in the manifest
  uint8_t modes;        // LayerModes
  uint8_t needs;        // LayerNeeds
  LayerKind kind;
  Grid<float> (*compute)(const LayerInputs&);  // null for previews
  // The record fields (FieldRole::Record) the layer reads: the season keeps only the fields some
  // layer of the bake reads (SeasonConfig::recordFields), the others are never allocated.
  SnowFieldSet records = 0;
};

// Every layer, in the order the scene reference lists them.
std::span<const LayerInfo> layerTable();
// The row of `name`, or null.
const LayerInfo* findLayer(const std::string& name);
// What the layers `names` are computed from together: their LayerNeeds flags or'd (a name
// without a row adds none).
uint8_t layersNeeds(const std::vector<std::string>& names);
// The record fields the layers `names` read together.
SnowFieldSet layersRecords(const std::vector<std::string>& names);

}  // namespace snow
