// The scene file's reference (snowbake help scene [--markdown], docs/scene.md), generated from the
// schema's rules (scene_schema.cpp) and the model parameter table (core/parameters.cpp).
#pragma once
#include <string>
#include <vector>

#include "scene.h"

namespace snow {

struct SceneKeyDoc {
  std::string section;       // the top-level table ("" at the top level, "parameters" for model parameters)
  std::string path;          // dotted key ("parameters.KEY" for model parameters)
  std::string type;          // string, number, integer, bool, date, array of numbers, ..., raster
  std::string range;         // "[min, max]" or the choices ("a, b, c"); empty when any value goes
  std::string defaultValue;  // empty for tables
  std::string unit;
  std::string doc;
};

// Every scene key in the reference's order (by section), then every model parameter.
std::vector<SceneKeyDoc> sceneKeyDocs();

std::string sceneReferenceText();
std::string sceneReferenceMarkdown();

// `scene`'s value of a key bound into the Scene, printed as the reference prints defaults; empty
// for keys read another way (array elements, rasters, tables).
std::string sceneValueText(const Scene& scene, const std::string& path);

}  // namespace snow
