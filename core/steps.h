// Host orchestration of each season step over an Exec (SerialExec, TbbExec, CudaExec): how many
// passes, which colours, which kernel. Written once, instantiated per backend.
//
// An Exec provides:
//   template <class K> void forEachCell(int width, int height, const K& kernel);
//   template <class K> void forEachCellOfColour(int width, int height, int colour, const K& kernel);
//   template <class F, class G> void forEachCellThen(int width, int height, const F& first, const G& second);
//     (first on every cell, then second: SerialExec::forEachCellThen)
//   double sum(const float* values, const uint8_t* valid, int width, int height);  // fixed order
//   float maxValue(const float* values, const uint8_t* valid, int width, int height);
//   void finish();  // waits for queued work (GPU) and reports its errors
#pragma once
#include "kernels/avalanche.h"
#include "kernels/edit.h"
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
double runEdit(Exec& exec, const SnowFieldsView& v, const EditArgs& a) {
  exec.forEachCell(v.width, v.height, EditKernel{v, a});
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
  const int substeps = powderDiffusionSubsteps(a.dtDays, a.diffusionRatePerDay, a.diffusionLengthM, minCell);
  PowderDiffusionArgs sub = a;
  sub.dtDays = a.dtDays / static_cast<float>(substeps);
  exec.forEachCell(v.width, v.height, PowderBaseKernel{v});
  // Each substep: every cell's shares from the state at the substep's start, then every cell
  // gathers what it keeps and what its neighbours give it. The TBB executor interleaves the two
  // passes row by row (powder_diffusion_rows.h); the others run them one after the other.
  for (int s = 0; s < substeps; ++s) exec.forEachCellThen(v.width, v.height, PowderFlowKernel{v, sub}, PowderGatherKernel{v});
}

// Avalanche substeps over a box that grows by one cell per substep (snow moves at most one cell
// a substep), then the per-row statistics of the grown box. Returns the grown box in `a`.
template <class Exec>
void runAvalancheSteps(Exec& exec, const SnowFieldsView& v, AvalancheArgs& a, int substeps) {
  for (int s = 0; s < substeps; ++s) {
    a.x0 = a.x0 > 0 ? a.x0 - 1 : 0;
    a.y0 = a.y0 > 0 ? a.y0 - 1 : 0;
    a.x1 = a.x1 < v.width ? a.x1 + 1 : v.width;
    a.y1 = a.y1 < v.height ? a.y1 + 1 : v.height;
    const int w = a.x1 - a.x0, h = a.y1 - a.y0;
    if (w <= 0 || h <= 0) return;
    // Every cell with moving snow is at least one cell inside the box, so all of its pipes and
    // neighbours are processed; cells outside hold no flows (AvalancheClearIdleKernel).
    exec.forEachCell(w, h, InBox<AvalancheFlowKernel>{AvalancheFlowKernel{v, a}, a.x0, a.y0});
    exec.forEachCell(w, h, InBox<AvalancheScaleKernel>{AvalancheScaleKernel{v, a}, a.x0, a.y0});
    exec.forEachCell(w, h, InBox<AvalancheApplyScaleKernel>{AvalancheApplyScaleKernel{v}, a.x0, a.y0});
    exec.forEachCell(w, h, InBox<AvalancheHeightKernel>{AvalancheHeightKernel{v, a}, a.x0, a.y0});
  }
  if (a.x1 > a.x0 && a.y1 > a.y0) {
    exec.forEachCell(a.x1 - a.x0, a.y1 - a.y0, InBox<AvalancheClearIdleKernel>{AvalancheClearIdleKernel{v}, a.x0, a.y0});
    exec.forEachCell(1, a.y1 - a.y0, AvalancheRowStatsKernel{v, a});
  }
}

}  // namespace snow
