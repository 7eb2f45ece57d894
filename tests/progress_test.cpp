// `snowbake bake --progress json`: the lines a render farm parses (docs/command-line.md).
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

struct JsonBake {
  int status;
  std::vector<json> lines;  // every line of stderr, parsed (a line that is not JSON fails the test)
  fs::path dir;
};

JsonBake bakeWithJsonProgress(const std::string& args) {
  JsonBake b;
  b.dir = snow::test::uniqueTestDir("progress");
  const std::string cmd = "'"s + SNOWBAKE_BINARY + "' bake " + args + " --out '" + (b.dir / "o").string() + "' --log-file '" +
                          (b.dir / "log.txt").string() + "' --progress json 2>'" + (b.dir / "err.txt").string() + "' </dev/null";
  const int raw = std::system(cmd.c_str());
  b.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  std::istringstream err(slurp(b.dir / "err.txt"));
  for (std::string line; std::getline(err, line);) {
    EXPECT_TRUE(json::accept(line)) << "not JSON: " << line;
    if (json::accept(line)) b.lines.push_back(json::parse(line));
  }
  return b;
}

}  // namespace

TEST(Progress, JsonLinesHaveEveryStageFractionsNeverDecreaseFileAndAvalancheEventsLiveAndTheFinalFileCountIsTheManifests) {
  const JsonBake b = bakeWithJsonProgress("preset:default --backend cpu --no-cache --set terrain.size=96 --set terrain.cell_size_m=20 "
                                          "--set season.days=40 --set outputs.frames_days=[20]");
  ASSERT_EQ(b.status, 0) << slurp(b.dir / "log.txt");
  ASSERT_FALSE(b.lines.empty());
  std::map<std::string, double> last;
  std::map<std::string, int> events;
  for (const json& l : b.lines) {
    if (l.value("type", "") == "progress") {
      const std::string stage = l["stage"];
      const double f = l["fraction"];
      EXPECT_GE(f, 0.0);
      EXPECT_LE(f, 1.0);
      if (last.count(stage)) {
        EXPECT_GE(f, last[stage]) << stage;
      }
      last[stage] = f;
      EXPECT_GE(l["elapsed_s"].get<double>(), 0.0);
    } else if (l.value("type", "") == "event") {
      ++events[l["stage"].get<std::string>() + "/" + l["event"].get<std::string>()];
    }
  }
  for (const char* stage : {"scene", "terrain", "precompute", "season", "outputs", "manifest"}) {
    ASSERT_TRUE(last.count(stage)) << stage << " never reported";
    EXPECT_EQ(last[stage], 1.0) << stage << " did not end at 1";
  }
  EXPECT_EQ(events["precompute/exposure"], 1);
  EXPECT_EQ(events["season/frame"], 1);
  const json& done = b.lines.back();
  ASSERT_EQ(done["type"], "done");
  EXPECT_EQ(done["outcome"], "ok");
  EXPECT_EQ(done["exit_status"], 0);
  const json manifest = json::parse(slurp(b.dir / "o" / "manifest.json"));
  EXPECT_EQ(done["files"].get<size_t>(), manifest["files"].size());
  EXPECT_EQ(events["season/file"] + events["outputs/file"], static_cast<int>(manifest["files"].size()) + 1) << "every file and the manifest";
  // Live: avalanches are reported by the season as they stop, before its last day's fraction 1;
  // the frame's files by the frame writer beside the season (its own thread, so only before the
  // outputs stage begins: the season's last day may come before the writer's files).
  const size_t none = b.lines.size();
  size_t firstFrameFile = none, firstAvalanche = none, seasonEnd = none, outputsStart = none;
  for (size_t i = 0; i < b.lines.size(); ++i) {
    const json& l = b.lines[i];
    // value(), not operator[]: a const json's operator[] of a missing key ("done" has no stage) is undefined.
    const std::string type = l.value("type", ""), stage = l.value("stage", ""), name = l.value("event", "");
    const bool season = stage == "season", event = type == "event";
    if (event && season && name == "file" && firstFrameFile == none) firstFrameFile = i;
    if (event && season && name == "avalanche" && firstAvalanche == none) firstAvalanche = i;
    if (type == "progress" && season && l.value("fraction", -1.0) == 1.0 && seasonEnd == none) seasonEnd = i;
    if (type == "progress" && stage == "outputs" && outputsStart == none) outputsStart = i;
  }
  EXPECT_GT(events["season/file"], 5);
  EXPECT_LT(firstFrameFile, outputsStart) << "a frame's file event came after the season";
  ASSERT_GT(events["season/avalanche"], 0) << "this season's storms release avalanches";
  EXPECT_LT(firstAvalanche, seasonEnd) << "avalanche events came after the season ended";
  EXPECT_LT(done["mass_balance_relative_error"].get<double>(), 1e-5);
  EXPECT_NE(slurp(b.dir / "log.txt").find("season:"), std::string::npos) << "the human log goes to --log-file";
  fs::remove_all(b.dir);
}

TEST(Progress, BadSceneEndsWithAnInputErrorLineAndExitTwo) {
  const JsonBake b = bakeWithJsonProgress("preset:default --set season.dayz=3");
  EXPECT_EQ(b.status, 2);
  ASSERT_FALSE(b.lines.empty());
  const json& done = b.lines.back();
  EXPECT_EQ(done["outcome"], "input_error");
  EXPECT_EQ(done["exit_status"], 2);
  EXPECT_NE(done["message"].get<std::string>().find("season.dayz"), std::string::npos) << done.dump();
  EXPECT_FALSE(fs::exists(b.dir / "o")) << "nothing written";
  fs::remove_all(b.dir);
}
