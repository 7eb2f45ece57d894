// Stage 5: the season on the chosen backend, frame days written beside it.
#include <iostream>

#include "core/format.h"
#include "frame_writer.h"
#include "progress.h"
#include "stages.h"

namespace snow {

SeasonReport runSeasonStage(const Scene& scene, const BakeOptions& options, int threads, SnowBackend& backend, SnowState& state,
                            const SeasonConfig& config, SeasonOutputs& outputs, OutputWriter& writer, std::ostream& log) {
  ProgressBar bar(log, "season", stderrIsTerminal() && &log == &std::cerr, options.progress);
  FrameWriter frames(writer, outputs.skiTracks ? &*outputs.skiTracks : nullptr, threads, options.framesBesideSeason);
  SeasonReport report = runSeason(
      backend, state, config, [&](double f) { bar.update(f); }, [&](double day, const SnowState& s) { frames.write(day, s); });
  frames.join();
  bar.finish();
  logSeasonReport(report, scene, config, backend.name(), log);
  return report;
}

}  // namespace snow
