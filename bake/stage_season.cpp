// Stage 5: the season on the chosen backend, its frame days handed to the frame writer.
#include <iostream>

#include "core/format.h"
#include "core/stop_request.h"
#include "frame_writer.h"
#include "progress.h"
#include "stages.h"

namespace snow {

SeasonReport runSeasonStage(const Scene& scene, SnowBackend& backend, SnowState& state, const SeasonConfig& config, FrameWriter& frames,
                            std::ostream& log) {
  progress().stage("season", 0.0);
  SeasonReport report = runSeason(
      backend, state, config,
      [&](double f) {
        throwIfStopRequested();  // once a simulated day
        progress().stage("season", f);
      },
      [&](double day, SnowState& s) {
        throwIfStopRequested();
        frames.write(day, s);
        progress().event("season", "frame", {{"day", jsonNumber(day)}});
      },
      [&](const AvalancheRecord& a) {  // as each comes to rest
        progress().event("season", "avalanche", {{"day", jsonNumber(a.day)}, {"released", a.released ? "true" : "false"},
                                                 {"released_m3", jsonNumber(a.releasedM3)}, {"simulated_s", jsonNumber(a.simulatedS)}});
      });
  frames.join();
  progress().stage("season", 1.0);
  logSeasonReport(report, scene, config, backend.name(), log);
  return report;
}

}  // namespace snow
