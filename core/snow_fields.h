// Every per-cell field of the simulation, declared once. SnowState's grids (snow_state.h), the
// kernels' SnowFieldsView pointers, ExecBackend's buffers (exec_backend.h: the CPU and CUDA
// backends' storage) with its upload and download, and the tests' views are all expanded from
// the lists below, so a field added here exists everywhere at once. Whatever must visit every
// field (a halo exchange between grid tiles, say) expands the same lists, or calls
// forEachSnowField (snow_state.h) on a state.
//
// Plain preprocessor lists (X-macros): nvcc and the host compilers read them alike, and this
// header includes nothing, so core's host+device headers stay free of TBB and CUDA host headers.
#pragma once

namespace snow {

// When a field travels between the host's SnowState and a backend.
enum class FieldRole {
  Terrain,       // the ground: uploaded with the state, never changed by a step (not downloaded)
  Evolved,       // the snow layers the season evolves: uploaded with the state, downloaded
  Record,        // accumulated for the bakers over the season: uploaded with the state, downloaded
  Static,        // precompute's, fixed for one wind and sun state: uploaded with the static fields
  ArtDirection,  // the scene's painted factors and masks, optional (an empty grid: absent, the
                 // kernels see null): uploaded with the static fields when present
  HostOnly,      // read by the host's runners only (optional): never uploaded
  BedformResult, // written by the bedform model into its own storage (optional): downloaded once bedforms ran
};

constexpr bool uploadedWithState(FieldRole r) {
  return r == FieldRole::Terrain || r == FieldRole::Evolved || r == FieldRole::Record;
}
constexpr bool uploadedWithStaticFields(FieldRole r) { return r == FieldRole::Static || r == FieldRole::ArtDirection; }
constexpr bool downloadedWithState(FieldRole r) { return r == FieldRole::Evolved || r == FieldRole::Record; }
// The backend keeps a buffer of the field's own.
constexpr bool heldByBackend(FieldRole r) { return uploadedWithState(r) || uploadedWithStaticFields(r); }
// SnowState::allocate leaves the field as it is (absent until the scene or a model fills it).
constexpr bool optionalField(FieldRole r) {
  return r == FieldRole::ArtDirection || r == FieldRole::HostOnly || r == FieldRole::BedformResult;
}
// The backend's buffer may be empty and the kernels' pointer null: an optional field, or a record
// field the season does not keep (SeasonConfig::recordFields), which the kernels then skip.
constexpr bool mayBeAbsent(FieldRole r) { return optionalField(r) || r == FieldRole::Record; }

// SNOW_STATE_FIELDS(X) calls X(member, view, Element, role, access, fill) for each field of
// SnowState, in declaration order:
//   member   SnowState's Grid<Element>
//   view     SnowFieldsView's pointer to it (unused, `none`, where access is None)
//   role     a FieldRole's name: when the field is uploaded and downloaded
//   access   the view's pointer: Mutable (Element*), Const (const Element*) or None (no pointer)
//   fill     the value SnowState::allocate gives the field; for an optional one, what its absence means
#define SNOW_STATE_FIELDS(X)                                                                       \
  /* B: terrain altitude (metres above sea level); C, S, U, P: metres of snow (paper §3.1) */     \
  X(bedrockM, bedrock, float, Terrain, Mutable, 0.f)                                               \
  X(compactedM, compacted, float, Evolved, Mutable, 0.f)                                           \
  X(stableM, stable, float, Evolved, Mutable, 0.f)                                                 \
  X(unstableM, unstable, float, Evolved, Mutable, 0.f)                                             \
  X(powderM, powder, float, Evolved, Mutable, 0.f)                                                 \
  /* avalanche flag (§6.1): 1 where unstable snow is in motion */                                  \
  X(snowMoving, moving, uint8_t, Evolved, Mutable, 0)                                              \
  /* 1 = simulated terrain, 0 = NODATA (no snow ever enters or leaves) */                          \
  X(validCell, valid, uint8_t, Terrain, Const, 1)                                                  \
  /* I = I_sun + I_sky + I_ind (hours of equivalent direct sun per day) */                         \
  X(exposureHours, exposure, float, Static, Const, 0.f)                                            \
  /* k_t*A + k_i*I: add the day's sea-level temperature T0 to get T */                             \
  X(temperatureBaseC, temperatureBase, float, Static, Const, 0.f)                                  \
  /* wind field W (east component; south component, +y = rows downward) */                         \
  X(windXMps, windX, float, Static, Const, 0.f)                                                    \
  X(windYMps, windY, float, Static, Const, 0.f)                                                    \
  X(windEffectZM, windEffectZ, float, Static, Const, 0.f) /* wind-effect surface altitude W_z */   \
  /* max(0, W . grad W_sz): where wind loading destabilises snow */                                \
  X(windLoadingMps2, windLoading, float, Static, Const, 0.f)                                       \
  /* metres of snow removed and deposited by wind transport, removed by melt, and taken away and  \
     left by avalanches (net per avalanche) */                                                     \
  X(windScourM, windScour, float, Record, Mutable, 0.f)                                            \
  X(windDepositM, windDeposit, float, Record, Mutable, 0.f)                                        \
  X(meltedM, melted, float, Record, Mutable, 0.f)                                                  \
  X(avalancheScourM, avalancheScour, float, Record, Mutable, 0.f)                                  \
  X(avalancheDepositM, avalancheDeposit, float, Record, Mutable, 0.f)                              \
  /* avalanches' peak flowing thickness (m, the moving snow's depth) and speed (m/s, the fastest  \
     pipe at the cell): over the current avalanche (reset at release) and over the season */      \
  X(avalanchePeakThicknessM, avalanchePeakThickness, float, Record, Mutable, 0.f)                  \
  X(avalanchePeakSpeedMps, avalanchePeakSpeed, float, Record, Mutable, 0.f)                        \
  X(avalancheSeasonPeakThicknessM, avalancheSeasonPeakThickness, float, Record, Mutable, 0.f)      \
  X(avalancheSeasonPeakSpeedMps, avalancheSeasonPeakSpeed, float, Record, Mutable, 0.f)            \
  /* Art direction (the scene's [multipliers], mapped from painted rasters): per-cell factors on  \
     a phenomenon, absent = 1 everywhere */                                                        \
  X(snowfallFactor, snowfallFactor, float, ArtDirection, Const, 1.f)                               \
  X(meltFactor, meltFactor, float, ArtDirection, Const, 1.f)                                       \
  X(windErosionFactor, windErosionFactor, float, ArtDirection, Const, 1.f)                         \
  X(avalancheReleaseFactor, none, float, HostOnly, None, 1.f) /* spontaneous release probability */ \
  X(skierSpawnFactor, none, float, HostOnly, None, 1.f)       /* where automatic skiers start */   \
  /* 1 where snow is never allowed (roads, buildings, rivers): the season treats those cells as   \
     outside the snow domain */                                                                    \
  X(noSnow, none, uint8_t, HostOnly, None, 0)                                                      \
  /* Wind bedforms (phenomena/bedforms.h): 1 where the slab-saltation model runs (absent:            \
     everywhere; the bedform kernels get it in BedformFields::mask), and the snow's cohesion      \
     there (0 loose .. 1 bonded; filled by download once bedforms ran) */                          \
  X(bedformMask, none, uint8_t, ArtDirection, None, 1)                                             \
  X(bedformCohesion, none, float, BedformResult, None, 0.f)

// What SNOW_SCRATCH_FIELDS' sizes are counted in.
enum class ScratchExtent {
  Cell,            // one value a cell, made with the state
  PowderShares,    // five a cell (toward +x, -x, +y, -y, and what the cell keeps; powder_diffusion.h),
                   // made with the state unless the executor keeps them in row buffers
  AvalancheCell,   // one a cell, made at the first avalanche
  AvalanchePipes,  // four a cell (signed pipe flows), made at the first avalanche
  AvalancheRows,   // two sets of seven a row (statistics for the host and the spans), made at the first avalanche
};

// SNOW_SCRATCH_FIELDS(X) calls X(view, Element, extent) for each of the backend's working
// fields, in the view only (SnowFieldsView's Element* `view`; ExecBackend's buffer `view`_):
#define SNOW_SCRATCH_FIELDS(X)                                                                     \
  /* snow volume changed by the last step (for the mass ledger) */                                \
  X(delta, float, Cell)                                                                            \
  /* |grad A| of the snow surface, taken before a per-cell pass that changes A, so the pass never \
     reads a neighbour that another thread is writing */                                           \
  X(surfaceSlope, float, Cell)                                                                     \
  /* for transport: wind transport's shares along x and y; powder diffusion's surface below the \
     powder in scratchSurface; the avalanche's outflow scales in scratchPowder */                  \
  X(scratchSurface, float, Cell)                                                                   \
  X(scratchPowder, float, Cell)                                                                    \
  X(powderFlow, float, PowderShares)                                                               \
  /* avalanches: four signed pipe flows per cell (m^3/s), U + P at release, U in double (the      \
     float layer is its rounding), two sets of row statistics (for the host and the spans) */ \
  X(flows, float, AvalanchePipes)                                                                  \
  X(avalancheBefore, float, AvalancheCell)                                                         \
  X(avalancheU, double, AvalancheCell)                                                             \
  /* 1 where snow crossed the cell's pipes in the last substep: dynamic friction, else static */  \
  X(avalancheFlowing, uint8_t, AvalancheCell)                                                      \
  X(rowStats, float, AvalancheRows)

constexpr bool madeWithState(ScratchExtent e) { return e == ScratchExtent::Cell || e == ScratchExtent::PowderShares; }
// Values of a scratch field on a grid of `cells` cells and `rows` rows.
constexpr unsigned long long scratchCount(ScratchExtent e, unsigned long long cells, unsigned long long rows,
                                          bool powderSharesInRows) {
  switch (e) {
    case ScratchExtent::Cell: return cells;
    case ScratchExtent::PowderShares: return powderSharesInRows ? 0 : 5 * cells;
    case ScratchExtent::AvalancheCell: return cells;
    case ScratchExtent::AvalanchePipes: return 4 * cells;
    case ScratchExtent::AvalancheRows: return 14 * rows;  // 2 * kAvalancheRowStats (avalanche_kernels.h)
  }
  return 0;
}

// Helpers for the lists' `access` column: SNOW_IF_VIEW(access, code) is `code` where the field
// has a view pointer; SNOW_VIEW_POINTER(access, Element) is that pointer's type.
#define SNOW_IF_VIEW(access, ...) SNOW_IF_VIEW_##access(__VA_ARGS__)
#define SNOW_IF_VIEW_Mutable(...) __VA_ARGS__
#define SNOW_IF_VIEW_Const(...) __VA_ARGS__
#define SNOW_IF_VIEW_None(...)
#define SNOW_VIEW_POINTER(access, Element) SNOW_VIEW_POINTER_##access(Element)
#define SNOW_VIEW_POINTER_Mutable(Element) Element*
#define SNOW_VIEW_POINTER_Const(Element) const Element*

}  // namespace snow
