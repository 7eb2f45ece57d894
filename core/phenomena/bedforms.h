// Wind bedforms (optional fine-scale wind mode): Werner's slab-saltation model (1995) with the
// improvements Cimbura (2022) collects -- Momiji's speed-up of the hop on crests and no erosion
// in the wind shadow, hops stepped cell by cell so that snow stops at obstacles -- extended to
// any wind direction without rotating the grid, and to snow by a per-cell cohesion (sintering)
// that grows with the snow's age and temperature.
//
// The loose powder of each cell in the bedform domain is counted in whole slabs of `slabM`
// metres (the rest, less than a slab, stays put as a residual): transport moves whole slabs, so
// the number of slabs is conserved exactly, and slab counts change by integer atomic additions,
// which give the same result in any order (any thread count, CPU or GPU).
//
// A round polls every cell once (non-repeated polling), in `batches` batches: a cell's batch is
// drawn from the counter-based RNG. In a batch, from a snapshot of the slab counts:
//   1. shadow: the fraction of each cell under the 15 deg shadow line of the surface upwind of it
//      (along its own wind direction, up to shadowLengthM);
//   2. saltation: a polled cell with a slab, not wholly in shadow, in wind above the threshold,
//      erodes one slab with probability (1 - shadow) x wind-erosion factor if |W| (1 - cohesion)
//      is above the threshold (cohesion raises the wind speed needed to lift snow); the slab hops
//      along the wind, cell by cell (a DDA walk through the cells it crosses), hop length
//      L = hopLengthM |W| / W_ref + Momiji's speed-up on the take-off height; a step up steeper
//      than the repose angle stops it (it lands before the obstacle); where a hop ends it lands
//      with probability shadow + (1 - shadow) p, p = p_s on snow or p_ns on bare ground, or hops on with the
//      wind of where it landed. A slab reaching a cell outside the domain (but on the terrain)
//      leaves the bedform model as powder of that cell; NODATA and the grid's edge (unless
//      periodic) are walls;
//   3. avalanching: pairwise relaxation over the four families of grid edges (each cell in at
//      most one edge of a family, so a family runs in parallel without conflicts): where the
//      surface step between two domain cells exceeds tan(repose) x spacing, whole slabs move
//      down until it does not, repeated until no edge moves.
// After every round (and at the end of a step without rounds) arrived slabs mix the cohesion
// they carry (their source cell's: snow keeps its age while it moves) into the cell's by count,
// and cohesion grows by sintering (fresh snowfall starts at 0):
//   dc/dt = sinteringPerDay x s / (s - min(T, 0))   (T the cell's temperature, s = sinteringScaleC:
//   full rate at 0 degC, half at -s, a third at -2s; warmer snow bonds faster)
// At the end of a step the slab counts go back to the powder layer.
//
// Preconditions: the bedform model's own fields (SNOW_BEDFORM_FIELDS, BedformStorage below),
// made at the first step after an upload; scratch: surfaceSlope (the domain, then each batch's
// snapshot surface) and delta (the slab counts' sum). Cells in the domain (`active`) are left
// by wind transport.
// Mass: conserved in whole slabs, exactly (BedformStepReport's slab ledger).
// Backend: SnowBackend::bedformStep and bedformCohesion (ExecBackend runs runBedformStep).
// Season: SeasonRun::addBedforms and bedformStep (core/season.cpp), hourly. Parameters:
// BedformParameters below (the scene's [bedforms]; validateBedformParameters and the
// measurements of a bedform field are in core/bedform_runs.h).
#pragma once
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "../util.h"
#include "bedform_kernels.h"

