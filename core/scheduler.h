// The Poisson event scheduler of the paper's §3.1.
//
// Each phenomenon is a Poisson process: while active, its step events arrive at a mean
// frequency f (per simulated day); episodic phenomena (snowfall, avalanches, skiers) also have
// start and stop events, or fixed active windows from the scene's timeline. The superposition of
// all these processes is itself a Poisson process of rate F = sum(f): the scheduler draws the
// time to the next event from Exp(F) and which event it is with probability f_e / F (Eq. 1),
// both from the counter-based generator keyed by the seed, so a run is reproducible.
//
// Temporal zoom: while a `zoomed` phenomenon (avalanche, ski run) is active, only the events of
// active zoomed phenomena can fire; the slow events wait (their Poisson clocks are memoryless,
// so suspending them changes nothing but time). Fixed-time actions (frames to record, user
// events) and the edges of fixed windows are met exactly.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace snow {

enum class EventKind { Start = 0, Step = 1, Stop = 2 };

struct EventContext {
  double day = 0;           // simulated time, days since the season start
  uint64_t eventIndex = 0;  // counts every event fired: the key for the kernels' random numbers
  double stepDays = 0;      // the nominal length of one step of this phenomenon: 1 / stepsPerDay
  EventKind kind = EventKind::Step;
};

struct PhenomenonSpec {
  std::string name;
  double stepsPerDay = 1.0;  // step events per day while active
  // Continuous phenomena (melt, diffusion) are always active and only step.
  bool alwaysActive = false;
  // Episodic phenomena: mean starts per day while inactive, and mean stops per day while active
  // (the mean duration is 1 / stopsPerDay). With neither, they start only when asked (start()).
  double startsPerDay = 0.0;
  double stopsPerDay = 0.0;
  // Fixed active periods [begin, end) in days. When given, they replace the Poisson start/stop.
  std::vector<std::pair<double, double>> windows;
  bool zoomed = false;   // temporal zoom: suppresses every non-zoomed event while active
  std::function<void(const EventContext&)> onStart, onStep, onStop;
  // Polled after each step of an active phenomenon: true ends it (e.g. an avalanche at rest).
  std::function<bool()> finished;
};

struct PhenomenonStats {
  std::string name;
  uint64_t starts = 0, steps = 0, stops = 0;
};

struct TraceEntry {
  double day;
  int phenomenon;
  EventKind kind;
};

class PoissonScheduler {
 public:
  explicit PoissonScheduler(uint64_t seed) : seed_(seed) {}

  int add(PhenomenonSpec spec);
  // Calls `action(day)` when simulated time reaches `day` (frames, user events).
  void addAction(double day, std::function<void(double)> action);
  // Starts a phenomenon now (a user-triggered avalanche, say); no effect if already active.
  void start(int phenomenon);
  void stop(int phenomenon);

  // Advances simulated time to `endDay`, firing events. `onProgress(day)` is called after each event.
  void runUntil(double endDay, const std::function<void(double)>& onProgress = {});

  double now() const { return now_; }
  bool isActive(int phenomenon) const { return phenomena_[phenomenon].active; }
  bool zoomActive() const;
  uint64_t eventsFired() const { return eventIndex_; }
  std::vector<PhenomenonStats> stats() const;
  void enableTrace(bool on) { traceOn_ = on; }
  const std::vector<TraceEntry>& trace() const { return trace_; }

 private:
  struct Phenomenon {
    PhenomenonSpec spec;
    bool active = false;
    PhenomenonStats stats;
  };
  struct Action {
    double day;
    uint64_t order;
    std::function<void(double)> action;
  };
  // Candidate events at the current instant, with their rates (per day).
  struct Candidate {
    int phenomenon;
    EventKind kind;
    double rate;
  };
  void collectCandidates(std::vector<Candidate>& out) const;
  double nextBoundary(double endDay) const;
  void applyBoundaries();
  void fire(int phenomenon, EventKind kind);
  double uniform();

  uint64_t seed_;
  uint64_t drawCounter_ = 0;
  uint64_t eventIndex_ = 0;
  uint64_t actionOrder_ = 0;
  double now_ = 0.0;
  std::vector<Phenomenon> phenomena_;
  std::vector<Action> actions_;  // pending, sorted by (day, order)
  bool traceOn_ = false;
  std::vector<TraceEntry> trace_;
};

}  // namespace snow
