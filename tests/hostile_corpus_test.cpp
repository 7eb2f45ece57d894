// The hostile corpus: terrain files and scenes that must be refused by the real `snowbake`
// program before any work: exit 2, one line naming the file (and, for scenes, the line and the
// key), within 10 s and 2 GB of address space (prlimit --as), nothing in the output folder.
//
// One row of kCorpus per case. To add one: a name (letters, digits, '_'), what it writes into
// the case's folder (a text file, a GeoTIFF, an image), the command's arguments (DIR stands for
// the case's folder) and the fragments the error must hold (DIR again for the folder). Scene
// rows use sceneRow(), which finds the line of the offending key itself.
#include <gtest/gtest.h>
#include <OpenImageIO/imageio.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "geotiff_support.h"
#include "temp_dir.h"

namespace fs = std::filesystem;

namespace {

struct HostileCase {
  std::string name;
  std::function<void(const fs::path& dir)> write;  // the corpus file(s)
  std::string args;                                  // after `snowbake`; DIR is the case's folder
  std::vector<std::string> expected;                 // fragments of the error; DIR as above
};

void PrintTo(const HostileCase& c, std::ostream* os) { *os << c.name << ": snowbake " << c.args; }

std::string replaceDir(std::string s, const fs::path& dir) {
  for (size_t at; (at = s.find("DIR")) != std::string::npos;) s.replace(at, 3, dir.string());
  return s;
}

void writeText(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// An 8 x 8 ESRI ASCII grid: `header` lines, then heights 1000 + x + y with `cell` (if given) at
// column 3 of row 3.
// `fraction` makes it a float grid.
std::string ascGrid(const std::string& header, const std::string& cell = "", int rows = 8, const std::string& fraction = "") {
  std::ostringstream o;
  o << header;
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < 8; ++x) o << (x ? " " : "") << (x == 3 && y == 3 && !cell.empty() ? cell : std::to_string(1000 + x + y) + fraction);
    o << "\n";
  }
  return o.str();
}
const std::string kHeader = "ncols 8\nnrows 8\nxllcorner 0\nyllcorner 0\ncellsize 5\nNODATA_value -9999\n";
std::string headerWith(const std::string& key, const std::string& value) {
  std::string h = kHeader;
  const size_t at = h.find(key + " ");
  const size_t end = h.find('\n', at);
  return h.replace(at, end - at, key + " " + value);
}

// A terrain row: `file` (written by `write`) read by `snowbake info`, and baked with --terrain on
// the default preset; both must refuse it.
HostileCase ascRow(const std::string& name, const std::string& text, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> expected{"DIR/" + name + ".asc"};
  expected.insert(expected.end(), extra.begin(), extra.end());
  return {name, [=](const fs::path& d) { writeText(d / (name + ".asc"), text); },
          "bake preset:default --terrain DIR/" + name + ".asc --out DIR/out --no-cache --quiet", expected};
}

// A GeoTIFF of 16 x 16 cells: `bands` bands of heights `value` + x, with a geotransform and a
// projected coordinate system unless `georeferenced` is false, a band scale and offset if given.
void writeGeoTiff(const fs::path& path, float value, int bands = 1, bool georeferenced = true, double scale = 1.0,
                  double offset = 0.0) {
  snow::test::GeoTiffSpec g;
  g.bands = bands, g.georeferenced = georeferenced, g.scale = scale, g.offset = offset;
  snow::test::writeGeoTiff(path.string(), g, [value](int x, int) { return value + static_cast<float>(x); });
}

HostileCase tiffRow(const std::string& name, std::function<void(const fs::path&)> write, const std::string& sceneExtra,
                    const std::vector<std::string>& extra) {
  std::vector<std::string> expected{"DIR/" + name + ".tif"};
  expected.insert(expected.end(), extra.begin(), extra.end());
  const std::string scene = "[terrain]\nfile = \"" + name + ".tif\"\n" + sceneExtra + "[season]\ndays = 5\n";
  return {name,
          [=](const fs::path& d) {
            write(d / (name + ".tif"));
            writeText(d / (name + ".toml"), scene);
          },
          "bake DIR/" + name + ".toml --out DIR/out --no-cache --quiet", expected};
}

