// `snowbake info`: the terrain as the loader read it (size, cell size, heights, NODATA, georeference).
#include "info.h"

#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/default_terrain.h"
#include "core/errors.h"
#include "core/format.h"
#include "scene/scene.h"
#include "inputs/terrain_loader.h"

namespace snow {

namespace fs = std::filesystem;

std::string describeTerrain(const std::string& source, bool json, const std::vector<std::string>& sets) {
  // A scene (file or preset) describes the terrain with its reading options; anything else is a
  // terrain file read with the defaults.
  std::string ext = fs::path(source).extension().string();
  Terrain t;
  if (source == "builtin:ridged") {
    t = makeBuiltinTerrain(DefaultTerrainOptions{});
  } else if (source.rfind("preset:", 0) == 0 || ext == ".toml") {
    t = loadTerrain(loadScene(source, sets).terrain);
  } else {
    if (!sets.empty()) throw InputError("--set applies to scene files; " + source + " is a terrain file");
    TerrainSource src;
    src.file = source;
    std::error_code ec;
    if (!fs::exists(source, ec)) throw InputError(source + ": terrain file does not exist");
    const TerrainFormat format = detectTerrainFormat(src);
    if (format != TerrainFormat::Dem)
      throw InputError(source + ": a " + enumName(format) + " file needs its cell size (and height mapping) from a scene: run "
                       "`snowbake info SCENE.toml` with a scene whose [terrain] names it");
    t = loadTerrain(src);
  }
  const TerrainInfo& i = t.info;
  if (json) {
    nlohmann::ordered_json j;
    j["source"] = i.source;
    j["format"] = i.format;
    j["driver"] = i.driver;
    j["width"] = i.spec.width;
    j["height"] = i.spec.height;
    j["cell_size_x_m"] = i.spec.cellSizeXM;
    j["cell_size_y_m"] = i.spec.cellSizeYM;
    j["native_cell_size_x"] = i.nativeCellSizeX;
    j["native_cell_size_y"] = i.nativeCellSizeY;
    j["native_unit"] = i.nativeUnit;
    j["min_elevation_m"] = i.minElevationM;
    j["max_elevation_m"] = i.maxElevationM;
    j["native_width"] = i.nativeWidth;
    j["native_height"] = i.nativeHeight;
    j["nodata_cells"] = i.nodataCells;
    j["filled_cells"] = i.filledCells;
    j["height_mapping"] = i.heightMapping;
    j["resampling"] = i.resampling;
    j["coordinate_system"] = i.coordinateSystem;
    j["coordinate_decision"] = i.coordinateDecision;
    if (i.latitudeKnown) j["centre_latitude_deg"] = i.centreLatitudeDeg; else j["centre_latitude_deg"] = nullptr;
    return j.dump(2) + "\n";
  }
  std::ostringstream o;
  o << i.source << "\n"
    << "  format:            " << i.format << " (" << i.driver << ")\n"
    << "  grid:              " << i.spec.width << " x " << i.spec.height << " cells\n"
    << "  cell size:         " << fixed(i.spec.cellSizeXM, 3) << " m (x) x " << fixed(i.spec.cellSizeYM, 3) << " m (y)"
    << "  [native " << i.nativeCellSizeX << " x " << i.nativeCellSizeY << " " << i.nativeUnit << "]\n"
    << "  elevation:         " << fixed(i.minElevationM, 1) << " to " << fixed(i.maxElevationM, 1) << " m\n"
    << "  NODATA cells:      " << i.nodataCells << (i.filledCells ? " (" + std::to_string(i.filledCells) + " filled)" : std::string())
    << "\n"
    << "  coordinate system: " << i.coordinateSystem << "\n"
    << "  decided by:        " << i.coordinateDecision << "\n";
  if (i.latitudeKnown) o << "  centre latitude:   " << fixed(i.centreLatitudeDeg, 4) << " deg\n";
  if (!i.heightMapping.empty()) o << "  heights:           " << i.heightMapping << "\n";
  if (!i.resampling.empty()) o << "  resampled:         " << i.resampling << "\n";
  return o.str();
}

}  // namespace snow
