// The JSON-lines progress sink (format: docs/command-line.md, "--progress json").
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "progress.h"

namespace snow {

std::string jsonText(const std::string& s) {
  std::string o = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      o += buf;
    } else {
      o += c;
    }
  }
  return o + "\"";
}

std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

JsonProgress::JsonProgress(std::ostream& out) : out_(out), start_(std::chrono::steady_clock::now()) {}

double JsonProgress::elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

void JsonProgress::stage(const std::string& name, double fraction) {
  const std::lock_guard lock(mutex_);
  auto [it, fresh] = stages_.try_emplace(name, StageClock{std::chrono::steady_clock::now(), -1});
  StageClock& clock = it->second;
  fraction = std::clamp(fraction, 0.0, 1.0);
  // Never decreasing, and a line only when the hundredth changes (a season reports once a day).
  if (fraction < clock.fraction || (!fresh && std::floor(fraction * 100) == std::floor(clock.fraction * 100) && fraction < 1.0)) return;
  if (fraction == clock.fraction) return;
  clock.fraction = fraction;
  const double inStage = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock.start).count();
  const double remaining = fraction >= 1.0 ? 0.0 : fraction > 0 ? inStage * (1.0 - fraction) / fraction : NAN;
  out_ << "{\"type\":\"progress\",\"stage\":" << jsonText(name) << ",\"fraction\":" << jsonNumber(fraction)
       << ",\"elapsed_s\":" << jsonNumber(elapsed()) << ",\"remaining_s\":" << jsonNumber(remaining) << "}\n"
       << std::flush;
}

void JsonProgress::event(const std::string& stage, const std::string& name, const ProgressFields& fields) {
  const std::lock_guard lock(mutex_);
  out_ << "{\"type\":\"event\",\"stage\":" << jsonText(stage) << ",\"event\":" << jsonText(name) << ",\"elapsed_s\":" << jsonNumber(elapsed());
  for (const auto& [key, value] : fields) out_ << "," << jsonText(key) << ":" << value;
  out_ << "}\n" << std::flush;
}

void JsonProgress::finish(const ProgressOutcome& o) {
  const std::lock_guard lock(mutex_);
  out_ << "{\"type\":\"done\",\"outcome\":" << jsonText(o.outcome) << ",\"exit_status\":" << o.exitStatus
       << ",\"elapsed_s\":" << jsonNumber(elapsed());
  if (o.files >= 0) out_ << ",\"files\":" << o.files << ",\"manifest\":" << jsonText(o.manifest);
  if (o.massBalance >= 0) out_ << ",\"mass_balance_relative_error\":" << jsonNumber(o.massBalance);
  if (!o.message.empty()) out_ << ",\"message\":" << jsonText(o.message);
  out_ << "}\n" << std::flush;
}

}  // namespace snow
