#include "bake_manifest.h"

#include <algorithm>
#include <iomanip>
#include <sstream>

#include "core/hash.h"

namespace snow {
namespace {

std::string isoDate(int year, int month, int day) {
  std::ostringstream d;
  d << std::setfill('0') << std::setw(4) << year << "-" << std::setw(2) << month << "-" << std::setw(2) << day;
  return d.str();
}

void addSeasonRecords(Manifest& m, const SeasonReport& report) {
  for (const AvalancheRecord& a : report.avalanches)
    m.avalanches.push_back({a.day, a.ruptureX, a.ruptureY, a.user, a.released, a.why, a.releaseCells, a.footprintCells, a.steps,
                            a.releasedM3, a.depositM3, a.runoutM, a.fallHeightM, a.simulatedS, a.ruptureSlopeDeg});
  for (const SkierRecord& k : report.skiers)
    m.skiers.push_back({k.day, k.startX, k.startY, k.user, k.cells, k.lengthM, k.dropM, k.triggered, k.why});
  for (ManifestEdit& e : m.edits)
    for (const EditRecord& r : report.edits)
      if (r.label == e.label) e.volumeM3 = r.volumeM3;
  m.editsNetM3 = report.editsNetM3;
  m.noSnowRemovedM3 = report.noSnowRemovedM3;
  m.events = report.events;
  m.snowfallAddedM3 = report.snowfallAddedM3;
  m.meltRemovedM3 = report.meltRemovedM3;
  m.initialSnowM3 = report.initial.totalM3();
  m.finalSnowM3 = report.final.totalM3();
  for (const auto& p : report.phenomena) m.phenomena.push_back({p.name, p.starts, p.steps, p.stops, p.skippedSteps});
}

}  // namespace

std::string terrainHashOf(const Scene& scene, const Terrain& terrain) {
  return scene.terrain.builtin ? Fnv1a64().add(terrain.heightsM.data(), terrain.heightsM.size() * sizeof(float)).hex()
                               : hashFileFnv1a64(scene.terrain.file);
}

Manifest assembleBakeManifest(const BakeManifestInputs& in) {
  const Scene& scene = *in.scene;
  const Terrain& terrain = *in.terrain;
  Manifest m;
  m.programVersion = in.programVersion;
  m.sceneSource = scene.sourceName;
  m.sceneName = scene.name;
  m.sceneHash = Fnv1a64().add(scene.canonicalToml).hex();
  m.terrainSource = terrain.info.source;
  m.terrainHash = in.terrainHash.empty() ? terrainHashOf(scene, terrain) : in.terrainHash;
  m.coordinateSystem = terrain.info.coordinateSystem;
  m.seed = scene.seed;
  m.backend = in.backendName;
  m.mode = enumName(scene.mode);
  for (const ParameterInfo& info : parameterTable()) m.parameters.push_back({info.key, scene.params.*(info.member)});
  m.occlusion = in.occlusion;
  m.grid = terrain.info.spec;
  m.latitudeDeg = in.latitudeDeg;
  m.seasonDays = scene.days;
  m.seasonStartDate = isoDate(scene.startYear, scene.startMonth, scene.startDay);
  m.artRasters = in.artRasters;
  m.edits = in.edits;
  addSeasonRecords(m, *in.report);
  m.files = in.files;
  m.commandLine = in.commandLine;
  if (!scene.terrain.builtin) m.inputHashes.push_back({scene.terrain.file, m.terrainHash});
  for (const auto& o : scene.occluders) m.inputHashes.push_back({o.file, hashFileFnv1a64(o.file)});
  for (const ManifestRaster& r : in.artRasters)
    if (std::find_if(m.inputHashes.begin(), m.inputHashes.end(), [&](const auto& h) { return h.first == r.source; }) == m.inputHashes.end())
      m.inputHashes.push_back({r.source, r.hash});
  return m;
}

}  // namespace snow
