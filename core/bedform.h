// Transitional: the bedforms' host side is core/bedform_runs.h. precompute/scene.h (another
// branch's file) still includes this name; delete this file once it includes bedform_runs.h.
#pragma once
#include "bedform_runs.h"
