// `snowbake bake --scene-list FILE --index N`: one level of a farm's list per task of a job array
// (docs/farm.md). The list is read and checked whole before any work, so a bad line fails every
// task the same way, at once.
#pragma once
#include <string>
#include <vector>

namespace snow {

// One line: `NAME SCENE [KEY=VALUE ...]`. NAME names the level's output folder (OUT/NAME), SCENE
// is a scene file (relative to the list's folder) or preset:NAME, and each KEY=VALUE is a --set.
struct SceneListEntry {
  std::string name;
  std::string scene;
  std::vector<std::string> sets;
  int line = 0;  // in the list file, from 1
};

// Every level of the list, in order; throws InputError naming the file and line of the first
// bad line (unknown syntax, a name that is not a folder name, a repeated name, no levels).
std::vector<SceneListEntry> readSceneList(const std::string& path);

// Level `index` (from 0, as Slurm's --array=0-N numbers tasks) of the list; throws InputError
// naming the file when index is out of range.
SceneListEntry sceneListEntry(const std::string& path, long long index);

}  // namespace snow
