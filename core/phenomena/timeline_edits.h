// Timeline edits (art direction, the model paper's brushes as painted masks): at a given day,
// add, remove or set a layer's depth, or move snow from one layer to another, each cell weighted
// by the mask's grey value w in [0, 1] (a soft falloff where the mask is grey):
//   add     L += w d
//   remove  L -= min(L, w d)
//   set     L  = (1 - w) L + w d          (w = 1: exactly d; w = 0: unchanged)
//   move    m  = w min(L, d) (or w L when no depth is given);  L -= m, L_to += m
// Per cell, no neighbour writes. The edits and their masks come from the scene's art direction
// (bake/art_direction.cpp builds each SeasonEdit: EditArgs and its weights).
// Scratch: delta (what the layers actually gained), and the backend's edit-weight buffer for the
// pass (emptied after it).
// Mass: adds or removes snow (a move changes the total by float rounding only); runEdit returns
// the volume added for the season's ledger, which stays exact.
// Backend: SnowBackend::applyEdit (ExecBackend runs runEdit). Season: SeasonRun::addEdits
// (core/season.cpp), each edit an action at its day. Parameters: none (the scene's edits).
#pragma once
#include <vector>

#include "../hd.h"
#include "../snow_state.h"

namespace snow {

enum class EditOp : int { Add = 0, Remove = 1, Set = 2, Move = 3 };

struct EditArgs {
  EditOp op = EditOp::Add;
  int layer = 0;      // SnowLayer
  int toLayer = 0;    // SnowLayer, for Move
  float depthM = 0.f;
  bool hasDepth = true;  // Move without a depth moves the whole layer (times w)
};

SNOW_HD SNOW_INLINE float* snowLayerField(const SnowFieldsView& v, int layer) {
  switch (layer) {
    case 0: return v.compacted;
    case 1: return v.stable;
    case 2: return v.unstable;
    default: return v.powder;
  }
}

struct EditKernel {
  SnowFieldsView v;
  EditArgs a;

  SNOW_HD void operator()(int x, int y) const {
    const int i = v.index(x, y);
    v.delta[i] = 0.f;
    if (!v.valid[i]) return;
    const float w = v.editWeight ? minf(1.f, maxf(0.f, v.editWeight[i])) : 1.f;  // no mask: everywhere
    if (!(w > 0.f)) return;
    float* field = snowLayerField(v, a.layer);
    const float before = field[i];
    switch (a.op) {
      case EditOp::Add:
        field[i] = before + w * a.depthM;
        break;
      case EditOp::Remove:
        field[i] = before - minf(before, w * a.depthM);
        break;
      case EditOp::Set:
        field[i] = maxf(0.f, (1.f - w) * before + w * a.depthM);
        break;
      case EditOp::Move: {
        float* to = snowLayerField(v, a.toLayer);
        const float amount = w * (a.hasDepth ? minf(before, a.depthM) : before);
        const float toBefore = to[i];
        field[i] = maxf(0.f, before - amount);
        to[i] = toBefore + (before - field[i]);
        v.delta[i] = (to[i] - toBefore) - (before - field[i]);
        return;
      }
    }
    v.delta[i] = field[i] - before;
  }
};

// The edit weighted by `weights` (one per cell, row order; empty: 1 everywhere), uploaded into
// `weightBuffer` for the pass only; returns the snow volume it added (negative: removed), in m^3.
template <class Exec, class WeightBuffer>
double runEdit(Exec& exec, SnowFieldsView v, WeightBuffer& weightBuffer, const EditArgs& a, const std::vector<float>& weights) {
  exec.upload(weightBuffer, weights);
  v.editWeight = weights.empty() ? nullptr : weightBuffer.data();
  exec.forEachCell(v.width, v.height, EditKernel{v, a});
  const double added = exec.sum(v.delta, v.valid, v.width, v.height) * static_cast<double>(v.cellSizeXM) * v.cellSizeYM;
  exec.upload(weightBuffer, std::vector<float>());
  exec.finish();
  return added;
}

}  // namespace snow
