// Bakes a scene written from text into a fresh temporary folder, on the CPU without cache:
// what the physics tests on real DEMs need. (Not in test_support.h: the GPU test binary
// includes that one and links no pipeline.)
#pragma once
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "bake/bake.h"
#include "temp_dir.h"

namespace snow::test {

struct Bake {
  std::filesystem::path dir;  // holds scene.toml and out/
  BakeResult result;
  std::filesystem::path out() const { return dir / "out"; }
};

inline Bake bakeSceneText(const std::string& name, const std::string& sceneText) {
  Bake b;
  // A folder of its own (ctest runs tests in parallel processes, two test runs on one machine must
  // not share one), removed when the test program passes (temp_dir.h): bakes are tens of MB.
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  b.dir = uniqueTempDir(name + "_" + (info ? std::string(info->test_suite_name()) + "." + info->name() : std::string("main")));
  const std::string scene = (b.dir / "scene.toml").string();
  std::ofstream(scene) << sceneText;
  BakeOptions o;
  o.scene = scene;
  o.outDir = b.out().string();
  o.backend = "cpu";
  o.useCache = false;
  o.progress = false;
  std::ostringstream log;
  b.result = runBake(o, log);
  return b;
}

}  // namespace snow::test
