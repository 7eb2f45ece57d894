// snowbake_fuzz: a seeded mutation fuzzer of the scene parser and each terrain reader
// (docs/testing.md). Each target starts from small valid inputs made here, mutates them (bit
// flips, interesting bytes, cut, repeated and spliced ranges, tokens from the scene schema and
// the formats' headers), and hands each one to the reader in this process, for a given time:
//   snowbake_fuzz TARGET SECONDS [--seed N] [--work DIR] [--corpus DIR]...
//   TARGET: scene, dem (ESRI ASCII grids through GDAL), heightmap (PGM through OpenImageIO),
//           raw (.r16 with its size in the scene), mesh (OBJ through assimp, rasterised), all
// A reader may refuse an input (InputError, or another exception with a message); it may not
// crash, hang (an input running past 5 s stops the run with exit 3, the input kept as
// DIR/hang.*) or allocate past the budget (the sanitizer build's max_allocation_size_mb and
// hard_rss_limit_mb, tools/run-tests.sh). The input being read is always DIR/current.*, so a
// crash leaves it behind. An input whose outcome (the refusal's text without its numbers) is new
// joins the corpus: the run prints inputs, seconds and corpus size per target.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/errors.h"
#include "inputs/terrain_loader.h"
#include "scene/scene.h"
#include "scene/scene_schema.h"

namespace fs = std::filesystem;
using Bytes = std::string;
using Clock = std::chrono::steady_clock;

namespace {

constexpr double kHangSeconds = 5.0;

struct Rng {
  uint64_t s;
  uint64_t next() {  // splitmix64
    uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  size_t below(size_t n) { return n ? static_cast<size_t>(next() % n) : 0; }
};

struct Target {
  std::string name, extension;
  std::vector<Bytes> seeds;
  std::vector<std::string> tokens;
  std::function<void(const std::string& path)> read;  // throws to refuse
};

std::string esriSeed(int w, int h, const std::string& nodata) {
  std::ostringstream o;
  o << "ncols " << w << "\nnrows " << h << "\nxllcorner 1000.0\nyllcorner 2000.0\ncellsize 5.0\n";
  if (!nodata.empty()) o << "NODATA_value " << nodata << "\n";
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) o << (x == 2 && y == 1 && !nodata.empty() ? nodata : std::to_string(1500 + 7 * x + 3 * y)) << " ";
    o << "\n";
  }
  return o.str();
}

Bytes pgmSeed(int w, int h) {
  Bytes b = "P5\n" + std::to_string(w) + " " + std::to_string(h) + "\n65535\n";
  for (int i = 0; i < w * h; ++i) b += static_cast<char>((i * 37) >> 8), b += static_cast<char>(i * 37);
  return b;
}

Bytes rawSeed(int w, int h) {  // two little-endian uint16 (width, height), then the samples
  Bytes b;
  for (int v : {w, h}) b += static_cast<char>(v & 0xff), b += static_cast<char>(v >> 8);
  for (int i = 0; i < w * h; ++i) b += static_cast<char>(i * 11), b += static_cast<char>(i);
  return b;
}

const char* kObjSeed =
    "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nv 2 2 3\nvn 0 0 1\n"
    "f 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 1 3 2\n";

const char* kSceneSeeds[] = {
    "name = \"fuzz\"\n[terrain]\nbuiltin = \"ridged\"\nsize = 64\n[season]\nstart_date = 2025-12-01\ndays = 30\n"
    "[[weather.keyframe]]\nday = 0\nsea_level_temperature_c = 4.0\nwind_speed_mps = 6\n[outputs]\nframes_days = [10, 20]\n",
    "mode = \"occlusion\"\n[terrain]\nbuiltin = \"ridged\"\n[occlusion]\ns_max_m = 1.0\n[outputs]\nlayers = [\"depth\", \"surface\"]\n"
    "encodings = [\"png16\"]\ndisplacement_size = [128, 128]\nvdb = true\n",
    "[terrain]\nfile = \"dem.asc\"\ncrop_m = [0, 0, 100, 100]\nresample_cell_size_m = 2.0\n[[events]]\ntype = \"avalanche\"\n"
    "day = 3\nposition_m = [10, 10]\n[[events]]\ntype = \"skier\"\nday = 2\ncount = 3\nposition_m = [5, 5]\n"
    "[[edits]]\nday = 4\nop = \"add\"\nlayer = \"powder\"\ndepth_m = 0.2\n[parameters]\nrain_snow_limit_m = 1200\n",
    "mode = \"mesh\"\n[terrain]\nfile = \"m.obj\"\nup_axis = \"y\"\n[mesh_snow]\ndepth_m = 0.3\nsite_spacing_m = 0.05\n"
    "[outputs]\nmeshes = [\"ply\"]\n[run]\nseed = 3\nthreads = 1\nmax_memory_gb = 2\n",
};

