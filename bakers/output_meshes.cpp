// OutputWriter's meshes: the snow surface and body from one adaptive triangulation, snow on the
// [[occluders]] meshes, and occlusion mode's input mesh raised by its snow.
#include <tbb/task_group.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>

#include "core/format.h"
#include "core/util.h"
#include "mesh_snow_body.h"
#include "mesh_tiles.h"
#include "mesh_writer.h"
#include "output_writer.h"
#include "static_snow/fallen_snow.h"
#include "rtin.h"

namespace snow {

namespace fs = std::filesystem;

namespace {

// The mean snow depth of the valid cells in a ring two cells wide round a mesh's footprint: how
// deep snow lies on open flat ground near it.
double snowDepthRoundMesh(const SnowState& s, const TriangleMesh& mesh, long& ring) {
  float lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (const auto& p : mesh.positions)
    for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  const double dx = s.spec.cellSizeXM, dy = s.spec.cellSizeYM, H = s.spec.height;
  double sum = 0;
  ring = 0;
  // Only the rows and columns near the footprint (a cell's centre is at ((col + 1/2) dx,
  // (H - row - 1/2) dy)).
  const int col0 = std::max(0, static_cast<int>(std::floor(lo[0] / dx)) - 3), col1 = std::min(s.spec.width - 1, static_cast<int>(hi[0] / dx) + 3);
  const int row0 = std::max(0, static_cast<int>(std::floor(H - hi[1] / dy)) - 3), row1 = std::min(s.spec.height - 1, static_cast<int>(H - lo[1] / dy) + 3);
  for (int row = row0; row <= row1; ++row)
    for (int col = col0; col <= col1; ++col) {
      const double x = (col + 0.5) * dx, y = (H - row - 0.5) * dy;
      const bool near = x > lo[0] - 2 * dx && x < hi[0] + 2 * dx && y > lo[1] - 2 * dy && y < hi[1] + 2 * dy;
      const bool under = x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1];
      if (near && !under && s.validCell(col, row)) sum += s.depthM(col, row), ++ring;
    }
  return ring > 0 ? sum / ring : 0.0;
}
}  // namespace

void OutputWriter::writeMeshes(const Day& d) {
  if (src_.plan) return planMeshes(d);
  if (scene_.meshSnow.onOccluders && !d.frame) writeOccluderSnow(d);
  if (scene_.outputs.meshes.empty()) return;
  writeGridMeshParts(d);
  if (src_.snowMesh && !d.frame) writeSnowMesh(d);
}

// The meshes writeMeshes would write, by the same names; whether some are left out depends on the snow.
void OutputWriter::planMeshes(const Day& d) {
  const auto& out = scene_.outputs;
  auto planAll = [&](const std::string& stem, const std::string& what, const std::string& condition) {
    for (const std::string& format : out.meshes) planFile(d.base(stem, src_.outDir) + "." + format, meshFormatDescription(format), what, 0.0, false, condition);
  };
  if (scene_.meshSnow.onOccluders && !d.frame)
    for (size_t k = 0; k < src_.occluders->size(); ++k) {
      const std::string& source = (*src_.occluders)[k].source;
      for (const std::string& format : out.meshes)
        planFile(d.base("occluder_" + std::to_string(k) + "_snow", src_.outDir) + "." + format, meshFormatDescription(format),
                 "snow body on the occluder " + source, 0.0, false, "left out when no snow lies on the terrain round the mesh");
    }
  if (out.meshes.empty()) return;
  const GridSpec& spec = d.s.spec;
  for (const std::string& part : out.meshParts) {
    if (part == "body") {
      planAll("snow_body", "the snow body alone, closed", "left out when there is no snow");
      continue;
    }
    const int tileCells = out.meshTileSizeM > 0.0 ? std::max(1, static_cast<int>(std::lround(out.meshTileSizeM / spec.cellSizeXM))) : 0;
    if (tileCells == 0 || tileCells >= std::max(spec.width, spec.height)) {
      planAll("snow_surface", "snow surface B+C+S+U+P", "");
      continue;
    }
    // cutIntoTiles: vertices at cell centres, so the last tile holds the centre of the last cell.
    const int columns = static_cast<int>(std::floor((spec.width - 0.5) / tileCells)) + 1;
    const int rows = static_cast<int>(std::floor((spec.height - 0.5) / tileCells)) + 1;
    for (int row = 0; row < rows; ++row)
      for (int column = 0; column < columns; ++column)
        planAll("snow_surface_x" + std::to_string(column) + "_y" + std::to_string(row), "snow surface B+C+S+U+P, a tile",
                src_.planNodata ? "left out when it holds no triangle (NODATA cells only)" : "");
  }
  if (src_.planSnowMesh && !d.frame)
    for (const std::string& format : out.meshes)
      planFile((fs::path(src_.outDir) / ("snow_mesh." + format)).string(), meshFormatDescription(format),
               "the input mesh with its vertices raised by their snow depth", 0.0);
}

