// Host orchestration of each season step over an Exec (SerialExec, TbbExec, CudaExec): how many
// passes, which colours, which kernel. Written once, instantiated per backend.
//
// An Exec provides:
//   template <class K> void forEachCell(int width, int height, const K& kernel);
//   template <class K> void forEachCellOfColour(int width, int height, int colour, const K& kernel);
//   double sum(const float* values, const uint8_t* valid, int width, int height);  // fixed order
//   float maxValue(const float* values, const uint8_t* valid, int width, int height);
//   void finish();  // waits for queued work (GPU) and reports its errors
#pragma once
#include "kernels/melt.h"
#include "kernels/powder_diffusion.h"
#include "kernels/snowfall.h"
#include "kernels/stability.h"
#include "kernels/wind_transport.h"
#include "snow_state.h"
#include "tiling.h"

namespace snow {

template <class Exec>
double runSnowfall(Exec& exec, const SnowFieldsView& v, const SnowfallArgs& a) {
  exec.forEachCell(v.width, v.height, SurfaceSlopeKernel{v});
  exec.forEachCell(v.width, v.height, SnowfallKernel{v, a});
  return exec.sum(v.delta, v.valid, v.width, v.height) * static_cast<double>(v.cellSizeXM) * v.cellSizeYM;
}

template <class Exec>
double runMelt(Exec& exec, const SnowFieldsView& v, const MeltArgs& a) {
  exec.forEachCell(v.width, v.height, MeltKernel{v, a});
  return exec.sum(v.delta, v.valid, v.width, v.height) * static_cast<double>(v.cellSizeXM) * v.cellSizeYM;
}

template <class Exec>
void runStability(Exec& exec, const SnowFieldsView& v, const StabilityArgs& a) {
  exec.forEachCell(v.width, v.height, SurfaceSlopeKernel{v});
  exec.forEachCell(v.width, v.height, StabilityKernel{v, a});
}

// One pass of five colours from a snapshot. Erosion per event is bounded by the powder there,
// and the deposit moves one cell: no substeps needed for stability.
template <class Exec>
void runWindTransport(Exec& exec, const SnowFieldsView& v, const WindTransportArgs& a) {
  exec.forEachCell(v.width, v.height, PowderSnapshotKernel{v});
  WindTransportArgs pass = a;
  for (int colour = 0; colour < 5; ++colour) {
    pass.colour = colour;
    exec.forEachCellOfColour(v.width, v.height, colour, WindTransportKernel{v, pass});
  }
}

template <class Exec>
void runPowderDiffusion(Exec& exec, const SnowFieldsView& v, const PowderDiffusionArgs& a) {
  const float minCell = v.cellSizeXM < v.cellSizeYM ? v.cellSizeXM : v.cellSizeYM;
  const int substeps = powderDiffusionSubsteps(a.dtDays, a.diffusionRatePerDay, a.referenceCellSizeM, minCell);
  PowderDiffusionArgs sub = a;
  sub.dtDays = a.dtDays / static_cast<float>(substeps);
  for (int s = 0; s < substeps; ++s) {
    exec.forEachCell(v.width, v.height, PowderSnapshotKernel{v});
    for (int colour = 0; colour < 5; ++colour) {
      sub.colour = colour;
      exec.forEachCellOfColour(v.width, v.height, colour, PowderDiffusionKernel{v, sub});
    }
  }
}

}  // namespace snow
