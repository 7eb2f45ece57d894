// Helpers of the tests that run the snowbake program and read what it wrote: a file's bytes, a
// run's exit status and output, a bake's manifest. The including target defines SNOWBAKE_BINARY.
#pragma once
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

namespace snow::test {

// A file's bytes ("" where it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct ProcessResult {
  int status;  // the exit status; -1 where the process did not exit (a signal)
  std::string err;
  std::string out;
};

// `snowbake ARGS` with no input, its stdout and stderr kept in `dir`'s stdout.txt and stderr.txt.
inline ProcessResult snowbake(const std::filesystem::path& dir, const std::string& args) {
  const std::string out = (dir / "stdout.txt").string(), err = (dir / "stderr.txt").string();
  const std::string cmd = std::string("'") + SNOWBAKE_BINARY + "' " + args + " >'" + out + "' 2>'" + err + "' </dev/null";
  const int raw = std::system(cmd.c_str());
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(err), slurp(out)};
}

// The manifest.json of a bake into `out`.
inline nlohmann::json manifestOf(const std::filesystem::path& out) {
  std::ifstream in(out / "manifest.json");
  return nlohmann::json::parse(in);
}

}  // namespace snow::test
