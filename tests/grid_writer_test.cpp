#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "core/atomic_file.h"
#include "bakers/grid_writer.h"

using namespace snow;
namespace fs = std::filesystem;

namespace {
fs::path tempDir() {
  fs::path p = fs::temp_directory_path() / ("snowbake_writer_" +
                                            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}
std::string bytesOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
Grid<float> ramp() {
  Grid<float> g(37, 23);
  for (int y = 0; y < 23; ++y)
    for (int x = 0; x < 37; ++x) g(x, y) = 0.001f * static_cast<float>(x * y) + (x == 3 ? 1234.5678f : 0.f);
  return g;
}
}  // namespace

TEST(GridWriter, FloatImagesReadBackExactly) {
  const fs::path dir = tempDir();
  const Grid<float> g = ramp();
  for (const char* format : {"exr", "tiff"}) {
    const WrittenImage img = writeFloatImage((dir / "layer").string(), format, g, "powder");
    EXPECT_EQ(readFloatImage(img.path).values(), g.values()) << format;
    EXPECT_FLOAT_EQ(img.minValue, 0.f);
    EXPECT_FLOAT_EQ(img.maxValue, 1234.5678f + 0.001f * 3 * 22);
  }
  fs::remove_all(dir);
}

// No time stamps in the files: a bake repeated a second later gives the same bytes.
TEST(GridWriter, SameGridSameBytesAcrossTime) {
  const fs::path dir = tempDir();
  for (const char* format : {"exr", "tiff"}) {
    const std::string a = writeFloatImage((dir / "a").string(), format, ramp(), "depth").path;
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    const std::string b = writeFloatImage((dir / "b").string(), format, ramp(), "depth").path;
    EXPECT_TRUE(bytesOf(a) == bytesOf(b)) << format;
  }
  fs::remove_all(dir);
}

TEST(AtomicFile, FailedWriteLeavesTheOldFileAndNoTemporary) {
  const fs::path dir = tempDir();
  const std::string path = (dir / "manifest.json").string();
  writeTextAtomically(path, "old");
  EXPECT_THROW(writeAtomically(path,
                               [](const std::string& temp) {
                                 std::ofstream(temp) << "half";
                                 throw std::runtime_error("interrupted");
                               }),
               std::runtime_error);
  EXPECT_EQ(bytesOf(path), "old");
  size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1u);
  writeTextAtomically(path, "new");
  EXPECT_EQ(bytesOf(path), "new");
  fs::remove_all(dir);
}
