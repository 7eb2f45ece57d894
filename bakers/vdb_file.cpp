#include "vdb_file.h"

#include <openvdb/io/Archive.h>
#include <openvdb/io/GridDescriptor.h>
#include <openvdb/io/io.h>

#include <cstdio>
#include <fstream>
#include <set>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/hash.h"

namespace snow {
namespace {

namespace io = openvdb::io;

// io::Archive::write's steps (OpenVDB 10: header, file metadata, grid count, then each grid with
// the file's compression restored after it), one grid at a time. Archive's writeHeader and
// writeGrid are protected: this is the subclass that reaches them.
class GridByGridArchive : private io::Archive {
 public:
  GridByGridArchive(std::ostream& os, int32_t gridCount) : os_(os), meta_(new io::StreamMetadata) {
    io::setStreamMetadataPtr(os_, meta_, /*transfer=*/false);
    io::setDataCompression(os_, compression());
    io::setWriteGridStatsMetadata(os_, isGridStatsMetadataEnabled());
    writeHeader(os_, /*seekable=*/true);
    openvdb::MetaMap().writeMeta(os_);
    os_.write(reinterpret_cast<const char*>(&gridCount), sizeof gridCount);
  }
  ~GridByGridArchive() override {
    io::StreamMetadata::Ptr none;
    io::setStreamMetadataPtr(os_, none, /*transfer=*/false);
  }
  GridByGridArchive(const GridByGridArchive&) = delete;
  GridByGridArchive& operator=(const GridByGridArchive&) = delete;

  void write(const openvdb::GridBase::ConstPtr& grid) {
    // Archive::write suffixes empty or repeated names; the bakers' grids never need it.
    const std::string name = grid->getName();
    if (name.empty() || !names_.insert(name).second) throw std::logic_error("VDB grid name empty or repeated: '" + name + "'");
    io::GridDescriptor gd(name, grid->type(), grid->saveFloatAsHalf());
    writeGrid(gd, grid, os_, /*seekable=*/true);
    io::setDataCompression(os_, compression());
  }
  std::string tag() const { return getUniqueTag(); }

 private:
  std::ostream& os_;
  io::StreamMetadata::Ptr meta_;
  std::set<std::string> names_;
};

// OpenVDB stamps each file with a random UUID; replace it with one derived from the content so
// the same bake gives the same bytes. The content is hashed in chunks as it is read (not held in
// memory) and the 36 bytes are patched in place.
void replaceTagByContentHash(const std::string& file, const std::string& tag, const std::string& path) {
  std::ifstream in(file, std::ios::binary);
  std::string head(512, '\0');  // the tag is looked for in the first 256 bytes
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  const size_t at = head.find(tag);
  if (tag.size() != 36 || at == std::string::npos || at >= 256) return;
  head.replace(at, tag.size(), std::string(tag.size(), '0'));
  Fnv1a64 ha, hb;
  hb.add("snowbake");
  ha.add(head), hb.add(head);
  std::vector<char> chunk(1 << 20);
  while (in) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    const size_t n = static_cast<size_t>(in.gcount());
    ha.add(chunk.data(), n), hb.add(chunk.data(), n);
  }
  in.close();
  const uint64_t a = ha.value(), b = hb.value();
  char uuid[40];
  std::snprintf(uuid, sizeof uuid, "%08x-%04x-%04x-%04x-%012llx", static_cast<unsigned>(a >> 32), static_cast<unsigned>((a >> 16) & 0xffff),
                static_cast<unsigned>(a & 0xffff), static_cast<unsigned>(b >> 48), static_cast<unsigned long long>(b & 0xffffffffffffull));
  std::fstream out(file, std::ios::binary | std::ios::in | std::ios::out);
  out.seekp(static_cast<std::streamoff>(at));
  out.write(uuid, 36);
  if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace

void writeVdbGridsOneByOneAtomically(const std::string& path, const std::vector<VdbGridMaker>& makers) {
  writeAtomically(path, [&](const std::string& temp) {
    std::string tag;
    {
      std::ofstream file(temp, std::ios_base::out | std::ios_base::binary | std::ios_base::trunc);
      if (file.fail()) throw std::runtime_error("cannot write " + path);
      GridByGridArchive archive(file, static_cast<int32_t>(makers.size()));
      for (const auto& make : makers) {
        const openvdb::GridBase::Ptr grid = make();
        if (!grid) throw std::logic_error("a VDB grid maker made no grid");
        archive.write(grid);
      }  // each grid freed here, before the next is made
      tag = archive.tag();
      file.close();
      if (file.fail()) throw std::runtime_error("cannot write " + path);
    }
    replaceTagByContentHash(temp, tag, path);
  });
}

void writeVdbGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids) {
  std::vector<VdbGridMaker> makers;
  for (const auto& g : grids) makers.push_back([g] { return g; });
  writeVdbGridsOneByOneAtomically(path, makers);
}

}  // namespace snow
