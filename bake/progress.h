// Progress of long stages: a bar redrawn in place on a terminal, plain lines (every 10%) in a log.
#pragma once
#include <ostream>
#include <string>

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

}  // namespace snow
