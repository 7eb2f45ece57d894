#include "bake_stage.h"

#include <atomic>
#include <exception>

#include "core/release_memory.h"
#include "core/stop_request.h"
#include "memory_trace.h"

namespace snow {

namespace {
// Atomic: a frame writer's thread or a TBB worker may read it while the bake's thread moves on.
std::atomic<const char*> stage{""};
}  // namespace

const char* currentBakeStage() { return stage.load(); }

// A new stage is a point where Ctrl-C stops the bake (core/stop_request.h).
BakeStage::BakeStage(const char* name) : name_(name), previous_(stage.exchange(name)), exceptions_(std::uncaught_exceptions()) {
  throwIfStopRequested();
}
BakeStage::~BakeStage() {
  if (std::uncaught_exceptions() != exceptions_) return;
  stage.store(previous_);
  noteStageMemory(name_);
  releaseFreedMemory();  // the stage's working sets, before the next stage's
}

}  // namespace snow
