#include "parameters.h"


namespace snow {

namespace {
using P = ModelParameters;
}  // namespace

const std::vector<ParameterInfo>& parameterTable() {
  static const std::vector<ParameterInfo> table = {
      {"lapse_rate_c_per_m", &P::lapseRateCPerM, "degC/m", -0.1, 0.1, "k_t: temperature change per metre of altitude"},
      {"sun_warming_c_per_hour", &P::sunWarmingCPerHour, "degC/h", 0.0, 10.0, "k_i: warming per hour of direct sun"},
      {"direct_sun_weight_hours", &P::directSunWeightHours, "h", 0.0, 24.0, "k_sun: weight of the direct sun exposure I_sun (docs/precompute.md)"},
      {"sky_ambient_weight_hours", &P::skyAmbientWeightHours, "h", 0.0, 24.0, "k_sky: weight of the sky exposure I_sky"},
      {"indirect_sun_weight_hours", &P::indirectSunWeightHours, "h", 0.0, 24.0, "k_ind: weight of the indirect (reflected) exposure I_ind"},
      {"venturi_per_m", &P::venturiPerM, "1/m", 0.0, 0.1, "k_venturi: wind speed-up per metre of altitude"},
      {"terrain_wind_effect", &P::terrainWindEffect, "-", 0.0, 1.0, "k_terrain: wind redirection along slopes"},
      {"sea_level_wind_speed_mps", &P::seaLevelWindSpeedMps, "m/s", 0.0, 100.0, "|W|: default wind speed at sea level"},
      {"wind_cap_deceleration_mps2", &P::windCapDecelerationMps2, "m/s^2", 1e-4, 100.0, "c: wind-shadow cap curvature"},
      {"snowfall_rate_per_day", &P::snowfallRatePerDay, "1/day", 0.0, 1.0, "k_snow: snow depth per metre above the rain-snow limit per day"},
      {"rain_snow_limit_m", &P::rainSnowLimitM, "m", -500.0, 9000.0, "A_0precip: altitude where rain turns to snow"},
      {"powder_from_precipitation", &P::powderFromPrecipitation, "-", 0.0, 1000.0, "k_powdery"},
      {"powder_critical_slope_min", &P::powderCriticalSlopeMin, "-", 0.0, 100.0, "s_c0"},
      {"powder_critical_slope_per_c", &P::powderCriticalSlopePerC, "1/degC", 0.0, 10.0, "k_sc,powdery"},
      {"powder_slope_temperature_c", &P::powderSlopeTemperatureC, "degC", -80.0, 40.0, "T_0powdery"},
      {"unstable_from_precipitation", &P::unstableFromPrecipitation, "-", 0.0, 1000.0, "k_unstable"},
      {"unstable_critical_slope", &P::unstableCriticalSlope, "-", 0.0, 100.0, "s_U"},
      {"melt_rate_m_per_day_per_c", &P::meltRateMPerDayPerC, "m/(day degC)", 0.0, 1.0, "k_melt"},
      {"melt_threshold_c", &P::meltThresholdC, "degC", -40.0, 40.0, "T_0melt"},
      {"warm_temperature_c", &P::warmTemperatureC, "degC", -80.0, 60.0, "T_warm"},
      {"cool_temperature_c", &P::coolTemperatureC, "degC", -80.0, 60.0, "T_cool"},
      {"freeze_temperature_c", &P::freezeTemperatureC, "degC", -80.0, 60.0, "T_freeze"},
      {"instability_by_warmth_m_per_day", &P::instabilityByWarmthMPerDay, "m/day", 0.0, 1e6, "k_w"},
      {"stability_by_cold_m_per_day", &P::stabilityByColdMPerDay, "m/day", 0.0, 1e6, "k_c"},
      {"diffusion_rest_slope", &P::diffusionRestSlope, "-", 0.0, 100.0, "s_d0: rest slope of powder"},
      {"diffusion_rate_per_day", &P::diffusionRatePerDay, "1/day", 0.0, 1000.0, "k_m: powder shift rate (a creep speed with diffusion_length_m)"},
      {"wind_erosion_rate_m_per_s_per_day", &P::windErosionRateMPerSPerDay, "m/s/day", 0.0, 100.0, "k_erosion"},
      {"wind_instability_per_mps2", &P::windInstabilityPerMps2, "m/day/(m/s^2)", 0.0, 100.0, "instability from wind loading (W . grad W_sz > 0)"},
      {"wind_shadow_tolerance_m", &P::windShadowToleranceM, "m", 0.0, 100.0, "W_z above the snow by more than this: no erosion"},
      {"snow_density_kg_per_m3", &P::snowDensityKgPerM3, "kg/m^3", 10.0, 1000.0, "rho"},
      {"gravity_mps2", &P::gravityMps2, "m/s^2", 0.1, 100.0, "g"},
      {"avalanche_rest_angle_deg", &P::avalancheRestAngleDeg, "deg", 1.0, 80.0, "theta_c: rest angle of avalanche snow"},
      {"snow_viscosity_per_s2", &P::snowViscosityPerS2, "1/s^2", 0.0, 10.0, "k_viscous: wet flow damped at k_v U per second (U in m)"},
      {"skier_target_slope_deg", &P::skierTargetSlopeDeg, "deg", 1.0, 80.0, "s_t"},
      {"track_amplitude_m", &P::trackAmplitudeM, "m", 0.0, 100.0, "a"},
      {"track_frequency_per_m", &P::trackFrequencyPerM, "1/m", 1e-5, 10.0, "f: the lowest turn frequency where the terrain is steeper than s_t"},
      {"skiers_per_hour", &P::skiersPerHour, "1/h", 0.0, 1000.0, "automatic skiers while skiing happens (0: none): a Poisson number each skiing hour, starting together"},
      {"ski_hours_per_day", &P::skiHoursPerDay, "h", 0.0, 24.0, "hours of skiing a day"},
      {"ski_min_snow_m", &P::skiMinSnowM, "m", 0.0, 100.0, "skiers go only where the snow is at least this deep"},
      {"ski_lookahead_m", &P::skiLookaheadM, "m", 0.1, 10000.0, "window a skier picks its next target cell in"},
      {"ski_slope_tolerance_deg", &P::skiSlopeToleranceDeg, "deg", 0.1, 90.0, "sigma of f(|s_n - s_t|) = exp(-((s_n - s_t)/sigma)^2)"},
      {"ski_steering", &P::skiSteering, "-", 0.01, 1.0, "share of the way the heading turns toward the target each step"},
      {"ski_compaction_m", &P::skiCompactionM, "m", 0.0, 10.0, "snow a skier turns U -> S (or S -> C) in each cell entered"},
      {"ski_trigger_factor", &P::skiTriggerFactor, "-", 0.0, 1e6, "how much a skier raises a cell's avalanche release probability"},
      {"ski_track_depth_m", &P::skiTrackDepthM, "m", 0.0, 10.0, "depth of a fresh ski track"},
      {"ski_track_width_m", &P::skiTrackWidthM, "m", 0.01, 100.0, "width of a ski track"},
      {"snowfall_starts_per_day", &P::snowfallStartsPerDay, "1/day", 0.0, 100.0, "mean frequency of snowfall starts"},
      {"snowfall_mean_duration_days", &P::snowfallMeanDurationDays, "day", 1e-3, 365.0, "mean duration of a snowfall"},
      {"snowfall_steps_per_day", &P::snowfallStepsPerDay, "1/day", 0.01, 1000.0, "snowfall step events per day"},
      {"state_change_steps_per_day", &P::stateChangeStepsPerDay, "1/day", 0.01, 1000.0, "melt and stability step events per day"},
      {"avalanche_dry_temperature_c", &P::avalancheDryTemperatureC, "degC", -60.0, 10.0, "at or below: dry, granular flow (alpha = 1)"},
      {"avalanche_wet_temperature_c", &P::avalancheWetTemperatureC, "degC", -60.0, 20.0, "at or above: wet, viscous flow (alpha = alpha_wet)"},
      {"avalanche_wet_granular_fraction", &P::avalancheWetGranularFraction, "-", 0.0, 1.0, "alpha of wet snow: share of granular friction it keeps"},
      {"avalanche_dynamic_friction_deg", &P::avalancheDynamicFrictionDeg, "deg", 0.5, 80.0, "delta: Coulomb friction angle of flowing snow (the rest angle holds snow that is not flowing)"},
      {"avalanche_turbulence_mps2", &P::avalancheTurbulenceMps2, "m/s^2", 0.0, 1e6, "xi: Voellmy turbulent drag g s^2 / (xi h) on flowing snow (0: none)"},
      {"avalanche_rate_per_km2_per_day", &P::avalancheRatePerKm2PerDay, "1/(km^2 day)", 0.0, 100.0, "spontaneous avalanches (an event that finds no cell able to release waits for one; 0: none)"},
      {"avalanche_reach_m_per_m", &P::avalancheReachMPerM, "m/m", 0.0, 10000.0, "release reach per metre of unstable snow"},
      {"avalanche_min_unstable_m", &P::avalancheMinUnstableM, "m", 0.001, 10.0, "no release where U is thinner"},
      {"avalanche_stop_speed_mps", &P::avalancheStopSpeedMps, "m/s", 1e-4, 10.0, "at rest below this pipe speed"},
      {"avalanche_stop_thickness_m", &P::avalancheStopThicknessM, "m", 0.0, 10.0, "h_stop: moving snow this thin or thinner does not flow (thin-flow stop)"},
      {"avalanche_stop_energy_fraction", &P::avalancheStopEnergyFraction, "1", 0.0, 1.0, "at rest once the flow's kinetic energy is below this share of its peak (0: off)"},
      {"avalanche_max_duration_s", &P::avalancheMaxDurationS, "s", 1.0, 36000.0, "cap on one avalanche's simulated time"},
      {"avalanche_step_s", &P::avalancheStepS, "s", 0.001, 10.0, "simulated time of one avalanche step"},
      {"diffusion_steps_per_day", &P::diffusionStepsPerDay, "1/day", 0.01, 1000.0, "powder diffusion step events per day"},
      {"wind_transport_steps_per_day", &P::windTransportStepsPerDay, "1/day", 0.01, 1000.0, "wind transport step events per day"},
      {"diffusion_length_m", &P::diffusionLengthM, "m", 0.01, 10000.0, "L_d: powder creep speed k_m * L_d per unit of excess slope"},
      {"diffusion_min_depth_m", &P::diffusionMinDepthM, "m", 0.0, 1.0, "a powder film thinner than this does not slide"},
  };
  return table;
}

const ParameterInfo* findParameter(const std::string& key) {
  for (const auto& p : parameterTable())
    if (key == p.key) return &p;
  return nullptr;
}

}  // namespace snow
