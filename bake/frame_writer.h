// Frame days written beside the season: a frame's outputs are written on a thread of their own
// from a copy of the state (and of the ski-track texture, which the season keeps stamping) while
// the season goes on. One frame in flight: the next frame, or the season's end, waits for it.
// Writers run in a task arena of their own so the season's parallel loops never run a writer's
// task; each frame lists into its own sink, merged in frame order: the same files and manifest
// as writing them in place. FrameTiming::AfterSeason holds every frame's copies instead and
// writes them in writeHeld(), once the season's backend is freed: its writers then never stand
// beside the season's scratch (the largest grids' way under the memory budget).
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
  // `timing`: FrameTiming::Auto is taken as Beside.
  FrameWriter(OutputWriter& writer, const SkiTracks* skiTracks, int threads, FrameTiming timing);
  ~FrameWriter();  // lets a writer still running finish (the season threw)
  FrameWriter(const FrameWriter&) = delete;
  FrameWriter& operator=(const FrameWriter&) = delete;

  // The outputs of frame day `day` from `state`, which it takes (moves from) to write beside the season.
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
