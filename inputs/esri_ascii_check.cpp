// ESRI ASCII grids checked as text before GDAL reads them (inputs/terrain_checks.h).
#include <charconv>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/errors.h"
#include "terrain_checks.h"

namespace snow {

namespace {

// The whole token as a finite number (a leading '+' allowed), else nothing.
bool finiteNumber(const std::string& token, double& value) {
  const char* begin = token.data() + (token.size() > 1 && token[0] == '+' ? 1 : 0);
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  return ec == std::errc() && ptr == end && std::isfinite(value);
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

[[noreturn]] void refuse(const std::string& path, long line, const std::string& what) {
  throw InputError(path + ":" + std::to_string(line) + ": " + what);
}

struct Header {
  double ncols = 0, nrows = 0;
  long lines = 0;          // header lines read
  std::string firstData;   // the first line of heights (already read)
};

// "key value" lines until the first line that starts with a number.
Header readHeader(const std::string& path, std::istream& in) {
  Header h;
  std::string text;
  while (std::getline(in, text)) {
    std::istringstream words(text);
    std::string key, value, extra;
    if (!(words >> key)) {
      ++h.lines;
      continue;
    }
    double number = 0;
    if (finiteNumber(key, number) || key[0] == '-' || key[0] == '.' || std::isdigit(static_cast<unsigned char>(key[0]))) {
      h.firstData = text;
      break;
    }
    ++h.lines;
    const std::string k = lower(key);
    if (!(words >> value) || (words >> extra)) refuse(path, h.lines, "header line '" + text + "' is not 'key value'");
    if (!finiteNumber(value, number)) refuse(path, h.lines, k + " '" + value + "' is not finite or not a number");
    if ((k == "cellsize" || k == "dx" || k == "dy") && !(number > 0))
      refuse(path, h.lines, k + " " + value + ": a cell size must be positive");
    if ((k == "ncols" || k == "nrows") && !(number >= 1 && number == std::floor(number)))
      refuse(path, h.lines, k + " " + value + ": must be a whole number of cells, 1 or more");
    if (k == "ncols") h.ncols = number;
    if (k == "nrows") h.nrows = number;
  }
  if (h.ncols < 1 || h.nrows < 1) refuse(path, h.lines, "the header names no ncols and nrows");
  return h;
}

}  // namespace

bool isEsriAsciiGrid(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string first;
  if (!(in >> std::setw(16) >> first)) return false;
  const std::string k = lower(first);
  return k == "ncols" || k == "nrows" || k == "xllcorner" || k == "xllcenter" || k == "yllcorner" || k == "yllcenter" || k == "cellsize";
}

void checkEsriAsciiGrid(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open for reading");
  const Header h = readHeader(path, in);
  const double expected = h.ncols * h.nrows;
  double count = 0;
  long line = h.lines + 1;
  std::string text = h.firstData, token;
  do {
    std::istringstream words(text);
    double value = 0;
    while (words >> token) {
      if (!finiteNumber(token, value))
        refuse(path, line, "'" + token + "' is not finite or not a number (a missing height takes the header's nodata_value)");
      if (++count > expected) refuse(path, line, "more heights than ncols x nrows in the header");
    }
    ++line;
  } while (std::getline(in, text));
  if (count < expected) {
    std::ostringstream o;
    o << path << ": has " << count << " heights, but the header's ncols x nrows is " << expected << " (truncated?)";
    throw InputError(o.str());
  }
}

}  // namespace snow