// A 16 x 16 image of `channels` channels through OpenImageIO (float or 16-bit).
void writeImage(const fs::path& path, int channels, OIIO::TypeDesc type, float value) {
  std::vector<float> px(static_cast<size_t>(16) * 16 * channels, value);
  auto out = OIIO::ImageOutput::create(path.string());
  OIIO::ImageSpec spec(16, 16, channels, type);
  out->open(path.string(), spec);
  out->write_image(OIIO::TypeDesc::FLOAT, px.data());
  out->close();
}

HostileCase imageRow(const std::string& name, const std::string& file, std::function<void(const fs::path&)> write,
                     const std::string& terrainKeys, const std::vector<std::string>& extra) {
  std::vector<std::string> expected{"DIR/" + file};
  expected.insert(expected.end(), extra.begin(), extra.end());
  const std::string scene = "[terrain]\nfile = \"" + file + "\"\n" + terrainKeys + "[season]\ndays = 5\n";
  return {name,
          [=](const fs::path& d) {
            write(d / file);
            writeText(d / (name + ".toml"), scene);
          },
          "bake DIR/" + name + ".toml --out DIR/out --no-cache --quiet", expected};
}

// A scene row: the builtin terrain and 10 days, plus `text`; the error must name the scene file,
// the line of `needle` in it and `key`.
HostileCase sceneRow(const std::string& name, const std::string& text, const std::string& needle, const std::string& key) {
  const std::string scene = "name = \"hostile\"\n[terrain]\nbuiltin = \"ridged\"\nsize = 32\n[season]\ndays = 10\n" + text;
  const size_t at = scene.find(needle);
  const long line = at == std::string::npos ? -1 : 1 + std::count(scene.begin(), scene.begin() + static_cast<long>(at), '\n');
  return {name, [=](const fs::path& d) { writeText(d / (name + ".toml"), scene); },
          "bake DIR/" + name + ".toml --out DIR/out --no-cache --quiet",
          {"DIR/" + name + ".toml:" + std::to_string(line) + ": " + key}};
}

const std::string kAvalanche = "[[events]]\ntype = \"avalanche\"\nposition_m = [100, 100]\n";
const std::string kSkier = "[[events]]\ntype = \"skier\"\nposition_m = [100, 100]\n";

