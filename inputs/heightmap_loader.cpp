// Heightmaps from DCC tools and engines: images through OpenImageIO (16-bit PNG, 32-bit float
// TIFF and EXR, ...) and raw .r16/.r32 files (Unity/Unreal style). Heights are
// offset + scale * value, where value is what OpenImageIO reads: 0..1 for integer images (a
// 16-bit count / 65535), the stored number for float images and .r32.
#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/errors.h"
#include "terrain_loader.h"

namespace snow {

namespace {

struct HeightMapping {
  double offset = 0.0, scale = 1.0;
  std::string description;
};

// From height_range_m or height_scale_m/height_offset_m; float data may go without either
// (values are metres), integer data must say how counts become metres.
HeightMapping heightMapping(const TerrainSource& src, bool integerData, const std::string& what) {
  HeightMapping m;
  std::ostringstream o;
  if (src.heightRangeM) {
    m.offset = (*src.heightRangeM)[0];
    m.scale = (*src.heightRangeM)[1] - (*src.heightRangeM)[0];
    o << "value 0..1 mapped to " << (*src.heightRangeM)[0] << ".." << (*src.heightRangeM)[1] << " m (terrain.height_range_m)";
  } else if (src.heightScaleM || src.heightOffsetM) {
    m.offset = src.heightOffsetM.value_or(0.0);
    m.scale = src.heightScaleM.value_or(1.0);
    o << "height = " << m.offset << " m + " << m.scale << " m x value (terrain.height_scale_m/height_offset_m)";
  } else if (integerData) {
    throw InputError(what + ": an integer heightmap needs terrain.height_range_m = [lowest, highest] (metres for black and "
                            "white) or terrain.height_scale_m");
  } else {
    o << "float values taken as metres";
  }
  m.description = o.str();
  return m;
}

double requireCellSize(const TerrainSource& src, const std::string& what) {
  if (!src.cellSizeM)
    throw InputError(what + ": a heightmap carries no cell size: set terrain.cell_size_m (metres between pixel centres)");
  return *src.cellSizeM;
}

// The channel (from 0) that holds the heights: the only one, or terrain.band's.
int heightChannel(const TerrainSource& src, int channels) {
  if (src.band == 0 && channels > 1)
    throw InputError(src.file + ": has " + std::to_string(channels) + " channels: set terrain.band to the one that holds the heights (from 1)");
  if (src.band > channels) throw InputError(src.file + ": terrain.band = " + std::to_string(src.band) + ", but the image has " + std::to_string(channels) + " channels");
  return src.band == 0 ? 0 : src.band - 1;
}

void fillTerrain(Terrain& t, const std::vector<float>& values, int w, int h, const HeightMapping& m, const std::string& what) {
  t.heightsM.resize(w, h);
  t.valid.resize(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float v = values[static_cast<size_t>(y) * w + x];
      if (!std::isfinite(v)) {
        std::ostringstream o;
        o << what << ": value at column " << x << ", row " << y << " is " << v << " (not finite)";
        throw InputError(o.str());
      }
      t.heightsM(x, y) = static_cast<float>(m.offset + m.scale * static_cast<double>(v));
    }
}

void setMetricSpec(Terrain& t, double cell, int w, int h) {
  t.info.spec.width = w;
  t.info.spec.height = h;
  t.info.spec.cellSizeXM = t.info.spec.cellSizeYM = cell;
  t.info.spec.originX = 0.0;
  t.info.spec.originY = h * cell;
  t.info.nativeCellSizeX = t.info.nativeCellSizeY = cell;
  t.info.nativeUnit = "metre (terrain.cell_size_m)";
  t.info.nativeWidth = w;
  t.info.nativeHeight = h;
  t.info.coordinateSystem = "local (metres)";
  t.info.coordinateDecision = "heightmap: cell size from terrain.cell_size_m";
}

}  // namespace

Terrain loadHeightmapImage(const TerrainSource& src) {
  const std::string& path = src.file;
  std::error_code ec;
  if (std::filesystem::file_size(path, ec) == 0) throw InputError(path + ": terrain file is empty");
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw InputError(path + ": cannot read as a heightmap image: " + OIIO::geterror());
  const OIIO::ImageSpec spec = in->spec();
  const double cell = requireCellSize(src, path);
  checkGridSize(path, spec.width, spec.height);
  const bool integerData = !spec.format.is_floating_point();
  const HeightMapping mapping = heightMapping(src, integerData, path);
  const int channel = heightChannel(src, spec.nchannels);
  std::vector<float> pixels(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
    throw InputError(path + ": read failed (truncated or corrupt?): " + in->geterror());
  std::vector<float> first(static_cast<size_t>(spec.width) * spec.height);
  for (size_t i = 0; i < first.size(); ++i) first[i] = pixels[i * spec.nchannels + channel];
  Terrain t;
  t.info.source = path;
  t.info.format = "heightmap";
  t.info.driver = std::string(in->format_name()) + ", " + spec.format.c_str() +
                  (spec.nchannels > 1 ? ", channel " + std::to_string(channel + 1) + " of " + std::to_string(spec.nchannels) : "");
  fillTerrain(t, first, spec.width, spec.height, mapping, path);
  setMetricSpec(t, cell, spec.width, spec.height);
  t.info.heightMapping = mapping.description;
  updateTerrainStatistics(t);
  return t;
}

Terrain loadRawHeightmap(const TerrainSource& src) {
  const std::string& path = src.file;
  const std::string ext = std::filesystem::path(path).extension().string();
  const bool is32 = ext == ".r32";
  if (src.rawWidth <= 0 || src.rawHeight <= 0)
    throw InputError(path + ": a raw heightmap needs terrain.raw_width and terrain.raw_height");
  const double cell = requireCellSize(src, path);
  checkGridSize(path, src.rawWidth, src.rawHeight);
  const size_t bytesPerValue = is32 ? 4 : 2;
  const size_t expected = static_cast<size_t>(src.rawWidth) * src.rawHeight * bytesPerValue;
  std::error_code ec;
  const auto actual = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read: " + ec.message());
  if (actual != expected) {
    std::ostringstream o;
    o << path << ": has " << actual << " bytes, but " << src.rawWidth << " x " << src.rawHeight << " "
      << (is32 ? "32-bit floats" : "16-bit values") << " need " << expected << " (check terrain.raw_width/raw_height"
      << (is32 ? "" : ", or use .r32 for float data") << ")";
    throw InputError(o.str());
  }
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> bytes(expected);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(expected)))
    throw InputError(path + ": read failed");
  const bool big = src.byteOrder == ByteOrder::Big;
  std::vector<float> values(static_cast<size_t>(src.rawWidth) * src.rawHeight);
  for (size_t i = 0; i < values.size(); ++i) {
    const unsigned char* b = &bytes[i * bytesPerValue];
    if (is32) {
      const uint32_t u = big ? (uint32_t(b[0]) << 24 | uint32_t(b[1]) << 16 | uint32_t(b[2]) << 8 | b[3])
                             : (uint32_t(b[3]) << 24 | uint32_t(b[2]) << 16 | uint32_t(b[1]) << 8 | b[0]);
      float f;
      std::memcpy(&f, &u, 4);
      values[i] = f;
    } else {
      const uint16_t u = big ? static_cast<uint16_t>(b[0] << 8 | b[1]) : static_cast<uint16_t>(b[1] << 8 | b[0]);
      values[i] = static_cast<float>(u) / 65535.0f;
    }
  }
  const HeightMapping mapping = heightMapping(src, !is32, path);
  Terrain t;
  t.info.source = path;
  t.info.format = "raw";
  t.info.driver = std::string(is32 ? "raw float32 " : "raw uint16 ") + enumName(src.byteOrder) + "-endian";
  fillTerrain(t, values, src.rawWidth, src.rawHeight, mapping, path);
  setMetricSpec(t, cell, src.rawWidth, src.rawHeight);
  t.info.heightMapping = mapping.description + (is32 ? "" : " (16-bit count / 65535)");
  updateTerrainStatistics(t);
  return t;
}

}  // namespace snow
