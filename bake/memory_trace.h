// The process's memory as the kernel counts it (/proc/self/status: VmRSS, the resident set now,
// and VmHWM, its peak), noted at the end of each bake stage (BakeStage), so the bake can say which
// stage its peak came in and set it against the memory model's owners (memory_model.h).
#pragma once
#include <string>
#include <vector>

namespace snow {

struct ProcessMemory {
  double residentBytes = 0;  // VmRSS
  double peakBytes = 0;      // VmHWM
};
// Zeros where /proc/self/status is absent. The peak is the process's, across peak windows.
ProcessMemory readProcessMemory();

// A window of the kernel's peak count, to tell one phase's peak from an earlier phase's (a bake
// across ranks: the season's per rank, below the whole precompute's). Starting one resets VmHWM
// through /proc/self/clear_refs, which also resets what getrusage and `time -v` report as the
// maximum resident set; false where the kernel refuses (the window is then the whole process's).
bool startPeakWindow();
// VmHWM since the window started: the phase's own peak.
double peakInWindow();

struct StageMemory {
  std::string stage;
  ProcessMemory atEnd;
};
// Called by BakeStage when a stage ends; stageMemory() lists them in order (since the last reset).
void noteStageMemory(const char* stage);
std::vector<StageMemory> stageMemory();
void resetStageMemory();
// The first stage at whose end the peak had reached `peakBytes` (within a MiB), "" if none.
std::string stageOfPeak(const std::vector<StageMemory>& stages, double peakBytes);

}  // namespace snow
