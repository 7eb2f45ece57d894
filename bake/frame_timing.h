// When a bake writes its frame days' outputs (BakeOptions::frames, frame_writer.h). The files
// are the same whichever: only the memory and the time differ.
#pragma once
#include <cstdint>

namespace snow {

enum class FrameTiming : uint8_t {
  Auto,         // beside the season, or after it where only that fits the memory budget (memory_model.h)
  Beside,       // on a thread of their own while the season goes on
  InPlace,      // the season waiting (for tests and timing comparisons)
  AfterSeason,  // from copies held through the season, once its backend and scratch are freed
};

}  // namespace snow
