// Where the files a bake writes are listed: the manifest entries, paths and seconds per kind of
// output of one group of writers. Groups that run on threads of their own (frames, the VDB, mesh
// parts) list into sinks of their own, merged in a fixed order, so the manifest is the same
// whatever finished first.
#pragma once
#include <chrono>
#include <map>
#include <string>
#include <vector>

#include "manifest.h"

namespace snow {

struct OutputSink {
  std::vector<ManifestFile> files;
  std::vector<std::string> paths;
  std::map<std::string, double> seconds;  // by kind of output: the time since the previous listing
  std::chrono::steady_clock::time_point last = std::chrono::steady_clock::now();

  void merge(const OutputSink& from) {
    files.insert(files.end(), from.files.begin(), from.files.end());
    paths.insert(paths.end(), from.paths.begin(), from.paths.end());
    for (const auto& [kind, s] : from.seconds) seconds[kind] += s;
    last = std::chrono::steady_clock::now();
  }
  // Adds the time since the last listing (or addition) to `kind`.
  void addSeconds(const std::string& kind) {
    const auto now = std::chrono::steady_clock::now();
    seconds[kind] += std::chrono::duration<double>(now - last).count();
    last = now;
  }
  void addSeconds(const std::string& kind, double s) {
    seconds[kind] += s;
    last = std::chrono::steady_clock::now();
  }
};

// The sink this thread lists into: set for the scope of one writer group.
OutputSink& currentSink();
class SinkScope {
 public:
  explicit SinkScope(OutputSink& sink);
  ~SinkScope();
  SinkScope(const SinkScope&) = delete;
  SinkScope& operator=(const SinkScope&) = delete;

 private:
  OutputSink* previous_;
};

}  // namespace snow
