// SNOW_HD: marks a function as callable from host code and, under nvcc, from device code.
// Kernel bodies (core/phenomena/*.h) are written once with it and run on both backends.
#pragma once
#include <cmath>

#if defined(__CUDACC__)
#define SNOW_HD __host__ __device__
#define SNOW_INLINE __forceinline__
#else
#define SNOW_HD
#define SNOW_INLINE inline
#endif

namespace snow {

SNOW_HD SNOW_INLINE float clampf(float v, float lo, float hi) { return v < lo ? lo : (v > hi ? hi : v); }
SNOW_HD SNOW_INLINE float maxf(float a, float b) { return a > b ? a : b; }
SNOW_HD SNOW_INLINE float minf(float a, float b) { return a < b ? a : b; }
SNOW_HD SNOW_INLINE int maxi(int a, int b) { return a > b ? a : b; }

}  // namespace snow
