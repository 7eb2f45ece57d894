// Which stage of a bake is running, for the message of a failure that cannot name its own
// (std::bad_alloc: main reports "out of memory during the <stage>", exit 1, instead of a
// terminate). Set by a BakeStage on the bake's thread while the stage runs; a stage left by an
// exception stays current, so that the handler still sees where it was thrown. A stage that ends
// notes the process's memory then (memory_trace.h).
#pragma once

namespace snow {

// "" outside a bake.
const char* currentBakeStage();

class BakeStage {
 public:
  explicit BakeStage(const char* name);
  ~BakeStage();
  BakeStage(const BakeStage&) = delete;
  BakeStage& operator=(const BakeStage&) = delete;

 private:
  const char* name_;
  const char* previous_;
  int exceptions_;
};

}  // namespace snow