// Snow on the [[occluders]] (Fearing, as mode = "mesh"), as deep as the terrain's snow round each
// mesh. Sites below the terrain's snow surface are buried in it (their snow is the terrain's) and
// left bare.
void OutputWriter::writeOccluderSnow(const Day& d) {
  const SnowState& s = d.s;
  const double dx = s.spec.cellSizeXM, dy = s.spec.cellSizeYM, H = s.spec.height;
  for (size_t k = 0; k < src_.occluders->size(); ++k) {
    const TriangleMesh& mesh = (*src_.occluders)[k];
    long ring = 0;
    FallenSnowSettings ps = scene_.meshSnow.placement;
    ps.seed = scene_.seed + k;
    ps.depthM = snowDepthRoundMesh(s, mesh, ring);
    const std::string name = "occluder_" + std::to_string(k) + "_snow";
    if (!(ps.depthM > 0.0)) {
      occluderNotes_ += "  " + name + ": no snow on the terrain round " + mesh.source + ": no snow body written\n";
      continue;
    }
    auto tm = WallClock::now();
    FallenSnow snow = placeFallenSnow(mesh, ps);
    double buriedM3 = 0;
    for (SnowSite& site : snow.sites) {
      const int col = std::clamp(static_cast<int>(site.position[0] / dx), 0, s.spec.width - 1);
      const int row = std::clamp(static_cast<int>(H - 1 - site.position[1] / dy), 0, s.spec.height - 1);
      if (site.position[2] < s.bedrockM(col, row) + s.depthM(col, row)) buriedM3 += site.depthM * site.footprintM2, site.depthM = 0.f;
    }
    FallenSnowStability ss = scene_.meshSnow.stability;
    ss.seed = scene_.seed + k;
    const FallenSnowStabilityReport st = stabilizeFallenSnow(mesh, snow, ss);
    const MeshSnowBody body = buildMeshSnowBody(snow, mesh, scene_.meshSnow.body);
    currentSink().addSeconds("snow on the occluders", elapsedSeconds(tm));
    // (Logged after the writers join: this runs beside the layers' thread.)
    occluderNotes_ += "  " + name + ": " + mesh.source + ", " + fixed(ps.depthM, 3) + " m as on the terrain round it (" +
                      std::to_string(ring) + " cells), " + std::to_string(snow.sites.size()) + " sites, " + fixed(snow.placedM3, 3) +
                      " m^3 placed (" + fixed(buriedM3, 3) + " in the terrain's snow), " + fixed(st.finalM3, 3) + " m^3 kept, " +
                      std::to_string(body.mesh.triangles.size()) + " triangles\n";
    for (const std::string& format : scene_.outputs.meshes) {
      const std::string path = d.base(name, src_.outDir) + "." + format;
      writeMesh(path, format, body.mesh);
      listFile(path,
               "snow body on the occluder " + mesh.source + " (Fearing: placement and stability, " + fixed(ps.depthM, 3) +
                   " m as on the terrain round it; the terrain's frame)",
               "m", meshFormatDescription(format), d.day, 0.f, 0.f);
    }
  }
}