std::vector<HostileCase> corpus() {
  using OIIO::TypeDesc;
  std::vector<HostileCase> c;
  // ESRI ASCII grids: header values.
  c.push_back(ascRow("negative_cellsize", ascGrid(headerWith("cellsize", "-5")), {":5:", "cellsize"}));
  c.push_back(ascRow("zero_cellsize", ascGrid(headerWith("cellsize", "0")), {":5:", "cellsize"}));
  c.push_back(ascRow("nan_cellsize", ascGrid(headerWith("cellsize", "nan")), {":5:", "cellsize"}));
  c.push_back(ascRow("infinite_cellsize", ascGrid(headerWith("cellsize", "inf")), {":5:", "cellsize"}));
  c.push_back(ascRow("tiny_negative_cellsize", ascGrid(headerWith("cellsize", "-1e-300")), {":5:", "cellsize"}));
  c.push_back(ascRow("text_cellsize", ascGrid(headerWith("cellsize", "five")), {":5:", "cellsize"}));
  c.push_back(ascRow("negative_dx", ascGrid("ncols 8\nnrows 8\nxllcorner 0\nyllcorner 0\ndx -5\ndy 5\n"), {":5:", "dx"}));
  c.push_back(ascRow("zero_dy", ascGrid("ncols 8\nnrows 8\nxllcorner 0\nyllcorner 0\ndx 5\ndy 0\n"), {":6:", "dy"}));
  c.push_back(ascRow("fractional_ncols", ascGrid(headerWith("ncols", "8.5")), {":1:", "ncols"}));
  c.push_back(ascRow("negative_nrows", ascGrid(headerWith("nrows", "-8")), {":2:", "nrows"}));
  c.push_back(ascRow("nan_corner", ascGrid(headerWith("xllcorner", "nan")), {":3:", "xllcorner"}));
  c.push_back(ascRow("nan_nodata_value_text", ascGrid(headerWith("NODATA_value", "none")), {":6:"}));
  // ESRI ASCII grids: heights (an integer grid: GDAL alone reads its `nan` as 0).
  c.push_back(ascRow("nan_in_integer_grid", ascGrid(kHeader, "nan"), {":10:", "'nan'"}));
  c.push_back(ascRow("minus_nan_in_integer_grid", ascGrid(kHeader, "-nan"), {":10:", "'-nan'"}));
  c.push_back(ascRow("inf_in_integer_grid", ascGrid(kHeader, "inf"), {":10:", "'inf'"}));
  c.push_back(ascRow("minus_infinity", ascGrid(kHeader, "-infinity"), {":10:"}));
  c.push_back(ascRow("nan_in_float_grid", ascGrid(kHeader, "nan", 8, ".5"), {":10:", "'nan'"}));
  c.push_back(ascRow("trailing_letters", ascGrid(kHeader, "12abc"), {":10:", "'12abc'"}));
  c.push_back(ascRow("decimal_comma", ascGrid(kHeader, "1003,5"), {":10:", "'1003,5'"}));
  c.push_back(ascRow("hex_height", ascGrid(kHeader, "0x3e8"), {":10:", "'0x3e8'"}));
  c.push_back(ascRow("truncated_rows", ascGrid(kHeader, "", 5), {"has 40 heights"}));
  c.push_back(ascRow("extra_heights", ascGrid(kHeader, "", 9), {":15:", "more heights"}));
  // Heights outside the Earth's (terrain.height_limits_m).
  c.push_back(ascRow("height_1e38", ascGrid(kHeader, "1e38"), {"terrain.height_limits_m"}));
  c.push_back(ascRow("height_above_10000", ascGrid(kHeader, "10001"), {"terrain.height_limits_m"}));
  c.push_back(ascRow("height_below_minus_12000", ascGrid(kHeader, "-12001"), {"terrain.height_limits_m"}));
  c.push_back(ascRow("heights_in_millimetres", ascGrid(kHeader, "2500000"), {"terrain.height_limits_m"}));
  c.push_back(ascRow("height_float_max", ascGrid(kHeader, "3.4e38"), {"terrain.height_limits_m"}));
  // GeoTIFFs: the band's scale and offset applied, bands chosen, georeference required.
  c.push_back(tiffRow("scaled_out_of_range", [](const fs::path& p) { writeGeoTiff(p, 2000.f, 1, true, 10.0); }, "",
                      {"terrain.height_limits_m", "GDAL offset and scale"}));
  c.push_back(tiffRow("offset_out_of_range", [](const fs::path& p) { writeGeoTiff(p, 2000.f, 1, true, 1.0, -50000.0); }, "",
                      {"terrain.height_limits_m"}));
  c.push_back(tiffRow("geotiff_1e30", [](const fs::path& p) { writeGeoTiff(p, 1e30f); }, "", {"terrain.height_limits_m"}));
  c.push_back(tiffRow("three_bands", [](const fs::path& p) { writeGeoTiff(p, 2000.f, 3); }, "", {"3 bands", "terrain.band"}));
  c.push_back(tiffRow("band_beyond_the_file", [](const fs::path& p) { writeGeoTiff(p, 2000.f, 3); }, "band = 4\n", {"terrain.band = 4"}));
  c.push_back(tiffRow("no_georeference", [](const fs::path& p) { writeGeoTiff(p, 2000.f, 1, false); }, "",
                      {"no georeference", "terrain.cell_size_m"}));
  c.push_back(tiffRow("no_georeference_above_limits", [](const fs::path& p) { writeGeoTiff(p, 20000.f, 1, false); },
                      "cell_size_m = 2.0\n", {"terrain.height_limits_m"}));
  c.push_back(tiffRow("narrowed_limits", [](const fs::path& p) { writeGeoTiff(p, 2000.f); }, "height_limits_m = [0, 1000]\n",
                      {"terrain.height_limits_m = [0, 1000]"}));
  // Heightmap images and raw files.
  c.push_back(imageRow("rgb_heightmap", "rgb_heightmap.png", [](const fs::path& p) { writeImage(p, 3, TypeDesc::UINT16, 0.5f); },
                       "cell_size_m = 2.0\nheight_range_m = [0, 1000]\n", {"3 channels", "terrain.band"}));
  c.push_back(imageRow("heightmap_channel_beyond", "channel_beyond.png", [](const fs::path& p) { writeImage(p, 2, TypeDesc::UINT16, 0.5f); },
                       "cell_size_m = 2.0\nheight_range_m = [0, 1000]\nband = 3\n", {"terrain.band = 3"}));
  c.push_back(imageRow("float_heightmap_1e30", "huge.exr", [](const fs::path& p) { writeImage(p, 1, TypeDesc::FLOAT, 1e30f); },
                       "cell_size_m = 2.0\n", {"terrain.height_limits_m"}));
  c.push_back(imageRow("heightmap_scale_beyond", "scaled.png", [](const fs::path& p) { writeImage(p, 1, TypeDesc::UINT16, 0.5f); },
                       "cell_size_m = 2.0\nheight_scale_m = 100000\n", {"terrain.height_limits_m"}));
  c.push_back(imageRow("raw_r32_1e30", "huge.r32",
                       [](const fs::path& p) {
                         const std::vector<float> v(64, 1e30f);
                         std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(v.data()), v.size() * 4);
                       },
                       "cell_size_m = 2.0\nraw_width = 8\nraw_height = 8\n", {"terrain.height_limits_m"}));
  // Scenes: impossible dates, events after the season's end, frames sharing a file, repeated names.
  c.push_back(sceneRow("february_31", "start_date = \"2025-02-31\"\n", "start_date", "season.start_date"));
  c.push_back(sceneRow("april_31", "start_date = \"2025-04-31\"\n", "start_date", "season.start_date"));
  c.push_back(sceneRow("february_29_no_leap_year", "start_date = \"2100-02-29\"\n", "start_date", "season.start_date"));
  c.push_back(sceneRow("toml_date_february_30", "start_date = 2025-02-30\n", "start_date", "TOML syntax error"));
  c.push_back(sceneRow("avalanche_after_the_season", kAvalanche + "day = 11\n", "day = 11", "events.day"));
  c.push_back(sceneRow("skier_after_the_season", kSkier + "day = 10.5\n", "day = 10.5", "events.day"));
  c.push_back(sceneRow("snowfall_after_the_season", "[[events]]\ntype = \"snowfall\"\nduration_days = 1\nday = 12\n", "day = 12", "events.day"));
  c.push_back(sceneRow("repeated_frame_day", "[outputs]\nframes_days = [\n  5,\n  5,\n]\n", "  5,\n]", "outputs.frames_days"));
  c.push_back(sceneRow("frame_days_one_tag", "[outputs]\nframes_days = [\n  4.6,\n  5.4,\n]\n", "5.4", "outputs.frames_days"));
  c.push_back(sceneRow("half_days_rounding_together", "[outputs]\nframes_days = [\n  2.5,\n  3,\n]\n", "  3,", "outputs.frames_days"));
  c.push_back(sceneRow("repeated_layers", "[outputs]\nlayers = [\n  \"depth\",\n  \"depth\",\n]\n", "  \"depth\",\n]", "outputs.layers"));
  c.push_back(sceneRow("repeated_encodings", "[outputs]\nencodings = [\n  \"png16\",\n  \"png16\",\n]\n", "  \"png16\",\n]",
                       "outputs.encodings"));
  c.push_back(sceneRow("repeated_meshes", "[outputs]\nmeshes = [\n  \"obj\",\n  \"obj\",\n]\n", "  \"obj\",\n]", "outputs.meshes"));
  c.push_back(sceneRow("repeated_mesh_parts", "[outputs]\nmeshes = [\"obj\"]\nmesh_parts = [\n  \"body\",\n  \"body\",\n]\n",
                       "  \"body\",\n]", "outputs.mesh_parts"));
  return c;
}

