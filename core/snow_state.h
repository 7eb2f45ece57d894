// The layered snow model of the paper's §3.1 and §5: bedrock B and, on top of it, compacted C,
// stable S, unstable U and powdery P snow (each a depth in metres of snow), the avalanche
// "snow moving" flag, and the static fields that precompute fills once per terrain; the host's
// SnowState and the kernels' SnowFieldsView, both expanded from snow_fields.h.
#pragma once
#include <cstdint>
#include <string>

#include "grid.h"
#include "hd.h"
#include "snow_fields.h"

namespace snow {

enum class SnowLayer : int { Compacted = 0, Stable = 1, Unstable = 2, Powder = 3 };
constexpr int kSnowLayerCount = 4;
inline const char* snowLayerName(SnowLayer l) {
  switch (l) {
    case SnowLayer::Compacted: return "compacted";
    case SnowLayer::Stable: return "stable";
    case SnowLayer::Unstable: return "unstable";
    case SnowLayer::Powder: return "powder";
  }
  return "?";
}

// Each field of SnowState by its member's name, in declaration order, and sets of them (a bit
// each): which record fields a season keeps (SeasonConfig::recordFields) and a layer reads.
enum class SnowField : int {
#define SNOW_FIELD_ID(member, view, Element, role, access, fill) member,
  SNOW_STATE_FIELDS(SNOW_FIELD_ID)
#undef SNOW_FIELD_ID
  Count
};
// Each of the backend's scratch fields (SNOW_SCRATCH_FIELDS) by its view's name.
enum class ScratchField : int {
#define SNOW_SCRATCH_ID(view, Element, extent) view,
  SNOW_SCRATCH_FIELDS(SNOW_SCRATCH_ID)
#undef SNOW_SCRATCH_ID
  Count
};
using SnowFieldSet = uint64_t;
static_assert(static_cast<int>(SnowField::Count) <= 64, "SnowFieldSet holds a bit a field");
constexpr SnowFieldSet fieldBit(SnowField f) { return SnowFieldSet(1) << static_cast<int>(f); }
// Every record field (FieldRole::Record): what a season keeps unless told otherwise.
constexpr SnowFieldSet kAllRecordFields = SnowFieldSet(0)
#define SNOW_RECORD_BIT(member, view, Element, role, access, fill) | (FieldRole::role == FieldRole::Record ? fieldBit(SnowField::member) : 0)
    SNOW_STATE_FIELDS(SNOW_RECORD_BIT)
#undef SNOW_RECORD_BIT
    ;

// Host-side state of one terrain: what the season evolves and what the bakers read. The grids
// are declared in snow_fields.h (SNOW_STATE_FIELDS), each with its role and its comment.
struct SnowState {
  GridSpec spec;
#define SNOW_STATE_MEMBER(member, view, Element, role, access, fill) Grid<Element> member;
  SNOW_STATE_FIELDS(SNOW_STATE_MEMBER)
#undef SNOW_STATE_MEMBER

