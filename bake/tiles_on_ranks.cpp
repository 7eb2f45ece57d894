#include "tiles_on_ranks.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "bakers/raster_tiles.h"
#include "distributed/window_gather.h"
#include "scene/layers.h"

namespace snow {

std::string whyRankZeroWritesEveryFile(const Scene& scene) {
  const OutputRequest& out = scene.outputs;
  // outputs.resize and the displacement maps are: each rank resamples its tiles' pixels from the
  // cells they read, gathered from their owners (OutputSources::gatherCells). So is
  // outputs.tiles.resize, whose whole files beside the tiles rank 0 writes one at a time, each
  // gathered from the ranks (OutputWriter::untiledWindow).
  for (const std::string& name : out.layers) {
    const LayerInfo* layer = findLayer(name);
    if (!layer) continue;
    // Every layer of the snow state is: the pictures too, drawn cell by cell with their normals
    // from the next cells (in the halo), the preview's altitude range and contact-sheet thumbnails
    // put together over the ranks. So are the sun's and the wind's, each cell from its own cell of
    // the rank's part of the precompute, and the skiers' (every rank's replica skis the whole grid,
    // and each rank writes the tiles over its cells from it).
    if ((layer->needs & kNeedsOcclusion) != 0)
      return "outputs.layers: \"" + name + "\" (read from the occlusion, not the snow state, the precompute or the skiers)";
  }
  if (out.vdb) return "outputs.vdb (one file of the whole snow body)";
  if (!out.meshes.empty()) return "outputs.meshes (triangulated over the whole grid)";
  return "";
}

std::optional<dist::Decomposition> decompositionOnTiles(const Scene& scene, const GridSpec& spec, int ranks, int minHalo) {
  if (!whyRankZeroWritesEveryFile(scene).empty()) return std::nullopt;
  std::optional<dist::Decomposition> d;
  if (scene.outputs.tiles.convention == TileConvention::None) {
    // Whole files alone: rank 0 writes each, gathered from the ranks one at a time, and any split
    // will do (the normals and slopes read the next cell, which the season's halo holds).
    d = dist::Decomposition::choose(ranks, spec.width, spec.height, std::max(minHalo, 1));
  } else {
    const TileLayout l = tileLayout(scene.outputs.tiles, spec.width, spec.height);
    // A tile reaches its overlap past the next tile's start, into the next rank's subdomain, and
    // its normals and slopes read the cell after that: the halo is widened to hold both (the
    // season runs on any halo of at least its own).
    const int halo = std::max(minHalo, std::max(l.tileWidth, l.tileHeight) - l.step + 1);
    d = dist::Decomposition::chooseOnTiles(ranks, spec.width, spec.height, halo, l.step, l.columns, l.rows);
  }
  // The writers tell a rank's window of the grid's cells from an image of the whole grid (the
  // avalanche maps, the ski-track texture at one texel a cell) by its size, on every rank alike
  // (OutputWriter::windowOf, untiledWindow): no rank's local grid may be the whole grid.
  if (d && ranks > 1)
    for (int r = 0; r < ranks; ++r)
      if (d->local(r).width() == spec.width && d->local(r).height() == spec.height) return std::nullopt;
  return d;
}

Scene sceneOfTheRanksTiles(const Scene& scene, const GridSpec& whole, int ownedWidth, int ownedHeight) {
  Scene mine = scene;
  const int tile = std::max(1, scene.outputs.tiles.sizePx);
  auto share = [&](int pixels, int cells, int owned) {
    if (pixels <= 0) return pixels;
    const double part = std::ceil(static_cast<double>(pixels) * owned / cells);
    return static_cast<int>(std::min<double>(pixels, part + tile + 2.0));
  };
  OutputRequest& o = mine.outputs;
  o.resizeWidth = share(o.resizeWidth, whole.width, ownedWidth), o.resizeHeight = share(o.resizeHeight, whole.height, ownedHeight);
  o.displacementWidth = share(o.displacementWidth, whole.width, ownedWidth);
  o.displacementHeight = share(o.displacementHeight, whole.height, ownedHeight);
  o.tiles.resizeWidth = share(o.tiles.resizeWidth, whole.width, ownedWidth);
  o.tiles.resizeHeight = share(o.tiles.resizeHeight, whole.height, ownedHeight);
  return mine;
}

void shareTheTiles(OutputSources& sources, const dist::Communicator& comm, const dist::Decomposition& d) {
  sources.stateCells = d.local(comm.rank());
  sources.tilesStartingIn = d.owned(comm.rank());
  sources.wholeFilesElsewhere = comm.rank() != 0;
  sources.wholeRange = [comm](const SeenRange& mine) {
    // Each rank's lowest and highest (an empty range's infinities included): their extremes are
    // the whole grid's, whatever the order.
    const std::vector<double> all = comm.allGather({mine.lo, mine.hi});
    SeenRange whole;
    for (size_t k = 0; k + 1 < all.size(); k += 2) whole.widen(SeenRange{all[k], all[k + 1]});
    return whole;
  };
  sources.gatherCells = [comm, d](const void* local, size_t elementBytes, const CellRect& want, void* held) {
    dist::gatherWindow(comm, d, local, elementBytes, want, held);
  };
  sources.wholeThumbnail = [comm](std::vector<uint8_t> mine) {
    // Each pixel is one rank's, 0 on every other: or'd together on rank 0.
    if (comm.rank() != 0) {
      comm.exchange({{0, mine.data(), mine.size()}}, {});
      return mine;
    }
    std::vector<uint8_t> theirs(mine.size());
    for (int peer = 1; peer < comm.size(); ++peer) {
      comm.exchange({}, {{peer, theirs.data(), theirs.size()}});
      for (size_t k = 0; k < mine.size(); ++k) mine[k] |= theirs[k];
    }
    return mine;
  };
}

namespace {

// A rank's listed files as bytes: each entry's fields in declaration order, then its absolute path.
class Packer {
 public:
  template <class T>
  void put(const T& v) {
    const auto* p = reinterpret_cast<const char*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  void put(const std::string& s) {
    put(static_cast<uint64_t>(s.size()));
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
  std::vector<char> bytes;
};
class Unpacker {
 public:
  explicit Unpacker(const std::vector<char>& bytes) : bytes_(bytes) {}
  template <class T>
  void get(T& v) {
    need(sizeof(T));
    std::memcpy(&v, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
  }
  void get(std::string& s) {
    uint64_t n = 0;
    get(n);
    need(n);
    s.assign(bytes_.data() + at_, n);
    at_ += n;
  }
  bool done() const { return at_ == bytes_.size(); }

 private:
  void need(size_t n) const {
    if (bytes_.size() - at_ < n) throw std::logic_error("mergeTheRanksFiles: a rank's list of files ends early");
  }
  const std::vector<char>& bytes_;
  size_t at_ = 0;
};

// Every field of ManifestFile, in order: a field added there is added here.
template <class Io>
void eachField(Io&& io, ManifestFile& f) {
  io(f.path), io(f.content), io(f.unit), io(f.format), io(f.day), io(f.minValue), io(f.maxValue), io(f.width), io(f.height);
  io(f.rangeMode), io(f.rangeLo), io(f.rangeHi), io(f.nodataPixel);
  io(f.tileConvention), io(f.tileColumn), io(f.tileRow), io(f.tileX), io(f.tileY);
  io(f.tileOriginX), io(f.tileOriginY), io(f.pixelSizeX), io(f.pixelSizeY), io(f.listing);
}

}  // namespace

void mergeTheRanksFiles(const dist::Communicator& comm, OutputSink& files) {
  if (files.files.size() != files.paths.size()) throw std::logic_error("mergeTheRanksFiles: files and paths differ in number");
  Packer pack;
  pack.put(static_cast<uint64_t>(files.files.size()));
  for (size_t k = 0; k < files.files.size(); ++k) {
    ManifestFile f = files.files[k];
    eachField([&](const auto& v) { pack.put(v); }, f);
    pack.put(files.paths[k]);
  }
  // Each rank's byte count, then rank 0 receives every other rank's list.
  const std::vector<double> sizes = comm.allGather({static_cast<double>(pack.bytes.size())});
  if (comm.rank() != 0) {
    comm.exchange({{0, pack.bytes.data(), pack.bytes.size()}}, {});
    return;
  }
  struct Listed {
    ManifestFile file;
    std::string path;
  };
  std::vector<Listed> all;
  for (int peer = 0; peer < comm.size(); ++peer) {
    std::vector<char> bytes = peer == 0 ? pack.bytes : std::vector<char>(static_cast<size_t>(sizes[peer]));
    if (peer != 0) comm.exchange({}, {{peer, bytes.data(), bytes.size()}});
    Unpacker in(bytes);
    uint64_t n = 0;
    in.get(n);
    for (uint64_t k = 0; k < n; ++k) {
      Listed l;
      eachField([&](auto& v) { in.get(v); }, l.file);
      in.get(l.path);
      if (l.file.listing < 0) throw std::logic_error("mergeTheRanksFiles: " + l.file.path + " was not listed by a writer");
      all.push_back(std::move(l));
    }
    if (!in.done()) throw std::logic_error("mergeTheRanksFiles: rank " + std::to_string(peer) + "'s list of files has bytes left");
  }
  std::sort(all.begin(), all.end(), [](const Listed& a, const Listed& b) { return a.file.listing < b.file.listing; });
  files.files.clear(), files.paths.clear();
  for (Listed& l : all) {
    files.files.push_back(std::move(l.file));
    files.paths.push_back(std::move(l.path));
  }
}

}  // namespace snow
