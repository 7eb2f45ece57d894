// scene.resolved.toml: the scene a bake ran, written beside its outputs; baking it gives the
// same bytes (docs/outputs.md, "The resolved scene").
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include "cli_support.h"
#include "temp_dir.h"

using namespace std::string_literals;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using snow::test::slurp;

fs::path resolvedSceneWorkDir() {
  return snow::test::uniqueTestDir("resolved");
}

int bakeLogged(const std::string& args, const fs::path& log) {
  const std::string cmd = "'"s + SNOWBAKE_BINARY + "' bake " + args + " --quiet --no-cache --backend cpu >'" + log.string() + "' 2>&1 </dev/null";
  const int raw = std::system(cmd.c_str());
  return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
}

std::map<std::string, std::string> resolvedFilesIn(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files[fs::relative(e.path(), dir).string()] = slurp(e.path());
  return files;
}

// The manifest without what legitimately names the run: the scene's source and hash (the resolved
// scene is another document for the same bake), the command line, and the scene-file line in an
// event mask's role ("events (avalanche, line 68).mask").
json comparableManifest(const std::string& text) {
  json m = json::parse(text);
  m["scene"].erase("source");
  m["scene"].erase("hash_fnv1a64");
  m.erase("command_line");
  m.erase("memory");  // the measured peak differs between two runs
  if (m.contains("art_direction"))
    for (json& r : m["art_direction"]["rasters"]) {
      std::string role = r["role"];
      if (const size_t at = role.find(", line "); at != std::string::npos) role.erase(at, role.find(')', at) - at);
      r["role"] = role;
    }
  return m;
}

// The resolved scene without its first line, a comment naming the file it was resolved from.
std::string withoutHeader(const std::string& toml) { return toml.substr(toml.find('\n') + 1); }

// Bakes SCENE with ARGS, then the scene.resolved.toml it wrote (from another folder, with no
// overrides), and compares every file.
void expectResolvedSceneReproducesTheBake(const std::string& scene, const std::string& args) {
  const fs::path dir = resolvedSceneWorkDir();
  ASSERT_EQ(bakeLogged(scene + " " + args + " --out '" + (dir / "a").string() + "'", dir / "a.log"), 0) << slurp(dir / "a.log");
  const fs::path resolved = dir / "a" / "scene.resolved.toml";
  ASSERT_TRUE(fs::exists(resolved));
  fs::copy_file(resolved, dir / "copy.toml");
  ASSERT_EQ(bakeLogged("'" + (dir / "copy.toml").string() + "' --out '" + (dir / "b").string() + "'", dir / "b.log"), 0) << slurp(dir / "b.log");
  const auto a = resolvedFilesIn(dir / "a"), b = resolvedFilesIn(dir / "b");
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    if (name == "manifest.json")
      EXPECT_TRUE(comparableManifest(bytes) == comparableManifest(b.at(name)))
          << json::diff(comparableManifest(bytes), comparableManifest(b.at(name))).dump().substr(0, 3000);
    else if (name == "scene.resolved.toml")
      EXPECT_EQ(withoutHeader(bytes), withoutHeader(b.at(name))) << "resolving is idempotent";
    else
      EXPECT_TRUE(bytes == b.at(name)) << name << " differs";
  }
  fs::remove_all(dir);
}

}  // namespace

TEST(ResolvedScene, BakingItGivesTheSameBytesWithOverridesAndDefaults) {
  expectResolvedSceneReproducesTheBake("preset:default", "--seed 7 --set terrain.size=96 --set terrain.cell_size_m=20 --set season.days=40 "
                                                         "--set outputs.frames_days=[20] --set outputs.encodings=[\\\"png16\\\"]");
}

TEST(ResolvedScene, BakingItGivesTheSameBytesWithMasksGivenByRelativePaths) {
  expectResolvedSceneReproducesTheBake("'"s + SNOWBAKE_SOURCE_DIR + "/presets/art_direction.toml'",
                                       "--set terrain.size=128");
}

TEST(ResolvedScene, HasEveryKeyTheSceneLeftOutAtItsDefaultAndTheCommandLineInTheManifest) {
  const fs::path dir = resolvedSceneWorkDir();
  ASSERT_EQ(bakeLogged("preset:default --set terrain.size=64 --set season.days=5 --set outputs.frames_days=[] --out '" + (dir / "a").string() + "'", dir / "a.log"), 0)
      << slurp(dir / "a.log");
  const std::string resolved = slurp(dir / "a" / "scene.resolved.toml");
  EXPECT_NE(resolved.find("days = 5"), std::string::npos) << "the --set override";
  EXPECT_NE(resolved.find("threads = 0"), std::string::npos) << "run.threads, left at its default";
  EXPECT_NE(resolved.find("[parameters]"), std::string::npos) << "every model parameter";
  // The second line lists the tables left out: a sub-table the scene did not write once, by its
  // name, and none of its keys written at defaults.
  const std::string leftOut = resolved.substr(resolved.find('\n') + 1, resolved.find('\n', resolved.find('\n') + 1) - resolved.find('\n') - 1);
  EXPECT_NE(leftOut.find(" [outputs.tiles]"), std::string::npos) << leftOut;
  EXPECT_EQ(leftOut.find("[outputs.tiles]"), leftOut.rfind("[outputs.tiles]")) << leftOut;
  EXPECT_EQ(resolved.find("size_px"), std::string::npos) << "a key of the absent [outputs.tiles]";
  const json m = json::parse(slurp(dir / "a" / "manifest.json"));
  ASSERT_TRUE(m["command_line"].is_array());
  EXPECT_EQ(m["command_line"][1], "bake");
  EXPECT_EQ(m["command_line"][2], "preset:default");
  EXPECT_EQ(m["scene"]["resolved"], "scene.resolved.toml");
  bool listed = false;
  for (const json& f : m["files"]) listed |= f["path"] == "scene.resolved.toml";
  EXPECT_TRUE(listed);
  fs::remove_all(dir);
}
