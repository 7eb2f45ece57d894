// A test's own temporary folder. Named by mkdtemp, so that two runs at once (ctest -j, or two
// checkouts on one machine) never share one, which fixed names under /tmp did. The folders are
// removed when the test program ends with every test passed, and kept to look at otherwise.
#pragma once
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace snow::test {

namespace detail {
inline std::vector<std::filesystem::path>& madeTempDirs() {
  static auto* dirs = new std::vector<std::filesystem::path>;  // never destroyed: read at exit
  return *dirs;
}
inline void removeTempDirsIfPassed() {
  if (!::testing::UnitTest::GetInstance()->Passed()) return;
  std::error_code ignored;
  for (const auto& d : madeTempDirs()) std::filesystem::remove_all(d, ignored);
}
}  // namespace detail

// A new, empty folder "snowbake_<stem>_XXXXXX" under the system's temporary folder.
inline std::filesystem::path uniqueTempDir(const std::string& stem) {
  std::string path = (std::filesystem::temp_directory_path() / ("snowbake_" + stem + "_XXXXXX")).string();
  if (!::mkdtemp(path.data())) throw std::runtime_error("cannot make a temporary folder " + path);
  static const bool atExit = std::atexit(detail::removeTempDirsIfPassed) == 0;
  (void)atExit;
  detail::madeTempDirs().push_back(path);
  return path;
}

// The same, named after the running test.
inline std::filesystem::path uniqueTestDir(const std::string& stem) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return uniqueTempDir(stem + "_" + (info ? std::string(info->name()) : std::string("main")));
}

}  // namespace snow::test
