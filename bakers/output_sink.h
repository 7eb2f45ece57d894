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

// A file `snowbake plan` says the bake would write: listed by the same writers in plan mode
// (OutputSources::plan), which write nothing and compute no values.
struct PlannedFile {
  std::string path{};     // absolute, as the bake writes it
  std::string format{};   // the manifest's format line
  std::string content{};
  double dataBytes = 0;   // pixel or sample bytes, uncompressed (0: not known before the bake: meshes, VDB, text)
  bool exactBytes = false;  // the file is exactly dataBytes long (r16, r32: no header, no compression)
  std::string condition{};  // empty: always written; else when it is left out (it depends on the season's snow)
  std::string note{};     // printed beside the file: why it stays whole under [outputs.tiles]
};

struct OutputSink {
  std::vector<ManifestFile> files;
  std::vector<std::string> paths;
  std::vector<PlannedFile> planned;  // plan mode only
  std::map<std::string, double> seconds;  // by kind of output: the time since the previous listing
  std::chrono::steady_clock::time_point last = std::chrono::steady_clock::now();

  void merge(const OutputSink& from) {
    files.insert(files.end(), from.files.begin(), from.files.end());
    paths.insert(paths.end(), from.paths.begin(), from.paths.end());
    planned.insert(planned.end(), from.planned.begin(), from.planned.end());
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
