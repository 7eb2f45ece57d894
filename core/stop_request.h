// Ctrl-C: SIGINT or SIGTERM asks a bake to stop. The signal handler only sets a flag; the bake
// looks at it between stages, once a simulated day and between a day's outputs, and stops there by
// throwing Interrupted, so no file is cut off mid-write (each is written to a temporary name and
// renamed, core/atomic_file.h) and no manifest is written. The program exits with 128 + 2 = 130.
#pragma once
#include <atomic>
#include <csignal>
#include <stdexcept>
#include <string>

namespace snow {

constexpr int kInterruptedExitStatus = 130;

class Interrupted : public std::runtime_error {
 public:
  explicit Interrupted(int signal)
      : std::runtime_error(std::string("interrupted by ") + (signal == SIGTERM ? "SIGTERM" : "SIGINT") +
                           ": stopped between steps; the files written so far are whole, no manifest was written"),
        signal_(signal) {}
  int signal() const { return signal_; }

 private:
  int signal_;
};

// The signal that asked to stop, 0 for none. Lock-free, so the handler may store into it.
inline std::atomic<int>& stopSignal() {
  static std::atomic<int> signal{0};
  return signal;
}
inline void throwIfStopRequested() {
  if (const int s = stopSignal().load(std::memory_order_relaxed)) throw Interrupted(s);
}

// SIGINT and SIGTERM set stopSignal() for this object's scope; the previous handlers come back
// after it (Python's own SIGINT handler, in the module).
class StopOnSignals {
 public:
  StopOnSignals() {
    stopSignal().store(0);
    struct sigaction a {};
    a.sa_handler = [](int s) { stopSignal().store(s); };
    sigemptyset(&a.sa_mask);
    sigaction(SIGINT, &a, &previousInt_);
    sigaction(SIGTERM, &a, &previousTerm_);
  }
  ~StopOnSignals() {
    sigaction(SIGINT, &previousInt_, nullptr);
    sigaction(SIGTERM, &previousTerm_, nullptr);
  }
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;

 private:
  struct sigaction previousInt_ {}, previousTerm_ {};
};

}  // namespace snow
