#include "memory_trace.h"

#include <algorithm>
#include <fstream>
#include <mutex>

namespace snow {

namespace {
std::mutex traceMutex;
std::vector<StageMemory>& trace() {
  static std::vector<StageMemory> t;
  return t;
}

double peakBeforeWindow = 0.0;  // the process's peak when the kernel's count was last reset

// VmRSS and VmHWM as the kernel counts them (the latter since the last reset).
ProcessMemory readKernelMemory() {
  ProcessMemory m;
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) m.residentBytes = std::stod(line.substr(6)) * 1024.0;
    if (line.rfind("VmHWM:", 0) == 0) m.peakBytes = std::stod(line.substr(6)) * 1024.0;
  }
  return m;
}
}  // namespace

ProcessMemory readProcessMemory() {
  ProcessMemory m = readKernelMemory();
  const std::lock_guard lock(traceMutex);
  m.peakBytes = std::max(m.peakBytes, peakBeforeWindow);
  return m;
}

bool startPeakWindow() {
  const std::lock_guard lock(traceMutex);  // no reader sees the reset before the peak is kept
  const double before = std::max(readKernelMemory().peakBytes, peakBeforeWindow);
  std::ofstream clear("/proc/self/clear_refs");
  if (!(clear << "5" << std::flush)) return false;  // "5": reset the peak resident set
  peakBeforeWindow = before;
  return true;
}

double peakInWindow() { return readKernelMemory().peakBytes; }

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
