#include "memory_trace.h"

#include <fstream>
#include <mutex>

namespace snow {

namespace {
std::mutex traceMutex;
std::vector<StageMemory>& trace() {
  static std::vector<StageMemory> t;
  return t;
}
}  // namespace

ProcessMemory readProcessMemory() {
  ProcessMemory m;
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) m.residentBytes = std::stod(line.substr(6)) * 1024.0;
    if (line.rfind("VmHWM:", 0) == 0) m.peakBytes = std::stod(line.substr(6)) * 1024.0;
  }
  return m;
}

void noteStageMemory(const char* stage) {
  const ProcessMemory m = readProcessMemory();
  const std::lock_guard lock(traceMutex);
  trace().push_back({stage, m});
}

std::vector<StageMemory> stageMemory() {
  const std::lock_guard lock(traceMutex);
  return trace();
}

void resetStageMemory() {
  const std::lock_guard lock(traceMutex);
  trace().clear();
}

std::string stageOfPeak(const std::vector<StageMemory>& stages, double peakBytes) {
  for (const StageMemory& s : stages)
    if (s.atEnd.peakBytes + 1024.0 * 1024.0 >= peakBytes) return s.stage;
  return "";
}

}  // namespace snow