struct CappedRun {
  int status = -1;
  std::string err;
  double seconds = 0;
};

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif

// The program under prlimit: 2 GiB of address space. Under AddressSanitizer, whose shadow memory
// reserves terabytes of address space at start, no cap on the address space can hold; there the
// cap is left out (said once) and ASan refuses instead any single allocation above 2 GiB (an
// abort, not exit 2), while the rest of each case is checked as everywhere.
CappedRun runCapped(const fs::path& dir, const std::string& args) {
  const std::string err = (dir / "stderr.txt").string();
  const char* asanOptions = std::getenv("ASAN_OPTIONS");
  const std::string cap = kSanitized ? "ASAN_OPTIONS='" + std::string(asanOptions ? asanOptions : "") + ":max_allocation_size_mb=2048' "
                                     : "prlimit --as=2147483648 -- ";
  if (kSanitized) {
    static const bool said = (std::cout << "[   NOTE   ] sanitizer build: no prlimit --as cap (ASan's shadow memory); ASan refuses "
                                           "any single allocation above 2 GiB instead\n", true);
    (void)said;
  }
  const std::string cmd = cap + "'" + std::string(SNOWBAKE_BINARY) + "' " + args + " >/dev/null 2>'" + err + "' </dev/null";
  const auto t0 = std::chrono::steady_clock::now();
  const int raw = std::system(cmd.c_str());
  CappedRun r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  std::ifstream in(err);
  std::stringstream s;
  s << in.rdbuf();
  r.err = s.str();
  return r;
}

