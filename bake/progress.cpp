#include "progress.h"

#include <unistd.h>

#include <algorithm>
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

}  // namespace snow