namespace snow {

struct BedformParameters {
  double slabM = 0.025;               // slab thickness (m of snow): the unit of transport
  double hopLengthM = 0.5;           // hop length at the reference wind speed
  double referenceWindMps = 10.0;
  double thresholdWindMps = 4.0;     // below it: no erosion, hops end
  double depositSnow = 0.4;          // p_s: landing probability on snow
  double depositBare = 0.9;          // p_ns: on bare (slab-free) ground
  double shadowAngleDeg = 15.0;
  double shadowLengthM = 10.0;       // how far upwind the shadow test looks
  double reposeAngleDeg = 30.0;
  double speedupLinear = 0.0;        // Momiji's C1 (hop metres per metre above the mean; 1.2 = Momiji's 0.4 cells a slab at Werner's scale)
  double speedupQuadraticPerM = 0.0;   // Momiji's C2 (0.018 = Momiji's 0.002)
  double maxSlopeDeg = 20.0;         // bedforms only where the snow bed is at most this steep
  double sinteringPerDay = 0.5;      // cohesion gained per day at 0 degC
  double sinteringScaleC = 10.0;     // rate halves at -scale degC
  double roundsPerHour = 10.0;        // polling rounds (each cell once) per hour of the season
  int batches = 4;                   // batches a round
  int maxHops = 64;
  bool periodic = false;             // wrap around (test windows only)
};

namespace bedform {
inline double tanDeg(double d) { return std::tan(d * kPi / 180.0); }
}  // namespace bedform

inline BedformArgs makeBedformArgs(const BedformParameters& p, double dtDays, int rounds, uint64_t roundBase, uint64_t seed,
                                   double seaLevelTemperatureC) {
  BedformArgs a;
  a.dtDays = static_cast<float>(dtDays);
  a.rounds = rounds;
  a.batches = p.batches;
  a.roundBase = roundBase;
  a.seed = seed;
  a.slabM = static_cast<float>(p.slabM);
  a.hopLengthM = static_cast<float>(p.hopLengthM);
  a.referenceWindMps = static_cast<float>(p.referenceWindMps);
  a.thresholdWindMps = static_cast<float>(p.thresholdWindMps);
  a.depositSnow = static_cast<float>(p.depositSnow);
  a.depositBare = static_cast<float>(p.depositBare);
  a.tanShadow = static_cast<float>(bedform::tanDeg(p.shadowAngleDeg));
  a.shadowLengthM = static_cast<float>(p.shadowLengthM);
  a.tanRepose = static_cast<float>(bedform::tanDeg(p.reposeAngleDeg));
  a.speedupLinear = static_cast<float>(p.speedupLinear);
  a.speedupQuadraticPerM = static_cast<float>(p.speedupQuadraticPerM);
  a.tanMaxSlope = static_cast<float>(bedform::tanDeg(p.maxSlopeDeg));
  a.sinteringPerDay = static_cast<float>(p.sinteringPerDay);
  a.sinteringScaleC = static_cast<float>(p.sinteringScaleC);
  a.seaLevelTemperatureC = static_cast<float>(seaLevelTemperatureC);
  a.maxHops = p.maxHops;
  a.periodic = p.periodic;
  return a;
}

// What a bedform step did.
struct BedformStepReport {
  long long slabsEroded = 0;    // slabs lifted by the wind
  long long slabsAvalanched = 0;  // slab moves of the repose relaxation
  long long domainCells = 0;
  // The slab ledger: slabs in the domain after the preparation, and after the step (those
  // that left the domain included); equal, exactly, when transport conserves mass.
  long long slabsBefore = 0, slabsAfter = 0;
  bool reposeConverged = true;  // every domain edge within the repose angle at the end
};

// The bedform model's fields on an Exec's storage; `ready` once made (at the first step after
// an upload).
template <class Exec>
struct BedformStorage {
  template <class T>
  using Buffer = typename Exec::template Buffer<T>;
#define SNOW_BEDFORM_BUFFER(member, Element, start) Buffer<Element> member;
  SNOW_BEDFORM_FIELDS(SNOW_BEDFORM_BUFFER)
#undef SNOW_BEDFORM_BUFFER
  bool ready = false;

