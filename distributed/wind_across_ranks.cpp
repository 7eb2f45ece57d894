#include "wind_across_ranks.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/util.h"
#include "halo_exchange.h"
#include "precompute/wind_system.h"
#include "precompute/wind_timeline.h"

namespace snow::dist {

namespace {

// Whether any valid owned cell's component is positive, and whether any is negative.
struct Signs {
  bool positive = false, negative = false;
};

double largestOverRanks(const Communicator& comm, double mine) {
  const std::vector<double> all = comm.allGather({mine});
  return *std::max_element(all.begin(), all.end());
}

}  // namespace

bool solveWindOnLocalGrid(const Communicator& comm, const Decomposition& d, const Grid<float>& altitude, const Grid<uint8_t>& valid,
                          const GridSpec& spec, const WindState& state, const ModelParameters& p, const WindSolverOptions& o,
                          WindField& out, Grid<float>& loading) {
  if (o.ordering != WindOrdering::UpwindSweep || o.maxIterations < 2) return false;  // the sweep's fixed point alone
  const auto t0 = WallClock::now();
  const CellRect local = d.local(comm.rank()), owned = d.owned(comm.rank());
  Grid<float> freeX, freeY;
  computeFreeStream(altitude, valid, spec, state, p, freeX, freeY, local);
  // The free stream's direction over every rank's owned cells.
  Signs sx, sy;
  for (int y = owned.y0; y < owned.y1; ++y)
    for (int x = owned.x0; x < owned.x1; ++x) {
      const float vx = freeX.values()[local.offsetOf(x, y)], vy = freeY.values()[local.offsetOf(x, y)];
      sx.positive |= vx > 0.f, sx.negative |= vx < 0.f, sy.positive |= vy > 0.f, sy.negative |= vy < 0.f;
    }
  const std::vector<double> signs = comm.allGather({double(sx.positive), double(sx.negative), double(sy.positive), double(sy.negative)});
  Signs all[2];
  for (size_t r = 0; r < signs.size(); r += 4)
    all[0].positive |= signs[r] != 0, all[0].negative |= signs[r + 1] != 0, all[1].positive |= signs[r + 2] != 0,
        all[1].negative |= signs[r + 3] != 0;
  if ((all[0].positive && all[0].negative) || (all[1].positive && all[1].negative)) return false;
  // The single process's first sweep order (the sign of the stream's sum, which one sign decides).
  const bool xf = !all[0].negative, yf = !all[1].negative;

  computeWindVectors(altitude, valid, spec, state, p, out.windXMps, out.windYMps, local);
  const WindSystem sys(altitude, valid, spec, local, out.windXMps, out.windYMps, freeX, freeY, p.windCapDecelerationMps2);
  std::vector<double> wz, wsz;
  sys.initialise(wz, wsz);
  const HaloPlan plan = haloPlan(d, comm.rank());
  const int most = d.columns + d.rows + 1;
  int rounds = 0;
  for (double moved = 1.0; moved != 0.0; ++rounds) {
    if (rounds == most) throw std::logic_error("solveWindOnLocalGrid: the sweeps did not settle in " + std::to_string(most) + " rounds");
    moved = sweepCells(sys, owned, xf, yf, wz, wsz);
    exchangeHalo(comm, d, plan, wz.data(), sizeof(double));
    exchangeHalo(comm, d, plan, wsz.data(), sizeof(double));
    moved = largestOverRanks(comm, moved);
  }
  // The single process's statistics: its first sweep's largest change (from W_z = A, W_sz =
  // W . grad A), then a sweep that moves nothing, and the residual at the solution.
  double first = 0.0;
  for (int y = owned.y0; y < owned.y1; ++y)
    for (int x = owned.x0; x < owned.x1; ++x) {
      if (!valid(x, y)) continue;
      const size_t i = local.offsetOf(x, y);
      first = std::max(first, std::max(std::abs(wz[i] - static_cast<double>(altitude(x, y))), std::abs(wsz[i] - sys.groundSpeed(x, y))));
    }
  first = largestOverRanks(comm, first);
  WindSolveStats& st = out.stats;
  st.ordering = windOrderingName(o.ordering);
  st.converged = first <= o.toleranceM || o.maxIterations > 1;
  st.iterations = first <= o.toleranceM || o.maxIterations <= 1 ? 1 : 2;
  st.lastUpdate = st.iterations == 1 ? first : 0.0;
  st.residual = largestOverRanks(comm, residualOver(sys, owned, wz, wsz));
  out.windEffectZM.resize(local.width(), local.height());
  out.verticalSpeedMps.resize(local.width(), local.height());
  for (size_t i = 0; i < wz.size(); ++i) {
    out.windEffectZM.values()[i] = static_cast<float>(wz[i]);
    out.verticalSpeedMps.values()[i] = static_cast<float>(wsz[i]);
  }
  // The loading of the owned cells (their neighbours are local), the halo's from its owners.
  loading = windLoading(out, valid, spec, local, owned);
  exchangeHalo(comm, d, plan, loading.data(), sizeof(float));
  st.seconds = elapsedSeconds(t0);
  return true;
}

}  // namespace snow::dist
