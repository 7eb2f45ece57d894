// When a bake writes its frame days' outputs (BakeOptions::frames, frame_writer.h). The files
// are the same whichever: only the memory and the time differ.
#pragma once
#include <cstdint>

namespace snow {

enum class FrameTiming : uint8_t {
  Auto,         // run.frame_writing: paused unless the scene asks otherwise; after the season where
                // only that fits the memory budget (memory_model.h)
  Paused,       // the season waiting, its scratch freed and its fields lent to the writers: the leanest
  Beside,       // on a thread of their own while the season goes on: the fastest
  InPlace,      // the season waiting, from a copy (for tests and timing comparisons)
  AfterSeason,  // from copies held through the season, once its backend and scratch are freed
};

}  // namespace snow
