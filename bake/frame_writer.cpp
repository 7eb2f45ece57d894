#include "frame_writer.h"

#include <algorithm>

#include "core/release_memory.h"

namespace snow {

FrameWriter::FrameWriter(OutputWriter& writer, const SkiTracks* skiTracks, int threads, FrameTiming timing)
    : writer_(writer), skiTracks_(skiTracks), timing_(timing == FrameTiming::Auto ? FrameTiming::Paused : timing), arena_(std::max(1, threads)) {}

FrameWriter::~FrameWriter() {
  if (thread_.joinable()) thread_.join();
}

void FrameWriter::join() {
  if (!thread_.joinable()) return;
  thread_.join();
  if (error_) std::rethrow_exception(error_);
  currentSink().merge(sink_);
  sink_ = OutputSink();
}

void FrameWriter::write(double day, SnowState& s) {
  if (timing_ == FrameTiming::InPlace || timing_ == FrameTiming::Paused) {
    writer_.writeDay(s, day, skiTracks_ ? &skiTracks_->depth() : nullptr);
    if (timing_ == FrameTiming::Paused) releaseFreedMemory();  // the writers' memory, before the season's scratch comes back
    return;
  }
  if (timing_ == FrameTiming::AfterSeason) {
    held_.push_back({day, std::move(s), skiTracks_ ? skiTracks_->depth() : Grid<float>()});
    return;
  }
  join();
  state_ = std::move(s);  // the season's frame copy, taken: one copy of the state in flight, not two
  if (skiTracks_) skiDepth_ = skiTracks_->depth();
  thread_ = std::thread([this, day] {
    try {
      SinkScope scope(sink_);
      arena_.execute([&] { writer_.writeDay(state_, day, skiTracks_ ? &skiDepth_ : nullptr); });
    } catch (...) {
      error_ = std::current_exception();
    }
    state_ = SnowState();  // freed once written, not held until the next frame
    skiDepth_ = Grid<float>();
    releaseFreedMemory();  // this thread's arena, which the season's threads never reuse
  });
}

void FrameWriter::writeHeld() {
  for (Held& h : held_) {
    writer_.writeDay(h.state, h.day, skiTracks_ ? &h.skiDepth : nullptr);
    h = Held{};
    releaseFreedMemory();
  }
  held_.clear();
}

}  // namespace snow
