// Stage 2: the terrain (DEM, heightmap, raw or mesh), the occluder meshes and the latitude.
#include "core/format.h"
#include "core/grid_window.h"
#include "stages.h"

namespace snow {

BakeTerrain loadBakeTerrain(const Scene& scene, std::ostream& log) {
  BakeTerrain t;
  auto t0 = WallClock::now();
  t.terrain = loadTerrain(scene.terrain);
  const TerrainInfo& ti = t.info();
  log << "terrain: " << ti.source << " (" << ti.format << "): " << ti.spec.width << " x " << ti.spec.height << " cells of "
      << fixed(ti.spec.cellSizeXM, 2) << " x " << fixed(ti.spec.cellSizeYM, 2) << " m, " << fixed(ti.minElevationM, 0) << "-"
      << fixed(ti.maxElevationM, 0) << " m, " << ti.nodataCells << " NODATA cells"
      << (ti.filledCells ? ", " + std::to_string(ti.filledCells) + " filled" : std::string()) << ", " << ti.coordinateSystem << " ("
      << fixed(elapsedSeconds(t0), 2) << " s)\n";
  if (!ti.resampling.empty()) log << "  resampled: " << ti.resampling << "\n";
  if (!scene.occluders.empty()) {
    t0 = WallClock::now();
    t.occluders = loadOccluders(scene.occluders);
    size_t triangles = 0;
    for (const auto& mesh : t.occluders) triangles += mesh.triangles.size();
    log << "occluders: " << scene.occluders.size() << " meshes, " << triangles << " triangles (" << fixed(elapsedSeconds(t0), 2)
        << " s); they shade the sun exposure\n";
  }
  t.latitudeDeg = scene.latitudeDeg ? *scene.latitudeDeg : (ti.latitudeKnown ? ti.centreLatitudeDeg : 45.0);
  if (!scene.latitudeDeg)
    log << "site: latitude " << fixed(t.latitudeDeg, 3) << " deg " << (ti.latitudeKnown ? "(from the DEM)" : "(default; set site.latitude_deg)")
        << "\n";
  return t;
}

SnowState initialState(const BakeTerrain& t, const CellRect& cells) {
  SnowState state;
  state.allocate(windowSpec(t.info().spec, cells), [](FieldRole r) { return r != FieldRole::Record && r != FieldRole::Static; });
  state.bedrockM = gridWindow(t.terrain.heightsM, cells);
  state.validCell = gridWindow(t.terrain.valid, cells);
  return state;
}

}  // namespace snow