  // Allocates every field for `s` (each with its fill: no snow, all cells valid, static fields
  // zero); the optional fields are left as they are.
  void allocate(const GridSpec& s) {
    allocate(s, [](FieldRole) { return true; });
  }
  // The same for the fields whose role `pick(role)` accepts; the others stay absent.
  template <class Pick>
  void allocate(const GridSpec& s, Pick pick) {
    spec = s;
#define SNOW_ALLOCATE(member, view, Element, role, access, fill) \
  if (!optionalField(FieldRole::role) && pick(FieldRole::role)) member.resize(s.width, s.height, fill);
    SNOW_STATE_FIELDS(SNOW_ALLOCATE)
#undef SNOW_ALLOCATE
  }
  // Frees the grids of the fields whose role `drop(role)` accepts (the season's host state while a
  // backend holds them); restoreFields gives them back their size, zeroed, for a download to fill.
  template <class Pick>
  void releaseFields(Pick drop) {
#define SNOW_RELEASE(member, view, Element, role, access, fill) \
  if (drop(FieldRole::role)) member = Grid<Element>();
    SNOW_STATE_FIELDS(SNOW_RELEASE)
#undef SNOW_RELEASE
  }
  // (of the record fields, only those in `records`: the ones a season keeps).
  template <class Pick>
  void restoreFields(Pick pick, SnowFieldSet records = kAllRecordFields) {
#define SNOW_RESTORE(member, view, Element, role, access, fill)                                                    \
  if (pick(FieldRole::role) && (FieldRole::role != FieldRole::Record || (records & fieldBit(SnowField::member))) && \
      member.size() != spec.cellCount())                                                                          \
    member.resize(spec.width, spec.height);
    SNOW_STATE_FIELDS(SNOW_RESTORE)
#undef SNOW_RESTORE
  }
  // Frees the record fields not in `kept`: a season keeps only those its outputs read.
  void keepRecordFields(SnowFieldSet kept) {
#define SNOW_KEEP_RECORD(member, view, Element, role, access, fill) \
  if (FieldRole::role == FieldRole::Record && !(kept & fieldBit(SnowField::member))) member = Grid<Element>();
    SNOW_STATE_FIELDS(SNOW_KEEP_RECORD)
#undef SNOW_KEEP_RECORD
  }
  // Bytes the grids hold now.
  template <class Pick>
  size_t bytes(Pick pick) const {
    size_t b = 0;
#define SNOW_BYTES(member, view, Element, role, access, fill) \
  if (pick(FieldRole::role)) b += member.size() * sizeof(Element);
    SNOW_STATE_FIELDS(SNOW_BYTES)
#undef SNOW_BYTES
    return b;
  }
  Grid<float>& layer(SnowLayer l) {
    switch (l) {
      case SnowLayer::Compacted: return compactedM;
      case SnowLayer::Stable: return stableM;
      case SnowLayer::Unstable: return unstableM;
      case SnowLayer::Powder: return powderM;
    }
    return powderM;
  }
  const Grid<float>& layer(SnowLayer l) const { return const_cast<SnowState*>(this)->layer(l); }
  float depthM(int x, int y) const { return compactedM(x, y) + stableM(x, y) + unstableM(x, y) + powderM(x, y); }
  // C + S + U + P of every cell (NODATA cells included, as stored).
  Grid<float> depthGrid() const {
    Grid<float> d(spec.width, spec.height, 0.f);
    for (int y = 0; y < spec.height; ++y)
      for (int x = 0; x < spec.width; ++x) d(x, y) = depthM(x, y);
    return d;
  }
};

// The four snow layers of a box of the grid (x0, y0: its north-west cell; the whole grid when the
// box is), and on request the current avalanche's peak fields: what the host's avalanche runner
// reads back from a backend, in place of whole copies of the state.
struct SnowBox {
  int x0 = 0, y0 = 0, width = 0, height = 0;
  Grid<float> compacted, stable, unstable, powder;
  Grid<float> peakThickness, peakSpeed;  // empty unless asked for
  size_t index(int x, int y) const { return static_cast<size_t>(y - y0) * width + (x - x0); }
  // C + S + U + P in float, as SnowState::depthM adds them.
  float depth(size_t i) const {
    return compacted.values()[i] + stable.values()[i] + unstable.values()[i] + powder.values()[i];
  }
  size_t bytes() const {
    return (compacted.size() + stable.size() + unstable.size() + powder.size() + peakThickness.size() + peakSpeed.size()) * sizeof(float);
  }
};

// A field of SnowState as forEachSnowField hands it over: its member name and its role.
struct SnowFieldInfo {
  const char* name;
  FieldRole role;
};

// Calls f(info, grid) for every field of `state` (a SnowState or a const one), in declaration
// order: for what must treat every field alike (checks, exchanges between grid tiles).
template <class State, class F>
void forEachSnowField(State& state, F&& f) {
#define SNOW_VISIT_FIELD(member, view, Element, role, access, fill) f(SnowFieldInfo{#member, FieldRole::role}, state.member);
  SNOW_STATE_FIELDS(SNOW_VISIT_FIELD)
#undef SNOW_VISIT_FIELD
}

// What kernels see: plain pointers into the backend's storage (host or device memory), one for
// each field of snow_fields.h that has a view (the art-direction factors null where absent: 1
// everywhere), and the backend's scratch fields.
struct SnowFieldsView {
  int width = 0;
  int height = 0;
  float cellSizeXM = 1.f;
  float cellSizeYM = 1.f;
#define SNOW_VIEW_MEMBER(member, view, Element, role, access, fill) \
  SNOW_IF_VIEW(access, SNOW_VIEW_POINTER(access, Element) view = nullptr;)
  SNOW_STATE_FIELDS(SNOW_VIEW_MEMBER)
#undef SNOW_VIEW_MEMBER
  const float* editWeight = nullptr;  // a timeline edit's per-cell weight (null: 1 everywhere)
  // The wind bedforms' domain at their last step (null: no bedforms yet): the layered wind
  // transport and powder diffusion leave these cells to the slab model (its saltation and repose).
  const uint8_t* bedformActive = nullptr;
#define SNOW_SCRATCH_MEMBER(view, Element, extent) Element* view = nullptr;
  SNOW_SCRATCH_FIELDS(SNOW_SCRATCH_MEMBER)
#undef SNOW_SCRATCH_MEMBER

  SNOW_HD SNOW_INLINE bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  SNOW_HD SNOW_INLINE int index(int x, int y) const { return y * width + x; }
  SNOW_HD SNOW_INLINE bool isValid(int x, int y) const { return inside(x, y) && valid[index(x, y)] != 0; }
  SNOW_HD SNOW_INLINE float snowDepth(int i) const { return compacted[i] + stable[i] + unstable[i] + powder[i]; }
  // A = B + C + S + U + P: the snow-surface altitude used at run time.
  SNOW_HD SNOW_INLINE float surface(int i) const { return bedrock[i] + snowDepth(i); }
};

}  // namespace snow
