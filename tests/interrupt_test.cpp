// Ctrl-C (core/stop_request.h): SIGINT sent to a running bake stops it between steps with exit
// status 130, a final JSON progress line saying so, no manifest and no file left under a
// temporary name.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "cli_support.h"

namespace snow {
namespace {

using snow::test::slurp;

namespace fs = std::filesystem;

TEST(Interrupt, SigintStopsABakeWithExit130NoManifestAndNoPartialFile) {
  const fs::path dir = fs::temp_directory_path() / ("snowbake_interrupt_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path out = dir / "out", err = dir / "stderr.jsonl";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::freopen(err.c_str(), "w", stderr);
    execl(SNOWBAKE_BINARY, SNOWBAKE_BINARY, "bake", "preset:default", "--set", "terrain.size=256", "--set", "season.days=120", "--set",
          "outputs.frames_days=[1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20]", "--no-cache", "--threads", "2", "--progress", "json",
          "--out", out.c_str(), static_cast<char*>(nullptr));
    _exit(99);
  }
  // Once the season has begun (and frames are being written), Ctrl-C.
  const auto t0 = std::chrono::steady_clock::now();
  while (slurp(err).find("\"event\":\"frame\"") == std::string::npos && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(120))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_NE(slurp(err).find("\"event\":\"frame\""), std::string::npos) << slurp(err);
  const auto tSignal = std::chrono::steady_clock::now();
  ASSERT_EQ(kill(pid, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  const double stopSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - tSignal).count();
  ASSERT_TRUE(WIFEXITED(status)) << "killed by the signal instead of stopping";
  EXPECT_EQ(WEXITSTATUS(status), 130);
  std::printf("[ measure ] stopped %.2f s after SIGINT\n", stopSeconds);
  EXPECT_LT(stopSeconds, 20.0);
  const std::string text = slurp(err);
  const std::string last = text.substr(text.rfind('{', text.size() - 2));
  EXPECT_NE(last.find("\"type\":\"done\""), std::string::npos) << last;
  EXPECT_NE(last.find("\"outcome\":\"interrupted\""), std::string::npos) << last;
  EXPECT_NE(last.find("\"exit_status\":130"), std::string::npos) << last;
  EXPECT_FALSE(fs::exists(out / "manifest.json"));
  size_t files = 0;
  for (const auto& e : fs::recursive_directory_iterator(out)) {
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
    files += e.is_regular_file();
  }
  EXPECT_GT(files, 0u) << "the frames written before the signal are kept";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace snow
