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
// Zeros where /proc/self/status is absent.
ProcessMemory readProcessMemory();

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
