// The scene reference (snowbake help scene): docs/scene.md is its Markdown, every key and every
// model parameter is in it with a doc string, and the defaults it prints are what a scene that
// leaves the keys out gets.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "scene/scene_reference.h"
#include "scene/scene_schema.h"
#include "scene/layers.h"

namespace snow {
namespace {

std::map<std::string, SceneKeyDoc> docsByPath() {
  std::map<std::string, SceneKeyDoc> docs;
  for (const SceneKeyDoc& d : sceneKeyDocs()) docs[d.path] = d;
  return docs;
}

TEST(SceneReference, DocsSceneMdIsTheGeneratedMarkdown) {
  std::ifstream in(std::string(SNOWBAKE_SOURCE_DIR) + "/docs/scene.md", std::ios::binary);
  ASSERT_TRUE(in) << "docs/scene.md is missing; write it with: ./build/snowbake help scene --markdown > docs/scene.md";
  std::stringstream file;
  file << in.rdbuf();
  EXPECT_TRUE(file.str() == sceneReferenceMarkdown())
      << "docs/scene.md differs from the schema; regenerate it with: ./build/snowbake help scene --markdown > docs/scene.md";
}

TEST(SceneReference, HelpScenePrintsIt) {
  auto run = [](const std::string& args) {
    std::string out;
    const std::string command = std::string("'").append(SNOWBAKE_BINARY).append("' help scene").append(args);
    FILE* p = popen(command.c_str(), "r");
    char buffer[4096];
    for (size_t n; p && (n = fread(buffer, 1, sizeof buffer, p)) > 0;) out.append(buffer, n);
    EXPECT_EQ(p ? pclose(p) : -1, 0) << args;
    return out;
  };
  EXPECT_EQ(run(" --markdown"), sceneReferenceMarkdown());
  EXPECT_EQ(run(""), sceneReferenceText());
}

TEST(SceneReference, EveryKeyAndParameterIsDocumented) {
  const auto docs = docsByPath();
  const std::string markdown = sceneReferenceMarkdown(), text = sceneReferenceText();
  for (const Rule& r : sceneRules()) {
    ASSERT_TRUE(docs.count(r.path)) << r.path << " is not in the reference";
    EXPECT_FALSE(docs.at(r.path).doc.empty()) << r.path << " has no doc string";
    EXPECT_NE(markdown.find("| `" + r.path + "` |"), std::string::npos) << r.path;
    EXPECT_NE(text.find("  " + r.path + " ("), std::string::npos) << r.path;
  }
  for (const ParameterInfo& p : parameterTable()) {
    const std::string path = std::string("parameters.") + p.key;
    ASSERT_TRUE(docs.count(path)) << path << " is not in the reference";
    EXPECT_FALSE(std::string(p.description).empty()) << path;
    EXPECT_FALSE(std::string(p.unit).empty()) << path;
    EXPECT_NE(markdown.find(std::string("| `") + p.key + "` |"), std::string::npos) << p.key;
  }
  EXPECT_EQ(docs.size(), sceneRules().size() + parameterTable().size());
  for (const LayerInfo& l : layerTable()) {
    EXPECT_NE(markdown.find(std::string("| `") + l.name + "` |"), std::string::npos) << l.name;
    EXPECT_NE(text.find(std::string("  ") + l.name + " ("), std::string::npos) << l.name;
  }
}

// A key the scene leaves out holds the default the reference prints: every key bound into the
// Scene (those whose default is not described in words), every model parameter, and the keys of
// a keyframe, an edit and a skier event given with their required keys alone.
TEST(SceneReference, PrintedDefaultsAreWhatAnEmptySceneGets) {
  const auto docs = docsByPath();
  const Scene s = loadSceneText(
      "[terrain]\nbuiltin = \"ridged\"\n[[weather.keyframe]]\nday = 0\n[[events]]\ntype = \"skier\"\nday = 1\nposition_m = [10, 10]\n"
      "[[edits]]\nday = 1\nop = \"add\"\nlayer = \"stable\"\ndepth_m = 1\n",
      "empty.toml", ".");
  int checked = 0;
  for (const Rule& r : sceneRules()) {
    if (!r.defaultText.empty() || r.path == "terrain.builtin") continue;
    const std::string printed = docs.at(r.path).defaultValue;
    if (const auto* b = std::get_if<Bind<Scene>>(&r.bind)) {
      EXPECT_EQ(b->show(s), printed) << r.path;
      ++checked;
    } else if (const auto* k = std::get_if<Bind<WeatherKeyframe>>(&r.bind)) {
      EXPECT_EQ(k->show(s.weather.keyframes.at(0)), printed) << r.path;
      ++checked;
    } else if (const auto* e = std::get_if<Bind<EditSpec>>(&r.bind)) {
      if (r.path == "edits.depth_m") continue;  // given: every op but move needs it
      EXPECT_EQ(e->show(s.edits.at(0)), printed) << r.path;
      ++checked;
    }
  }
  EXPECT_EQ(sceneValueText(s, "season.days"), docs.at("season.days").defaultValue);
  EXPECT_EQ(docs.at("season.days").defaultValue, "120");
  EXPECT_EQ(docs.at("outputs.layers").defaultValue, "[\"compacted\", \"stable\", \"unstable\", \"powder\", \"depth\"]");
  EXPECT_EQ(docs.at("mode").defaultValue, "\"season\"");
  EXPECT_EQ(docs.at("weather.keyframe.wind_direction_deg").defaultValue, "270");
  EXPECT_EQ(std::to_string(s.userSkiers.at(0).count), docs.at("events.count").defaultValue);
  for (const ParameterInfo& p : parameterTable()) {
    std::ostringstream value;
    value.precision(15);
    value << s.params.*p.member;
    EXPECT_EQ(value.str(), docs.at(std::string("parameters.") + p.key).defaultValue) << p.key;
    ++checked;
  }
  EXPECT_GT(checked, 140);  // most keys, and every parameter
}

TEST(SceneReference, RangesAndChoicesAreTheValidatorsOwn) {
  const auto docs = docsByPath();
  EXPECT_EQ(docs.at("site.latitude_deg").range, "[-90, 90]");  // as the out-of-range error prints it
  EXPECT_EQ(docs.at("outputs.format").range, "exr, tiff");      // as the bad-choice error lists them
  EXPECT_EQ(docs.at("run.backend").range, "cpu, cuda, auto");
  EXPECT_EQ(docs.at("parameters.melt_rate_m_per_day_per_c").range, "[0, 1]");
}

}  // namespace
}  // namespace snow
