// Progress of a bake, through one sink: the human bar (redrawn in place on a terminal, plain lines
// every 10% in a log) or JSON lines for a render farm (docs/command-line.md, "--progress json").
// Stages report fractions and events to progress(); the bake sets the sink for its scope.
#pragma once
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace snow {

class ProgressBar {
 public:
  ProgressBar(std::ostream& out, std::string stage, bool terminal, bool enabled = true);
  void update(double fraction);  // 0..1
  void finish();

 private:
  std::ostream& out_;
  std::string stage_;
  bool terminal_;
  bool enabled_;
  int lastShown_ = -1;
  bool finished_ = false;
};

// True when the stream is attached to a terminal (stderr is what snowbake logs to).
bool stderrIsTerminal();

// An event's fields besides its stage and name, as key and JSON value (jsonText/jsonNumber).
using ProgressFields = std::vector<std::pair<std::string, std::string>>;
std::string jsonText(const std::string& s);
std::string jsonNumber(double v);

// How a bake ended, for the final line.
struct ProgressOutcome {
  std::string outcome{};  // "ok", "input_error", "interrupted" (exit status 130) or "failed"
  int exitStatus = 0;
  long long files = -1;  // the files the manifest lists (-1: no manifest)
  std::string manifest{};
  double massBalance = -1;  // the season's relative mass-balance error (-1: none)
  std::string message{};
};

class ProgressSink {
 public:
  virtual ~ProgressSink() = default;
  // The stage's fraction done, 0..1; a stage begins at 0 and ends at 1. May be called from any thread.
  virtual void stage(const std::string& name, double fraction) = 0;
  virtual void event(const std::string& stage, const std::string& name, const ProgressFields& fields = {}) = 0;
  virtual void finish(const ProgressOutcome& outcome) = 0;
};

// The human bar: stages that report fractions between 0 and 1 draw one; events are left to the log.
class HumanProgress : public ProgressSink {
 public:
  HumanProgress(std::ostream& out, bool terminal, bool enabled) : out_(out), terminal_(terminal), enabled_(enabled) {}
  void stage(const std::string& name, double fraction) override;
  void event(const std::string&, const std::string&, const ProgressFields&) override {}
  void finish(const ProgressOutcome&) override {}

 private:
  std::ostream& out_;
  bool terminal_, enabled_;
  std::mutex mutex_;
  std::map<std::string, std::unique_ptr<ProgressBar>> bars_;
};

// One JSON object a line: {"type":"progress"|"event"|"done", ...}; fractions never decrease
// within a stage; the remaining time is the stage's, extrapolated linearly.
class JsonProgress : public ProgressSink {
 public:
  explicit JsonProgress(std::ostream& out);
  void stage(const std::string& name, double fraction) override;
  void event(const std::string& stage, const std::string& name, const ProgressFields& fields = {}) override;
  void finish(const ProgressOutcome& outcome) override;

 private:
  struct StageClock {
    std::chrono::steady_clock::time_point start;
    double fraction = -1;
  };
  double elapsed() const;
  std::ostream& out_;
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;
  std::map<std::string, StageClock> stages_;
};

// The sink stages report to: a sink that drops everything unless a ProgressScope set one.
ProgressSink& progress();
class ProgressScope {
 public:
  explicit ProgressScope(ProgressSink& sink);
  ~ProgressScope();
  ProgressScope(const ProgressScope&) = delete;
  ProgressScope& operator=(const ProgressScope&) = delete;

 private:
  ProgressSink* previous_;
};

}  // namespace snow
