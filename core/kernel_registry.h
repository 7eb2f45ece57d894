// The continuous season steps a backend runs (one per phenomenon module that needs no fixture of
// its own), by name. tests/gpu/backend_parity.h runs each of them, and the steps that do need a
// fixture (timeline edits, avalanches, bedforms, skiers), on two backends from the same state and
// compares the results: the GPU binary CUDA against the serial reference, tests/backend_test.cpp
// the TBB backend. A step added here is checked on every backend without writing a new test.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "backend.h"

namespace snow {

struct RegisteredStep {
  std::string name;
  // Runs the step once; returns its mass-ledger value (m^3) where it has one, else 0.
  std::function<double(SnowBackend&)> run;
};

inline std::vector<RegisteredStep> registeredSteps(const ModelParameters& p, const WeatherState& weather) {
  return {
      {"snowfall", [p, weather](SnowBackend& b) { return b.snowfall(makeSnowfallArgs(p, 0.5, weather)); }},
      {"melt", [p, weather](SnowBackend& b) { return b.melt(makeMeltArgs(p, 0.5, weather)); }},
      {"stability change",
       [p, weather](SnowBackend& b) {
         b.stabilityChange(makeStabilityArgs(p, 0.5, weather));
         return 0.0;
       }},
      {"wind transport",
       [p](SnowBackend& b) {
         b.windTransport(makeWindTransportArgs(p, 0.5));
         return 0.0;
       }},
      {"powder diffusion",
       [p](SnowBackend& b) {
         b.powderDiffusion(makePowderDiffusionArgs(p, 0.5));
         return 0.0;
       }},
  };
}

}  // namespace snow
