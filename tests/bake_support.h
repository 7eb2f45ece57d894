// Bakes a scene written from text into a fresh temporary folder, on the CPU without cache:
// what the physics tests on real DEMs need. (Not in test_support.h: the GPU test binary
// includes that one and links no pipeline.)
#pragma once
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "bake/bake.h"

namespace snow::test {

struct Bake {
  std::filesystem::path dir;  // holds scene.toml and out/
  BakeResult result;
  std::filesystem::path out() const { return dir / "out"; }
};

inline Bake bakeSceneText(const std::string& name, const std::string& sceneText) {
  Bake b;
  // One folder per test, name and process: ctest runs tests in parallel processes, and two test
  // runs on one machine must not share folders.
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  b.dir = std::filesystem::temp_directory_path() /
          ("snowbake_" + name + "_" + (info ? std::string(info->test_suite_name()) + "." + info->name() : std::string("main")) + "_" +
           std::to_string(::getpid()));
  std::filesystem::remove_all(b.dir);
  std::filesystem::create_directories(b.dir);
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
