// Lane helpers that several row paths' lane bodies share (field_lanes.inc), compiled once per
// instruction set into the same namespaces as those bodies (sse2_lanes, avx2_lanes). Include it
// before a row header's own SNOW_LANES_BODY. Host only: never included by CUDA translation units.
#pragma once
#include "../simd_lanes.h"
#include "../snow_state.h"

namespace snow {

#define SNOW_LANES_BODY "phenomena/field_lanes.inc"
#include "../simd_lanes_for_each_isa.inc"

}  // namespace snow
