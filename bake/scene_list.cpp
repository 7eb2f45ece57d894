#include "scene_list.h"

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "core/errors.h"

namespace snow {

namespace fs = std::filesystem;

namespace {

// A scene given by path is found beside the list, wherever the task starts.
std::string sceneBesideList(const std::string& scene, const std::string& listPath) {
  if (scene.rfind("preset:", 0) == 0 || scene.rfind("builtin:", 0) == 0 || fs::path(scene).is_absolute()) return scene;
  return (fs::path(listPath).parent_path() / scene).lexically_normal().string();
}

SceneListEntry parseLine(const std::string& text, int line, const std::string& path) {
  const std::string where = path + ":" + std::to_string(line) + ": ";
  std::istringstream words(text);
  SceneListEntry e;
  e.line = line;
  if (!(words >> e.name >> e.scene)) throw InputError(where + "expected NAME SCENE [KEY=VALUE ...], found '" + text + "'");
  static const std::regex folderName(R"([A-Za-z0-9_][A-Za-z0-9._-]*)");
  if (!std::regex_match(e.name, folderName))
    throw InputError(where + "level name '" + e.name + "' is not a plain folder name (letters, digits, . _ -)");
  e.scene = sceneBesideList(e.scene, path);
  for (std::string set; words >> set;) {
    const size_t eq = set.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError(where + "'" + set + "' is not KEY=VALUE");
    e.sets.push_back(set);
  }
  return e;
}

}  // namespace

std::vector<SceneListEntry> readSceneList(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot read the scene list (--scene-list)");
  std::vector<SceneListEntry> entries;
  std::map<std::string, int> lineOfName;
  int line = 0;
  for (std::string text; std::getline(in, text);) {
    ++line;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const size_t first = text.find_first_not_of(" \t");
    if (first == std::string::npos || text[first] == '#') continue;
    SceneListEntry e = parseLine(text, line, path);
    if (const auto seen = lineOfName.find(e.name); seen != lineOfName.end())
      throw InputError(path + ":" + std::to_string(line) + ": level name '" + e.name + "' is already used on line " +
                       std::to_string(seen->second) + " (each level needs its own output folder)");
    lineOfName[e.name] = line;
    entries.push_back(std::move(e));
  }
  if (entries.empty()) throw InputError(path + ": the scene list has no levels (one `NAME SCENE [KEY=VALUE ...]` a line)");
  return entries;
}

SceneListEntry sceneListEntry(const std::string& path, long long index) {
  std::vector<SceneListEntry> entries = readSceneList(path);
  const long long n = static_cast<long long>(entries.size());
  if (index < 0 || index >= n)
    throw InputError(path + ": --index " + std::to_string(index) + " is out of range: the list has " + std::to_string(n) +
                     " levels, numbered from 0 to " + std::to_string(n - 1));
  return entries[static_cast<size_t>(index)];
}

}  // namespace snow
