// Hands the heap's free pages back to the system. glibc keeps what a thread frees in that thread's
// arena, for that thread to reuse: a day's writers (each on the frame writer's or TBB's threads)
// left their working sets resident after them, so each stood on the last one's and the season's
// peak was their sum, not their largest (docs/memory.md). Called where a large working set ends.
#pragma once
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace snow {

inline void releaseFreedMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace snow