std::vector<std::string> schemaTokens() {
  std::vector<std::string> t{"=", "[", "]", "[[", "]]", "\"", ".", ",", "\n", "#", "1e308", "-1", "0", "nan", "inf", "-inf",
                             "2025-02-31", "true", "{", "}", "'''", "\\u0000", "65536", "4294967296"};
  for (const auto& r : snow::sceneRules()) {
    t.push_back(r.path);
    const size_t dot = r.path.rfind('.');
    if (dot != std::string::npos) t.push_back(r.path.substr(dot + 1));
    for (const auto& c : r.choices) t.push_back("\"" + c + "\"");
  }
  return t;
}

snow::TerrainSource source(const std::string& path, snow::TerrainFormat format) {
  snow::TerrainSource s;
  s.file = path;
  s.format = format;
  return s;
}

std::vector<Target> targets() {
  std::vector<Target> t;
  t.push_back({"scene", ".toml", {kSceneSeeds[0], kSceneSeeds[1], kSceneSeeds[2], kSceneSeeds[3]}, schemaTokens(),
               [](const std::string& path) { snow::loadSceneFile(path); }});
  t.push_back({"dem", ".asc", {esriSeed(5, 4, "-9999"), esriSeed(3, 3, ""), esriSeed(6, 5, "nan")},
               {"ncols", "nrows", "xllcorner", "xllcenter", "cellsize", "dx", "NODATA_value", "-9999", "nan", "1e38", "-", "e",
                "100000", "0", "-5", "\n", " "},
               [](const std::string& path) { snow::loadTerrain(source(path, snow::TerrainFormat::Dem)); }});
  t.push_back({"heightmap", ".pgm", {pgmSeed(4, 4), pgmSeed(7, 3)}, {"P5", "P2", "65535", "255", "0", "99999", "\n", " "},
               [](const std::string& path) {
                 snow::TerrainSource s = source(path, snow::TerrainFormat::Heightmap);
                 s.cellSizeM = 2.0;
                 s.heightRangeM = std::array<double, 2>{0.0, 1000.0};
                 snow::loadTerrain(s);
               }});
  t.push_back({"raw", ".r16", {rawSeed(4, 4), rawSeed(9, 2)}, {},
               [](const std::string& path) {
                 std::ifstream in(path, std::ios::binary);
                 unsigned char head[4] = {0, 0, 0, 0};
                 in.read(reinterpret_cast<char*>(head), 4);
                 const Bytes rest((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
                 const std::string body = path + ".body.r16";
                 std::ofstream(body, std::ios::binary) << rest;
                 snow::TerrainSource s = source(body, snow::TerrainFormat::Raw);
                 s.rawWidth = head[0] | head[1] << 8, s.rawHeight = head[2] | head[3] << 8;
                 s.cellSizeM = 1.0;
                 s.heightRangeM = std::array<double, 2>{0.0, 500.0};
                 snow::loadTerrain(s);
               }});
  t.push_back({"mesh", ".obj", {kObjSeed}, {"v ", "vn ", "vt ", "f ", "/", "1e30", "-1e30", "nan", "0", "-1", "99", "\n", "o x\n", "g\n"},
               [](const std::string& path) {
                 snow::TerrainSource s = source(path, snow::TerrainFormat::Mesh);
                 s.cellSizeM = 0.5;
                 snow::loadTerrain(s);
               }});
  return t;
}

Bytes mutate(Bytes b, const Target& t, const std::vector<Bytes>& corpus, Rng& r) {
  const int rounds = 1 + static_cast<int>(r.below(4));
  for (int k = 0; k < rounds; ++k) {
    const size_t at = r.below(b.size() + 1);
    switch (r.below(7)) {
      case 0:
        if (!b.empty()) b[r.below(b.size())] ^= static_cast<char>(1u << r.below(8));
        break;
      case 1: {
        static const char interesting[] = {0, '\xff', '-', '9', 'e', '.', ' ', '\n', '"', '['};
        if (!b.empty()) b[r.below(b.size())] = interesting[r.below(sizeof interesting)];
        break;
      }
      case 2:
        b.erase(at, r.below(16) + 1);
        break;
      case 3: {  // repeat a range
        const size_t len = std::min<size_t>(r.below(64) + 1, b.size() - std::min(at, b.size()));
        b.insert(at, b.substr(at, len));
        break;
      }
      case 4:
        if (!t.tokens.empty()) b.insert(at, t.tokens[r.below(t.tokens.size())]);
        break;
      case 5: {  // splice another corpus entry's range
        const Bytes& o = corpus[r.below(corpus.size())];
        const size_t from = r.below(o.size() + 1);
        b.insert(at, o.substr(from, r.below(64) + 1));
        break;
      }
      default: {  // a number replaced by an extreme one
        static const char* numbers[] = {"0", "-1", "1e308", "3e38", "65536", "2147483648", "-9999", "1e-300", "nan"};
        const size_t d = b.find_first_of("0123456789", at);
        if (d != Bytes::npos) {
          size_t e = d;
          while (e < b.size() && (isdigit(static_cast<unsigned char>(b[e])) || b[e] == '.')) ++e;
          b.replace(d, e - d, numbers[r.below(sizeof numbers / sizeof *numbers)]);
        }
      }
    }
  }
  if (b.size() > 1 << 20) b.resize(1 << 20);
  return b;
}

// The refusal's text without its numbers and paths: an outcome class.
std::string outcome(const std::string& what, const std::string& path) {
  std::string s = what;
  for (size_t p; (p = s.find(path)) != std::string::npos;) s.erase(p, path.size());
  std::string o;
  for (char c : s)
    if (!isdigit(static_cast<unsigned char>(c))) o += c;
  return o.substr(0, 80);
}

std::atomic<int64_t> startedNs{0};  // when the current input started (0: none running)

int64_t nowNs() { return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count(); }

// Stops the run when an input takes longer than kHangSeconds, keeping it as hang.EXT.
void watchdog(const fs::path& work) {
  for (;;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const int64_t s = startedNs.load();
    if (!s || (nowNs() - s) * 1e-9 <= kHangSeconds) continue;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(work, ec))
      if (e.path().stem() == "current") {
        const fs::path kept = work / ("hang" + e.path().extension().string());
        fs::copy_file(e.path(), kept, fs::copy_options::overwrite_existing, ec);
        std::cerr << "snowbake_fuzz: an input ran past " << kHangSeconds << " s: kept as " << kept << "\n";
      }
    std::_Exit(3);
  }
}

void loadCorpus(const fs::path& dir, const Target& t, std::vector<Bytes>& corpus) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().extension() == t.extension && e.path().stem().string().rfind(t.name, 0) == 0) {
      std::ifstream in(e.path(), std::ios::binary);
      corpus.emplace_back((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    }
}

void fuzzTarget(const Target& t, double seconds, uint64_t seed, const fs::path& work, const std::vector<fs::path>& corpusDirs) {
  std::vector<Bytes> corpus = t.seeds;
  for (const auto& d : corpusDirs) loadCorpus(d, t, corpus);
  const size_t initial = corpus.size();
  std::set<std::string> outcomes;
  Rng r{seed};
  const fs::path current = work / ("current" + t.extension);
  const auto t0 = Clock::now();
  size_t runs = 0, refused = 0;
  double slowest = 0;
  // Every corpus entry as it is first, then mutations until the time is up.
  while (runs < initial || std::chrono::duration<double>(Clock::now() - t0).count() < seconds) {
    const Bytes input = runs < initial ? corpus[runs] : mutate(corpus[r.below(corpus.size())], t, corpus, r);
    std::ofstream(current, std::ios::binary | std::ios::trunc) << input;
    std::string result = "accepted";
    const int64_t start = nowNs();
    startedNs = start;
    try {
      t.read(current.string());
    } catch (const std::exception& e) {
      result = outcome(e.what(), current.string());
      ++refused;
    }
    startedNs = 0;
    slowest = std::max(slowest, (nowNs() - start) * 1e-9);
    ++runs;
    if (outcomes.insert(result).second && runs > initial) corpus.push_back(input);
  }
  std::cout << t.name << ": " << runs << " inputs in " << std::chrono::duration<double>(Clock::now() - t0).count() << " s ("
            << refused << " refused, slowest " << slowest << " s), corpus " << initial << " -> " << corpus.size() << ", "
            << outcomes.size() << " distinct outcomes" << std::endl;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: snowbake_fuzz scene|dem|heightmap|raw|mesh|all SECONDS [--seed N] [--work DIR] [--corpus DIR]...\n";
    return 2;
  }
  const std::string which = argv[1];
  const double seconds = std::atof(argv[2]);
  uint64_t seed = 1;
  fs::path work = fs::temp_directory_path() / "snowbake-fuzz";
  std::vector<fs::path> corpusDirs;
  for (int i = 3; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--seed") seed = std::strtoull(argv[i + 1], nullptr, 10);
    else if (a == "--work") work = argv[i + 1];
    else if (a == "--corpus") corpusDirs.emplace_back(argv[i + 1]);
    else return std::cerr << "snowbake_fuzz: unknown option " << a << "\n", 2;
  }
  fs::create_directories(work);
  std::thread(watchdog, work).detach();
  bool any = false;
  for (const Target& t : targets())
    if (which == "all" || which == t.name) {
      fuzzTarget(t, seconds, seed, work, corpusDirs);
      any = true;
    }
  if (!any) return std::cerr << "snowbake_fuzz: unknown target " << which << "\n", 2;
  return 0;
}
