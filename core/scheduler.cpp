#include "scheduler.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "rng.h"

namespace snow {

int PoissonScheduler::add(PhenomenonSpec spec) {
  if (!(spec.stepsPerDay > 0.0) || !std::isfinite(spec.stepsPerDay))
    throw std::invalid_argument("phenomenon '" + spec.name + "': steps per day must be positive and finite");
  if (spec.startsPerDay < 0.0 || spec.stopsPerDay < 0.0)
    throw std::invalid_argument("phenomenon '" + spec.name + "': negative start or stop frequency");
  for (const auto& w : spec.windows)
    if (!(w.second > w.first)) throw std::invalid_argument("phenomenon '" + spec.name + "': empty window");
  std::sort(spec.windows.begin(), spec.windows.end());
  Phenomenon p;
  p.stats.name = spec.name;
  if (spec.alwaysActive && (!spec.windows.empty() || spec.startsPerDay > 0.0 || spec.stopsPerDay > 0.0))
    throw std::invalid_argument("phenomenon '" + spec.name + "': always active, so it takes no start, stop or windows");
  p.active = spec.alwaysActive;
  p.spec = std::move(spec);
  phenomena_.push_back(std::move(p));
  return static_cast<int>(phenomena_.size()) - 1;
}

void PoissonScheduler::addAction(double day, std::function<void(double)> action) {
  Action a{day, actionOrder_++, std::move(action)};
  auto it = std::upper_bound(actions_.begin(), actions_.end(), a, [](const Action& l, const Action& r) {
    return l.day < r.day || (l.day == r.day && l.order < r.order);
  });
  actions_.insert(it, std::move(a));
}

void PoissonScheduler::start(int id) {
  if (!phenomena_.at(id).active) fire(id, EventKind::Start);
}
void PoissonScheduler::stop(int id) {
  if (phenomena_.at(id).active && !phenomena_[id].spec.alwaysActive) fire(id, EventKind::Stop);
}

bool PoissonScheduler::zoomActive() const {
  for (const auto& p : phenomena_)
    if (p.active && p.spec.zoomed) return true;
  return false;
}

std::vector<PhenomenonStats> PoissonScheduler::stats() const {
  std::vector<PhenomenonStats> out;
  for (const auto& p : phenomena_) out.push_back(p.stats);
  return out;
}

double PoissonScheduler::uniform() {
  const Philox4x32 r = RandomKey{seed_}.draw(drawCounter_++, 0u, RngStream::Scheduler);
  return uniformOpenDouble(r.v[0], r.v[1]);
}

void PoissonScheduler::collectCandidates(std::vector<Candidate>& out) const {
  out.clear();
  const bool zoom = zoomActive();
  for (int i = 0; i < static_cast<int>(phenomena_.size()); ++i) {
    const auto& p = phenomena_[i];
    if (zoom && !(p.active && p.spec.zoomed)) continue;  // the temporal zoom: slow events wait
    const bool fixed = !p.spec.windows.empty();
    if (p.active) {
      out.push_back({i, EventKind::Step, p.spec.stepsPerDay});
      if (!fixed && p.spec.stopsPerDay > 0.0) out.push_back({i, EventKind::Stop, p.spec.stopsPerDay});
    } else if (!fixed && p.spec.startsPerDay > 0.0) {
      out.push_back({i, EventKind::Start, p.spec.startsPerDay});
    }
  }
}

double PoissonScheduler::nextBoundary(double endDay) const {
  double b = endDay;
  if (!actions_.empty()) b = std::min(b, actions_.front().day);
  for (const auto& p : phenomena_)
    for (const auto& w : p.spec.windows) {
      if (w.first > now_) b = std::min(b, w.first);
      if (w.second > now_) b = std::min(b, w.second);
    }
  return b;
}

// At the current instant: open or close fixed windows, then run the actions that are due.
void PoissonScheduler::applyBoundaries() {
  for (int i = 0; i < static_cast<int>(phenomena_.size()); ++i) {
    const auto& p = phenomena_[i];
    if (p.spec.windows.empty()) continue;
    bool inside = false;
    for (const auto& w : p.spec.windows) inside = inside || (now_ >= w.first && now_ < w.second);
    if (inside && !p.active) fire(i, EventKind::Start);
    if (!inside && p.active) fire(i, EventKind::Stop);
  }
  while (!actions_.empty() && actions_.front().day <= now_) {
    Action a = std::move(actions_.front());
    actions_.erase(actions_.begin());
    a.action(now_);
  }
}

void PoissonScheduler::fire(int id, EventKind kind) {
  Phenomenon& p = phenomena_[id];
  EventContext ctx{now_, eventIndex_++, 1.0 / p.spec.stepsPerDay, kind};
  if (traceOn_) trace_.push_back({now_, id, kind});
  switch (kind) {
    case EventKind::Start:
      p.active = true;
      ++p.stats.starts;
      if (p.spec.onStart) p.spec.onStart(ctx);
      break;
    case EventKind::Step:
      ++p.stats.steps;
      if (p.spec.onStep) p.spec.onStep(ctx);
      if (p.spec.finished && p.spec.finished()) fire(id, EventKind::Stop);
      break;
    case EventKind::Stop:
      p.active = false;
      ++p.stats.stops;
      if (p.spec.onStop) p.spec.onStop(ctx);
      break;
  }
}

void PoissonScheduler::runUntil(double endDay, const std::function<void(double)>& onProgress) {
  std::vector<Candidate> candidates;
  applyBoundaries();
  while (now_ < endDay) {
    collectCandidates(candidates);
    double total = 0.0;
    for (const auto& c : candidates) total += c.rate;
    const double boundary = nextBoundary(endDay);
    // Exp(total) waiting time; with nothing that can fire, jump to the next boundary.
    const double wait = total > 0.0 ? -std::log(uniform()) / total : std::numeric_limits<double>::infinity();
    if (now_ + wait >= boundary) {
      // Memorylessness: restarting every clock at the boundary leaves the process unchanged.
      now_ = boundary;
      applyBoundaries();
      if (onProgress) onProgress(now_);
      continue;
    }
    now_ += wait;
    const double pick = uniform() * total;  // Eq. (1): P(e) = f_e / sum f
    double acc = 0.0;
    const Candidate* chosen = &candidates.back();
    for (const auto& c : candidates) {
      acc += c.rate;
      if (pick < acc) {
        chosen = &c;
        break;
      }
    }
    fire(chosen->phenomenon, chosen->kind);
    if (onProgress) onProgress(now_);
  }
}

}  // namespace snow
