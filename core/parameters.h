// Every constant of the model paper's Table 2 (Cordonnier et al. 2018), in SI-style units named
// in the member names, with the paper's defaults; plus the event frequencies of §3.2 and §7.4.
// The scene file overrides any of them under [parameters] by the snake_case key listed in
// parameterTable() (core/parameters.cpp), which also holds each one's valid range.
#pragma once
#include <string>
#include <vector>

namespace snow {

// How moving snow flows (season.avalanche_flow): a depth-averaged shallow-water layer whose
// momentum moves with it, or the paper's pipes (core/phenomena/avalanches.h).
enum class AvalancheFlow { ShallowWater, Pipes };

struct ModelParameters {
  // --- §4.1 temperature and sun exposure
  double lapseRateCPerM = -0.01;             // k_t (k_r in the text): temperature change with altitude
  double sunWarmingCPerHour = 0.41;          // k_i: temperature rise per hour of direct daylight
  double directSunWeightHours = 0.9;         // k_sun
  double skyAmbientWeightHours = 0.1;        // k_sky
  double indirectSunWeightHours = 0.9;       // k_ind
  // --- §4.2 wind
  double venturiPerM = 1e-3;                 // k_venturi: wind speed-up per metre of altitude
  double terrainWindEffect = 0.5;            // k_terrain: redirection along the slope (dimensionless)
  double seaLevelWindSpeedMps = 10.0;        // |W|: default when the weather timeline gives none
  double windCapDecelerationMps2 = 0.7;      // c: fall of the wind-effect surface's vertical speed
  // --- §5.1 snowfall
  double snowfallRatePerDay = 1e-4;          // k_snow: metres of snow per metre above A_0precip per day
  double rainSnowLimitM = 1000.0;            // A_0precip (site dependent; the paper leaves it to the user)
  double powderFromPrecipitation = 5.0;      // k_powdery
  double powderCriticalSlopeMin = 0.5;       // s_c0 (slope as rise over run)
  double powderCriticalSlopePerC = 5e-2;     // k_sc,powdery (per degree C below T_0powdery)
  double powderSlopeTemperatureC = -10.0;    // T_0powdery
  double unstableFromPrecipitation = 1.0;    // k_unstable
  double unstableCriticalSlope = 0.3;        // s_U
  // --- §5.2 state changes
  double meltRateMPerDayPerC = 0.01;         // k_melt
  double meltThresholdC = 0.0;               // T_0melt
  double warmTemperatureC = 5.0;             // T_warm
  double coolTemperatureC = -5.0;            // T_cool
  double freezeTemperatureC = -20.0;         // T_freeze
  double instabilityByWarmthMPerDay = 1.0;   // k_w (Table 2 prints 1e4: an all-or-nothing switch; docs/models/season.md)
  double stabilityByColdMPerDay = 0.3;       // k_c (Table 2: 1e4): a storm's unstable snow halves in ~2 days at T_cool
  // --- §5.3 powder diffusion and §5.4 wind transport
  double diffusionRestSlope = 0.5;           // s_d0
  double diffusionRatePerDay = 0.5;          // k_m, defined at the paper's 10 m cells (see powder_diffusion.h)
  double windErosionRateMPerSPerDay = 0.1;   // k_erosion (read as m s day^-1; see phenomena/wind_transport.h)
  double windInstabilityPerMps2 = 0.05;      // not in Table 2: S -> U per day per m/s^2 of wind loading (§5.4)
  double windShadowToleranceM = 0.1;         // W_z this far above the snow: sheltered from erosion
  // --- §6.1 avalanches
  double snowDensityKgPerM3 = 500.0;         // rho (0.5 g cm^-3); cancels in a = dP / (rho dx)
  double gravityMps2 = 9.8;                  // g
  double avalancheRestAngleDeg = 30.0;       // theta_c
  double snowViscosityPerS2 = 5e-4;          // k_viscous: damping rate k_v U (U in metres) of wet flow
  // --- §6.2 ski tracks
  double skierTargetSlopeDeg = 30.0;         // s_t
  double trackAmplitudeM = 5.0;              // a
  double trackFrequencyPerM = 0.01;          // f: the lowest turn frequency where the terrain is steeper than s_t (see ski_runs.h)
  // --- §6.2 skiers, beyond Table 2
  double skiersPerHour = 1.0;                // automatic skiers while skiing happens (the paper: about one an hour)
  double skiHoursPerDay = 7.0;               // hours of skiing a day
  double skiMinSnowM = 0.3;                  // skiers go only where the snow is at least this deep
  double skiLookaheadM = 30.0;               // the window a skier picks its next target cell in
  double skiSlopeToleranceDeg = 10.0;        // sigma of f(|s_n - s_t|) = exp(-((s_n - s_t)/sigma)^2)
  double skiSteering = 0.5;                  // share of the way the heading turns toward the target each step
  double skiCompactionM = 0.05;              // snow a skier turns U -> S (or S -> C) in each cell entered
  double skiTriggerFactor = 0.1;             // how much a skier raises a cell's avalanche probability
  double skiTrackDepthM = 0.1;               // depth of a fresh ski track
  double skiTrackWidthM = 1.2;               // width of a ski track
  // --- §6.1 avalanches, beyond Table 2
  double avalancheDryTemperatureC = -10.0;    // alpha = 1 (granular) at or below
  double avalancheWetTemperatureC = 0.0;      // alpha = 0 (viscous) at or above
  double avalancheWetGranularFraction = 0.2;  // alpha of wet snow: the granular friction it keeps
  double avalancheDynamicFrictionDeg = 14.0;  // delta: Coulomb friction angle while snow flows (theta_c: to start and stop)
  double avalancheTurbulenceMps2 = 500.0;     // xi: Voellmy's turbulent drag g s^2 / (xi h); 0: none
                                              // (both fitted to AvaFrame com1DFA: docs/models/avalanches.md)
  double avalancheRatePerKm2PerDay = 1.0 / 7.0;  // spontaneous releases: about one a week per km^2
  double avalancheReachMPerM = 50.0;          // release reach: metres per metre of unstable snow at the rupture
  double avalancheMinUnstableM = 0.05;        // no release where U is thinner
  double avalancheStopSpeedMps = 0.05;        // at rest when no pipe flows faster
  double avalancheStopThicknessM = 0.05;      // h_stop: moving snow this thin does not flow (it is at rest)
  double avalancheStopEnergyFraction = 0.001;  // at rest when the kinetic energy falls below this share of its peak (com1DFA's kind of criterion; its stopCrit is 0.01)
  double avalancheMaxDurationS = 600.0;       // cap on one avalanche's simulated time
  double avalancheStepS = 0.1;                // simulated time of one avalanche step (temporal zoom)
  // --- §3.2 / §7.4 event frequencies (mean events per simulated day) and durations
  double snowfallStartsPerDay = 1.0 / 7.0;   // a snowfall starts once a week on average
  double snowfallMeanDurationDays = 3.0;     // and lasts three days on average
  double snowfallStepsPerDay = 2.0;
  double stateChangeStepsPerDay = 2.0;       // delta t_m = 0.5 day
  double diffusionStepsPerDay = 2.0;
  double windTransportStepsPerDay = 2.0;
  // Length that turns k_m (a share per day) into a creep speed: powder moves k_m * L_d metres a
  // day per unit of slope above its rest slope, whatever the cell size (see powder_diffusion.h).
  double diffusionLengthM = 400.0;
  // A powder film thinner than this does not slide (a dusting sticks to rock; it also keeps the
  // diffusion's work to where there is snow to move).
  double diffusionMinDepthM = 0.001;
  // Not a number, so not in parameterTable(): the scene's season.avalanche_flow.
  AvalancheFlow avalancheFlow = AvalancheFlow::Pipes;
};

// One row per parameter: the scene-file key, its member, its unit and its valid range.
struct ParameterInfo {
  const char* key;
  double ModelParameters::*member;
  const char* unit;
  double minValue;
  double maxValue;
  const char* description;
};

const std::vector<ParameterInfo>& parameterTable();
const ParameterInfo* findParameter(const std::string& key);

}  // namespace snow
