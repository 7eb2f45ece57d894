// Bytes a bake sets aside on disk while it has no use for them in memory (a frame's layers that
// wait for the season's value range, a frame whose instant falls inside an avalanche): one
// unlinked temporary file, so nothing is left behind however the process ends. Written once,
// read back by extent; the kernel's page cache, not the process, holds what was written.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace snow {

class SpillFile {
 public:
  // Where a piece of the file lies.
  struct Extent {
    uint64_t offset = 0, bytes = 0;
  };

  // A file in `folder` (empty: the system's temporary folder; O_TMPFILE where the file system has
  // it, else a unique name unlinked at once); throws naming the folder when it cannot be made.
  explicit SpillFile(const std::string& folder);
  ~SpillFile();
  SpillFile(const SpillFile&) = delete;
  SpillFile& operator=(const SpillFile&) = delete;

  // Appends `bytes` bytes; throws naming the folder where the disk is full.
  Extent write(const void* data, uint64_t bytes);
  void read(const Extent& e, void* data) const;
  uint64_t size() const { return end_; }

  template <class T>
  Extent put(const std::vector<T>& values) {
    return write(values.data(), values.size() * sizeof(T));
  }
  template <class T>
  std::vector<T> get(const Extent& e) const {
    std::vector<T> values(e.bytes / sizeof(T));
    read(e, values.data());
    return values;
  }

 private:
  std::string folder_;
  int fd_ = -1;
  uint64_t end_ = 0;
};

}  // namespace snow
