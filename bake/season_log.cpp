// The season's report in the log: events, per-phenomenon steps and times, every avalanche, edit
// and user skier, and the mass balance.
#include <algorithm>
#include <iomanip>

#include "core/format.h"
#include "stages.h"

namespace snow {
namespace {

void logAvalanches(const SeasonReport& report, const Scene& scene, std::ostream& log) {
  for (const AvalancheRecord& a : report.avalanches) {
    log << "  avalanche day " << fixed(a.day, 2) << " at cell (" << a.ruptureX << ", " << a.ruptureY << ")" << (a.user ? " (user)" : "");
    if (!a.released) {
      log << ": not released, " << a.why << "\n";
      continue;
    }
    log << " on a " << fixed(a.ruptureSlopeDeg, 1) << " deg slope: " << a.releaseCells << " cells released (" << fixed(a.releasedM3, 0) << " m^3), runout " << fixed(a.runoutM, 0)
        << " m, fall " << fixed(a.fallHeightM, 0) << " m, " << a.steps << " steps of " << fixed(scene.params.avalancheStepS, 2) << " s, "
        << fixed(a.secondsPerStep() * 1e3, 3) << " ms a step; " << a.why << "\n";
  }
}

void logSkiers(const SeasonReport& report, std::ostream& log) {
  if (report.skiers.empty()) return;
  int users = 0, triggered = 0, skied = 0;
  double length = 0.0;
  for (const SkierRecord& k : report.skiers) {
    users += k.user, triggered += k.triggered, skied += k.cells > 0;
    length += k.lengthM;
  }
  log << "  skiers: " << report.skiers.size() << " (" << users << " from the scene), " << skied << " skied, " << fixed(length / 1000.0, 1)
      << " km in all, " << triggered << " set off an avalanche\n";
  for (const SkierRecord& k : report.skiers)
    if (k.user)
      log << "  skier day " << fixed(k.day, 2) << " from cell (" << k.startX << ", " << k.startY << "): " << k.cells << " cells, "
          << fixed(k.lengthM, 0) << " m, drop " << fixed(k.dropM, 0) << " m; " << k.why << "\n";
}

// Spontaneous releases counted by the snowfall they follow (from its start to the next one's).
void logReleasesPerStorm(const SeasonReport& report, const SeasonConfig& config, std::ostream& log) {
  const auto& storms = config.weather.snowfallPeriods;
  if (storms.empty() || report.avalancheTries == 0) return;
  log << "  spontaneous releases per storm:";
  for (size_t k = 0; k < storms.size(); ++k) {
    const double end = k + 1 < storms.size() ? storms[k + 1].startDay : 1e300;
    int n = 0;
    double lo = 90.0, hi = 0.0;
    for (const AvalancheRecord& a : report.avalanches)
      if (!a.user && a.released && a.day >= storms[k].startDay && a.day < end)
        ++n, lo = std::min(lo, a.ruptureSlopeDeg), hi = std::max(hi, a.ruptureSlopeDeg);
    log << " day " << fixed(storms[k].startDay, 1) << ": " << n;
    if (n > 0) log << " (slopes " << fixed(lo, 0) << "-" << fixed(hi, 0) << " deg)";
    log << (k + 1 < storms.size() ? "," : "\n");
  }
}

}  // namespace

void logSeasonReport(const SeasonReport& report, const Scene& scene, const SeasonConfig& config, const std::string& backendName,
                     std::ostream& log) {
  log << "season: " << fixed(scene.days, 0) << " days, " << report.events << " events on " << backendName << " ("
      << fixed(report.seconds, 2) << " s)\n";
  for (const auto& p : report.phenomena)
    log << "  " << std::left << std::setw(24) << p.name << std::right << std::setw(6) << p.steps << " steps"
        << (p.skippedSteps ? " (" + std::to_string(p.skippedSteps) + " skipped: " + p.skippedWhy + ")" : std::string()) << "  "
        << fixed(p.seconds, 3) << " s\n";
  logAvalanches(report, scene, log);
  for (const EditRecord& e : report.edits)
    log << "  " << e.label << ": " << std::scientific << std::setprecision(4) << e.volumeM3 << std::defaultfloat << " m^3\n";
  if (report.noSnowRemovedM3 > 0.0)
    log << "  no-snow mask: " << std::scientific << std::setprecision(4) << report.noSnowRemovedM3 << std::defaultfloat
        << " m^3 of initial snow removed\n";
  if (report.avalancheTries > 0)
    log << "  spontaneous avalanche events: " << report.avalancheTries << " (" << report.avalancheTryCalls << " tries with the retries, "
        << report.avalancheSnapshotsKept << " on a kept snapshot; " << fixed(report.avalancheTrySeconds, 2) << " s)\n";
  logReleasesPerStorm(report, config, log);
  if (config.bedforms)
    log << "  wind bedforms: " << report.bedforms.domainCells << " cells, " << report.bedforms.rounds << " rounds, "
        << report.bedforms.slabsEroded << " slabs lifted, " << report.bedforms.slabsAvalanched << " slab moves by avalanching, "
        << report.bedforms.calmSteps << " calm hours; "
        << (report.bedforms.atRest ? "at rest (within the repose angle)" : "NOT at rest after the relaxation cap") << "\n";
  logSkiers(report, log);
  log << "  snow: " << std::scientific << std::setprecision(4) << report.final.totalM3() << " m^3 (added " << report.snowfallAddedM3
      << ", melted " << report.meltRemovedM3 << "), mass balance error " << report.massBalanceRelativeError() << std::defaultfloat << "\n";
}

}  // namespace snow
