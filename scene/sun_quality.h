// precompute.sun_quality: the named sample counts of the sun exposure (precompute/exposure.h) and
// of occlusion mode's ambient occlusion (static_snow/occlusion.h).
#pragma once
#include <string>
#include <vector>

namespace snow {

struct SunQuality {
  std::string name;
  int azimuths;             // sky: horizon directions N
  int bisections;           // sky: horizon angle to 90 deg / 2^bisections
  double hourStep;          // direct: hours between sun positions (sampled at the middle of each step)
  double dayStep;           // days between exposure samples over the season (interpolated between)
  int indirectDirections;   // indirect: directions per ring (0 = no indirect pass)
  int indirectRings;        // indirect: rings out to the radius
  double indirectRadiusM;   // indirect: sampling radius, metres
  int occlusionAoRays;      // occlusion mode: ambient-occlusion rays per cell (occlusion.ao_rays = 0)
};

// The named qualities, in the order the scene reference lists them.
const std::vector<SunQuality>& sunQualities();
// "draft", "production", "reference"; throws InputError for anything else.
SunQuality sunQuality(const std::string& name);
const std::vector<std::string>& sunQualityNames();

}  // namespace snow
