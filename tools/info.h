// `snowbake info`: what snowbake understood of a terrain, as text or JSON.
#pragma once
#include <string>
#include <vector>

namespace snow {

// A DEM file, builtin:ridged, or a scene (file or preset:NAME, with --set overrides) whose
// [terrain] says how to read its file.
std::string describeTerrain(const std::string& source, bool json, const std::vector<std::string>& sets = {});

}  // namespace snow