class HostileCorpus : public ::testing::TestWithParam<HostileCase> {};

TEST_P(HostileCorpus, RefusedWithExit2AndOneLineNamingTheFileWithinTenSecondsAndTwoGigabytesWritingNothing) {
  const HostileCase& hc = GetParam();
  const fs::path dir = snow::test::uniqueTempDir("hostile_" + hc.name);
  hc.write(dir);
  const CappedRun r = runCapped(dir, replaceDir(hc.args, dir));
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_LT(r.seconds, 10.0);
  // The error is one line (the log's first line, the scene's name, may come before it).
  std::vector<std::string> errors;
  std::istringstream lines(r.err);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("snowbake: error: ", 0) == 0) errors.push_back(line);
  ASSERT_EQ(errors.size(), 1u) << r.err;
  for (const auto& fragment : hc.expected) EXPECT_NE(errors[0].find(replaceDir(fragment, dir)), std::string::npos) << fragment << "\n" << r.err;
  EXPECT_FALSE(fs::exists(dir / "out")) << "the output folder was created";
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Corpus, HostileCorpus, ::testing::ValuesIn(corpus()),
                         [](const ::testing::TestParamInfo<HostileCase>& info) { return info.param.name; });

TEST(HostileCorpus, HoldsAtLeastFortyCasesWithDistinctNames) {
  const auto c = corpus();
  EXPECT_GE(c.size(), 40u);
  std::set<std::string> names;
  for (const auto& hc : c) EXPECT_TRUE(names.insert(hc.name).second) << hc.name;
}

}  // namespace
