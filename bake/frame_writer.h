// Frame days' outputs, written one of three ways (frame_timing.h); the same files and manifest
// whichever. Paused (the default): the season waits, frees its scratch and lends its own fields
// to the writers (SeasonConfig::lendFrames), so a frame costs its writers and no more. Beside: on
// a thread of their own from a copy of the state (and of the ski-track texture, which the season
// keeps stamping) while the season goes on, one frame in flight (the next frame, or the season's
// end, waits for it); writers run in a task arena of their own so the season's parallel loops
// never run a writer's task, and each frame lists into its own sink, merged in frame order.
// AfterSeason: every frame's copies held through the season and written in writeHeld(), once
// its backend is freed.
#pragma once
#include <tbb/task_arena.h>

#include <exception>
#include <thread>
#include <vector>

#include "bakers/output_writer.h"
#include "frame_timing.h"
#include "core/ski_runs.h"

namespace snow {

class FrameWriter {
 public:
  // `timing`: FrameTiming::Auto is taken as Paused.
  FrameWriter(OutputWriter& writer, const SkiTracks* skiTracks, int threads, FrameTiming timing);
  // Paused: write() leaves the state as it was, so the season may lend it its own fields
  // (SeasonConfig::lendFrames).
  bool lendsFrames() const { return timing_ == FrameTiming::Paused; }
  ~FrameWriter();  // lets a writer still running finish (the season threw)
  FrameWriter(const FrameWriter&) = delete;
  FrameWriter& operator=(const FrameWriter&) = delete;

  // The outputs of frame day `day` from `state`: written before it returns (Paused, InPlace), or
  // taken (moved from) to write beside the season, or held (AfterSeason).
  void write(double day, SnowState& state);
  // Waits for the frame in flight, merges its files into the current sink, rethrows its error.
  void join();
  // Writes the frames held (FrameTiming::AfterSeason) in order, each freed once written.
  void writeHeld();

 private:
  OutputWriter& writer_;
  const SkiTracks* skiTracks_;
  FrameTiming timing_;
  tbb::task_arena arena_;
  std::thread thread_;
  SnowState state_;
  Grid<float> skiDepth_;
  OutputSink sink_;
  std::exception_ptr error_;
  struct Held {
    double day;
    SnowState state;
    Grid<float> skiDepth;
  };
  std::vector<Held> held_;
};

}  // namespace snow
