// Integer atomics for kernel bodies that run on every executor (the TBB threads and CUDA). Only
// integer operations whose result does not depend on their order are used where bytes must not
// depend on the schedule (additions, minimum).
#pragma once
#include <cstdint>

#include "hd.h"

namespace snow {

SNOW_HD SNOW_INLINE void atomicAddInt(int* p, int v) {
#if defined(__CUDA_ARCH__)
  atomicAdd(p, v);
#else
  __atomic_fetch_add(p, v, __ATOMIC_RELAXED);
#endif
}
SNOW_HD SNOW_INLINE void atomicAddCount(unsigned long long* p, unsigned long long v) {
#if defined(__CUDA_ARCH__)
  atomicAdd(p, v);
#else
  __atomic_fetch_add(p, v, __ATOMIC_RELAXED);
#endif
}
SNOW_HD SNOW_INLINE void atomicMinInt(int* p, int v) {
#if defined(__CUDA_ARCH__)
  atomicMin(p, v);
#else
  int seen = __atomic_load_n(p, __ATOMIC_RELAXED);
  while (v < seen && !__atomic_compare_exchange_n(p, &seen, v, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
  }
#endif
}
// A plain load and store that other threads may touch at the same time (relaxed: no ordering).
SNOW_HD SNOW_INLINE int atomicLoadInt(const int* p) {
#if defined(__CUDA_ARCH__)
  return *reinterpret_cast<const volatile int*>(p);
#else
  return __atomic_load_n(p, __ATOMIC_RELAXED);
#endif
}
SNOW_HD SNOW_INLINE void atomicStoreInt(int* p, int v) {
#if defined(__CUDA_ARCH__)
  *reinterpret_cast<volatile int*>(p) = v;
#else
  __atomic_store_n(p, v, __ATOMIC_RELAXED);
#endif
}

}  // namespace snow