// One adaptive triangulation for every part asked (rtin.h), within the vertical error bound of
// the surface (and of the bedrock, the body's bottom); each part on its own task into its own
// sink, merged in the parts' order. An untiled surface is written as it is read from the
// triangulation (writeSurfaceMeshes: no mesh arrays); the other parts' meshes are built, then the
// triangulation and the surface grid freed, then their files written (the triangulation is not
// held beside the files being written).
void OutputWriter::writeGridMeshParts(const Day& d) {
  const SnowState& s = d.s;
  const auto& out = scene_.outputs;
  const auto& parts = out.meshParts;
  const bool body = std::find(parts.begin(), parts.end(), "body") != parts.end();
  Grid<float> surface = findLayer("surface")->compute(LayerInputs{&s});
  std::vector<const Grid<float>*> fields{&surface};
  if (body) fields.push_back(&s.bedrockM);
  const auto tTri = WallClock::now();
  RtinMesh triangulation = buildRtin(fields, s.validCell, out.meshMaxErrorM);
  currentSink().addSeconds("mesh triangulation (adaptive)", elapsedSeconds(tTri));
  const std::string frameNote = " (adaptive triangulation, vertical error at most " + fixed(out.meshMaxErrorM, 3) +
                                " m at every grid point; x east, y north from the south-west corner; UVs line up with the maps)";
  auto listAll = [&](const std::string& stem, const MeshCounts& counts, const std::string& what) {
    for (const std::string& format : out.meshes)
      listFile(d.base(stem, src_.outDir) + "." + format,
               what + ", " + std::to_string(counts.vertices) + " vertices, " + std::to_string(counts.triangles) + " triangles" + frameNote, "m",
               meshFormatDescription(format), d.day, 0.f, 0.f);
  };
  auto writeAll = [&](const std::string& stem, const MeshData& mesh, const std::string& what) {
    for (const std::string& format : out.meshes) writeMesh(d.base(stem, src_.outDir) + "." + format, format, mesh);
    listAll(stem, {mesh.positions.size(), mesh.triangles.size()}, what);
  };
  const int tileCells = out.meshTileSizeM > 0.0 ? std::max(1, static_cast<int>(std::lround(out.meshTileSizeM / s.spec.cellSizeXM))) : 0;
  const bool tiled = !(tileCells == 0 || tileCells >= std::max(s.spec.width, s.spec.height));
  auto streamSurface = [&] {
    std::vector<std::pair<std::string, std::string>> files;
    for (const std::string& format : out.meshes) files.push_back({d.base("snow_surface", src_.outDir) + "." + format, format});
    listAll("snow_surface", writeSurfaceMeshes(files, triangulation, surface, s.spec), "snow surface B+C+S+U+P");
  };
  auto writeSurface = [&](const MeshData& mesh) {
    for (const MeshTile& t : cutIntoTiles(mesh, s.spec, tileCells))
      writeAll("snow_surface_x" + std::to_string(t.column) + "_y" + std::to_string(t.row), t.mesh,
               "snow surface B+C+S+U+P, tile column " + std::to_string(t.column) + " (from the west), row " + std::to_string(t.row) +
                   " (from the north) of " + std::to_string(tileCells) + " x " + std::to_string(tileCells) + " cells");
  };
  auto writeBody = [&](const MeshData& mesh) {
    if (mesh.triangles.empty()) {
      log_ << "  snow_body" << d.dayTag << ": no snow, no mesh written\n";
      return;
    }
    writeAll("snow_body", mesh, "the snow body alone, closed (top on the snow surface, bottom on the bedrock, walls at the grid's edge)");
  };
  std::vector<OutputSink> partSinks(parts.size());
  std::vector<MeshData> meshes(parts.size());
  tbb::task_group partGroup;
  for (size_t k = 0; k < parts.size(); ++k)
    partGroup.run([&, k] {
      SinkScope scope(partSinks[k]);
      auto tm = WallClock::now();
      if (parts[k] == "surface" && !tiled) {
        streamSurface();  // its time listed with its files
        return;
      }
      meshes[k] = parts[k] == "surface" ? surfaceMesh(triangulation, surface, s.spec)
                                        : snowBodyMesh(triangulation, s.bedrockM, findLayer("depth")->compute(LayerInputs{&s}), s.validCell, s.spec);
      currentSink().addSeconds("mesh building", elapsedSeconds(tm));
    });
  partGroup.wait();
  triangulation = RtinMesh();
  surface = Grid<float>();
  for (size_t k = 0; k < parts.size(); ++k)
    partGroup.run([&, k] {
      SinkScope scope(partSinks[k]);
      if (parts[k] == "surface") {
        if (tiled) writeSurface(meshes[k]);
      } else {
        writeBody(meshes[k]);
      }
      meshes[k] = MeshData();  // freed once written
    });
  partGroup.wait();
  for (const OutputSink& partSink : partSinks) currentSink().merge(partSink);
}

// Occlusion mode on a mesh terrain: the input mesh with its vertices raised by their snow.
void OutputWriter::writeSnowMesh(const Day& d) {
  const TriangleMesh& m = *src_.snowMesh;
  for (const std::string& format : scene_.outputs.meshes) {
    const std::string path = (fs::path(src_.outDir) / ("snow_mesh." + format)).string();
    writeMesh(path, format, MeshData{m.positions, {}, {}, m.triangles});
    listFile(path,
             "the input mesh " + m.source + " with its vertices raised by their snow depth (occlusion mode, per vertex; " +
                 std::to_string(m.positions.size()) + " vertices, " + std::to_string(m.triangles.size()) +
                 " triangles), in the input's own coordinates",
             "m", meshFormatDescription(format), d.day, 0.f, 0.f);
  }
}

}  // namespace snow
