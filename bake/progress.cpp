#include "progress.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace snow {

bool stderrIsTerminal() { return ::isatty(STDERR_FILENO) == 1; }

ProgressBar::ProgressBar(std::ostream& out, std::string stage, bool terminal, bool enabled)
    : out_(out), stage_(std::move(stage)), terminal_(terminal), enabled_(enabled) {}

void ProgressBar::update(double fraction) {
  if (!enabled_ || finished_) return;
  const int percent = static_cast<int>(std::floor(std::clamp(fraction, 0.0, 1.0) * 100.0));
  if (terminal_) {
    if (percent == lastShown_) return;
    lastShown_ = percent;
    const int filled = percent * 30 / 100;
    out_ << "\r  " << stage_ << " [" << std::string(filled, '#') << std::string(30 - filled, '.') << "] " << percent << "%"
         << std::flush;
  } else {
    const int decile = percent / 10 * 10;
    if (decile <= lastShown_) return;
    lastShown_ = decile;
    out_ << "  " << stage_ << " " << decile << "%\n" << std::flush;
  }
}

void ProgressBar::finish() {
  if (!enabled_ || finished_) return;
  update(1.0);
  finished_ = true;
  if (terminal_) out_ << "\n" << std::flush;
}

void HumanProgress::stage(const std::string& name, double fraction) {
  const std::lock_guard lock(mutex_);
  auto it = bars_.find(name);
  // Stages that only begin (0) and end (1) draw nothing; a fraction in between starts a bar.
  if (it == bars_.end()) {
    if (fraction <= 0.0 || fraction >= 1.0) return;
    it = bars_.emplace(name, std::make_unique<ProgressBar>(out_, name, terminal_, enabled_)).first;
  }
  if (fraction >= 1.0)
    it->second->finish();
  else
    it->second->update(fraction);
}

namespace {

class NoProgress : public ProgressSink {
 public:
  void stage(const std::string&, double) override {}
  void event(const std::string&, const std::string&, const ProgressFields&) override {}
  void finish(const ProgressOutcome&) override {}
};

NoProgress noProgress;
// Not thread-local: the frame writer's thread reports into the bake's sink.
std::atomic<ProgressSink*> current{&noProgress};

}  // namespace

ProgressSink& progress() { return *current.load(); }

ProgressScope::ProgressScope(ProgressSink& sink) : previous_(current.exchange(&sink)) {}
ProgressScope::~ProgressScope() { current.store(previous_); }

}  // namespace snow
