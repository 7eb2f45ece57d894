// End-to-end: the `snowbake` program as pipelines run it.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

using namespace std::string_literals;
namespace fs = std::filesystem;

namespace {

struct ProcessResult {
  int status;
  std::string err;
  std::string out;
};

fs::path workDir() {
  const fs::path p = fs::temp_directory_path() / ("snowbake_cli_" +
                                                  std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

ProcessResult snowbake(const fs::path& dir, const std::string& args) {
  const std::string out = (dir / "stdout.txt").string(), err = (dir / "stderr.txt").string();
  const std::string cmd = "'"s + SNOWBAKE_BINARY + "' " + args + " >'" + out + "' 2>'" + err + "' </dev/null";
  const int raw = std::system(cmd.c_str());
  auto slurp = [](const std::string& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(err), slurp(out)};
}

std::map<std::string, std::string> filesIn(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    files[fs::relative(e.path(), dir).string()] = s.str();
  }
  return files;
}

// A small, quick version of the default bake.
const std::string kSmall = "--set terrain.size=96 --set terrain.cell_size_m=20 --set season.days=40 --set outputs.frames_days=[20] "
                           "--quiet ";

}  // namespace

TEST(Cli, SameSeedSameBytesAndThreadCountDoesNotMatter) {
  const fs::path dir = workDir();
  ASSERT_EQ(snowbake(dir, "bake preset:default --backend cpu --threads 1 --seed 5 --out " + (dir / "a").string() + " " + kSmall).status, 0);
  ASSERT_EQ(snowbake(dir, "bake preset:default --backend cpu --threads 2 --seed 5 --out " + (dir / "b").string() + " " + kSmall).status, 0);
  ASSERT_EQ(snowbake(dir, "bake preset:default --backend cpu --threads 2 --seed 6 --out " + (dir / "c").string() + " " + kSmall).status, 0);
  const auto a = filesIn(dir / "a"), b = filesIn(dir / "b"), c = filesIn(dir / "c");
  EXPECT_GE(a.size(), 11u);  // 5 layers final + 5 at day 20 + manifest
  EXPECT_TRUE(a.count("manifest.json"));
  EXPECT_TRUE(a.count("frames/powder.0020.exr"));
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    EXPECT_TRUE(bytes == b.at(name)) << name << " differs between 1 and 2 threads";
  }
  EXPECT_FALSE(a.at("powder.exr") == c.at("powder.exr")) << "another seed should give another season";
  if (!HasFailure()) fs::remove_all(dir);  // kept for inspection when it fails
}

TEST(Cli, ManifestListsEveryFileWritten) {
  const fs::path dir = workDir();
  const ProcessResult r = snowbake(dir, "bake preset:default --backend cpu --out " + (dir / "o").string() + " " + kSmall);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto files = filesIn(dir / "o");
  const std::string manifest = files.at("manifest.json");
  for (const auto& [name, bytes] : files)
    if (name != "manifest.json") {
      EXPECT_NE(manifest.find("\"" + name + "\""), std::string::npos) << name;
    }
  EXPECT_NE(manifest.find("\"unit\": \"m\""), std::string::npos);
  EXPECT_NE(r.err.find("season:"), std::string::npos) << "stage timings are reported";
  fs::remove_all(dir);
}

TEST(Cli, BadSceneExitsTwoWithOneLineNamingFileAndKey) {
  const fs::path dir = workDir();
  const std::string scene = (dir / "bad.toml").string();
  std::ofstream(scene) << "[terrain]\nbuiltin = \"ridged\"\n[season]\ndays = -4\n";
  fs::create_directories(dir / "out");
  std::ofstream(dir / "out" / "keep.txt") << "earlier bake";
  const ProcessResult r = snowbake(dir, "bake " + scene + " --out " + (dir / "out").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find(scene + ":4"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("season.days"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // Nothing was written or touched.
  const auto files = filesIn(dir / "out");
  EXPECT_EQ(files.size(), 1u);
  EXPECT_EQ(files.at("keep.txt"), "earlier bake");
  fs::remove_all(dir);
}

TEST(Cli, UsageErrorsExitTwoAndHelpExitsZero) {
  const fs::path dir = workDir();
  EXPECT_EQ(snowbake(dir, "bake").status, 2);
  EXPECT_EQ(snowbake(dir, "frobnicate").status, 2);
  EXPECT_EQ(snowbake(dir, "bake preset:default --backend gpu").status, 2);
  const ProcessResult help = snowbake(dir, "bake --help");
  EXPECT_EQ(help.status, 0);
  EXPECT_NE(help.out.find("--terrain"), std::string::npos);
  EXPECT_EQ(snowbake(dir, "--help").status, 0);
  EXPECT_EQ(snowbake(dir, "demo --help").status, 0);
  EXPECT_EQ(snowbake(dir, "info --help").status, 0);
  const ProcessResult missing = snowbake(dir, "bake preset:default --terrain /nonexistent/dem.tif");
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.err.find("/nonexistent/dem.tif"), std::string::npos) << missing.err;
  fs::remove_all(dir);
}

TEST(Cli, InfoReportsTheTerrainAsJson) {
  const fs::path dir = workDir();
  const ProcessResult r = snowbake(dir, "info builtin:ridged --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\"width\": 512"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"cell_size_x_m\": 10.0"), std::string::npos) << r.out;
  const ProcessResult bad = snowbake(dir, "info /nonexistent/x.asc");
  EXPECT_EQ(bad.status, 2);
  fs::remove_all(dir);
}

TEST(Cli, AutoBackendSaysWhichItPicked) {
  const fs::path dir = workDir();
  const ProcessResult r = snowbake(dir, "bake preset:default --backend auto --out " + (dir / "o").string() + " " + kSmall);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("backend: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(auto: "), std::string::npos) << r.err;
  fs::remove_all(dir);
}