  BedformFields fields(const uint8_t* mask) {
    BedformFields f;
#define SNOW_BEDFORM_POINTER(member, Element, start) f.member = member.data();
    SNOW_BEDFORM_FIELDS(SNOW_BEDFORM_POINTER)
#undef SNOW_BEDFORM_POINTER
    f.mask = mask;
    return f;
  }
};

// Throws std::invalid_argument for arguments no step can run with.
inline void checkBedformArgs(const BedformArgs& args, int width, int height) {
  if (args.periodic && (width % 2 != 0 || height % 2 != 0))  // the repose edge families need even sizes to wrap
    throw std::invalid_argument("bedforms: a periodic grid needs an even width and height");
  if (!(args.slabM > 0.f) || args.batches < 1 || args.rounds < 0)
    throw std::invalid_argument("bedforms: slab thickness, batches and rounds must be positive");
}

// Each field as its `start` says (the powder layer from `powderM`, the backend's buffer).
template <class Exec, class PowderBuffer>
void makeBedformStorage(Exec& exec, BedformStorage<Exec>& bed, PowderBuffer& powderM, size_t cells) {
  std::vector<float> powder;
  exec.download(powderM, powder);  // the snow already there is not fresh
#define SNOW_MAKE_BEDFORM_FIELD(member, Element, start)                                                          \
  if constexpr (BedformStart::start == BedformStart::Zero) exec.upload(bed.member, std::vector<Element>(cells)); \
  else if constexpr (BedformStart::start == BedformStart::Powder) exec.upload(bed.member, powder);
  SNOW_BEDFORM_FIELDS(SNOW_MAKE_BEDFORM_FIELD)
#undef SNOW_MAKE_BEDFORM_FIELD
  bed.ready = true;
}

// Slabs in the domain and those that left it: conserved by a step.
template <class Exec>
long long bedformSlabTotal(Exec& exec, BedformStorage<Exec>& bed) {
  std::vector<int> slabs, exported;
  exec.download(bed.slabs, slabs);
  exec.download(bed.exported, exported);
  long long total = 0;
  for (size_t i = 0; i < slabs.size(); ++i) total += static_cast<long long>(slabs[i]) + exported[i];
  return total;
}

// Relaxation sweeps over the four edge families until no edge moves (true), at most maxSweeps;
// `relaxed` carries the relaxation's move counter from sweep to sweep.
template <class Exec>
bool relaxBedforms(Exec& exec, BedformStorage<Exec>& bed, const SnowFieldsView& v, const BedformFields& f, BedformArgs& a,
                   int maxSweeps, unsigned long long& relaxed) {
  const int w = v.width, h = v.height;
  for (int sweep = 0; sweep < maxSweeps; ++sweep) {
    for (int family = 0; family < 4; ++family) {
      a.family = family;
      if (family < 2) exec.forEachCell((w + 1) / 2, h, BedformReposeKernel{v, f, a});
      else exec.forEachCell(w, (h + 1) / 2, BedformReposeKernel{v, f, a});
    }
    unsigned long long now = 0;
    exec.downloadRange(bed.counters, 1, 1, &now);
    if (now == relaxed) return true;
    relaxed = now;
  }
  return false;
}

// Polling round r of a step: its batches (snapshot, shadow, saltation, relaxation), then the
// round's share of the cohesion.
template <class Exec>
void bedformRound(Exec& exec, BedformStorage<Exec>& bed, const SnowFieldsView& v, const BedformFields& f,
                  const BedformArgs& args, int r, BedformArgs& a, unsigned long long& relaxed) {
  const int w = v.width, h = v.height;
  a.round = args.roundBase + static_cast<uint64_t>(r);
  for (int b = 0; b < args.batches; ++b) {
    a.batch = b;
    exec.forEachCell(w, h, BedformSnapshotKernel{v, f, a.slabM, v.surfaceSlope});
    a.maxSurface = exec.maxValue(v.surfaceSlope, v.valid, w, h);
    exec.forEachCell(w, h, BedformShadowKernel{v, f, a});
    exec.forEachCell(w, h, BedformSaltationKernel{v, f, a});
    relaxBedforms(exec, bed, v, f, a, 16, relaxed);
  }
  BedformArgs c = a;
  c.dtDays = args.dtDays / static_cast<float>(args.rounds);
  exec.forEachCell(w, h, BedformCohesionKernel{v, f, c});
}

// One bedform step on storage made for this state (makeBedformStorage; v.bedformActive its
// `active` field): the preparation, `args.rounds` polling rounds, the final relaxation, the
// cohesion and the slabs back into the powder. `mask` is the scene's (null: whole terrain).
template <class Exec>
BedformStepReport runBedformStep(Exec& exec, const SnowFieldsView& v, BedformStorage<Exec>& bed, const uint8_t* mask,
                                 const BedformArgs& args) {
  const int w = v.width, h = v.height;
  exec.upload(bed.counters, std::vector<unsigned long long>(4, 0ull));
  const BedformFields f = bed.fields(mask);
  BedformArgs a = args;
  exec.forEachCell(w, h, BedformPrepareKernel{v, f, a});
  BedformStepReport report;
  const double cells = exec.sum(v.surfaceSlope, v.valid, w, h);
  report.domainCells = static_cast<long long>(cells);
  a.meanSlabs = cells > 0 ? static_cast<float>(exec.sum(v.delta, v.valid, w, h) / cells) : 0.f;
  report.slabsBefore = bedformSlabTotal(exec, bed);
  unsigned long long relaxed = 0;
  if (report.domainCells > 0) {
    for (int r = 0; r < args.rounds; ++r) bedformRound(exec, bed, v, f, args, r, a, relaxed);
    report.reposeConverged = relaxBedforms(exec, bed, v, f, a, 1 << 16, relaxed);
  }
  report.slabsAfter = bedformSlabTotal(exec, bed);
  BedformArgs c = a;
  c.dtDays = args.rounds > 0 ? 0.f : args.dtDays;  // the rest of the arrivals; sintering if no round ran
  exec.forEachCell(w, h, BedformCohesionKernel{v, f, c});
  exec.forEachCell(w, h, BedformFinishKernel{v, f, a});
  unsigned long long counters[2] = {0, 0};
  exec.downloadRange(bed.counters, 0, 2, counters);
  exec.finish();
  report.slabsEroded = static_cast<long long>(counters[0]);
  report.slabsAvalanched = static_cast<long long>(counters[1]);
  return report;
}

}  // namespace snow
