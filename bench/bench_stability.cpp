// `snowbake bench --stage stability`: the study behind the stability rates' defaults
// (core/stability_study.h, docs/models/season.md): over k_c and k_w from 1e-3 to 1e4 m/day, the
// half-life of a storm's unstable snow at each temperature, and how fast warmth destabilises.
#include <sstream>

#include "bench_suite.h"
#include "core/stability_study.h"

namespace snow {

namespace {

constexpr auto fmt = benchFormat;
constexpr double kSlope = 0.7;      // 35 degrees: release terrain
constexpr double kStormM = 0.4;     // a 3-day storm's snow at 2300 m (k_snow 1e-4 m/m/day, A_0precip 1000 m)
constexpr double kHorizonDays = 30.0;

std::string daysText(const StabilityOutcome& r) { return r.reached ? fmt("%.1f", r.days) : "> " + fmt("%.0f", kHorizonDays); }

}  // namespace

std::string stabilityBench(const BenchOptions& o, std::ostream& log, int) {
  std::ostringstream table, csv;
  const std::vector<double> rates{1e-3, 1e-2, 0.1, 0.3, 1.0, 10.0, 100.0, 1e4};
  const std::vector<double> temperatures{-25, -20, -10, -5, 0, 2, 5};
  const ModelParameters defaults;
  table << "Stability change (§5.2) on a 35° plane: days until half of a storm's " << fmt("%.1f", kStormM)
        << " m of unstable snow (over as much stable snow) has become stable, per k_c (k_w = " << fmt("%g", defaults.instabilityByWarmthMPerDay)
        << " m/day), and until half of " << fmt("%.1f", kStormM) << " m of stable snow has become unstable, per k_w (k_c = "
        << fmt("%g", defaults.stabilityByColdMPerDay) << " m/day); T_warm 5, T_cool -5, T_freeze -20 °C, steps of "
        << fmt("%.1f", 1.0 / defaults.stateChangeStepsPerDay) << " day\n\n| k (m/day) | part |";
  for (double t : temperatures) table << " " << fmt("%+.0f °C", t) << " |";
  table << "\n|---|---|";
  for (size_t k = 0; k < temperatures.size(); ++k) table << "---|";
  table << "\n";
  csv << "k_m_per_day,part,temperature_c,days,reached\n";
  for (const bool cold : {true, false})
    for (double k : rates) {
      ModelParameters p;
      (cold ? p.stabilityByColdMPerDay : p.instabilityByWarmthMPerDay) = k;
      const bool isDefault = k == (cold ? defaults.stabilityByColdMPerDay : defaults.instabilityByWarmthMPerDay);
      table << "| " << fmt("%g", k) << (isDefault ? " (default)" : "") << " | " << (cold ? "U halves (k_c)" : "S halves (k_w)") << " |";
      for (double t : temperatures) {
        const StabilityOutcome r = cold ? unstableHalfLife(p, t, kSlope, kStormM, kHorizonDays) : stableHalfLife(p, t, kSlope, kStormM, kHorizonDays);
        table << " " << daysText(r) << " |";
        csv << k << "," << (cold ? "unstable_half_life" : "stable_half_life") << "," << t << "," << r.days << "," << r.reached << "\n";
      }
      table << "\n";
    }
  log << "  stability study done\n";
  table << "\nTable 2's 1e4 m/day turns any layer over within one step; the defaults aim at a half-life of 1–3 days at T_cool and "
           "destabilisation within 1–2 days above 0 °C.\n";
  writeCsvFile(o, "stability.csv", csv.str(), table);
  return table.str();
}

}  // namespace snow
