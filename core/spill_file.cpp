#include "spill_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace snow {

namespace {
[[noreturn]] void fail(const std::string& what, const std::string& folder, int error) {
  throw std::runtime_error(what + " (a temporary file in " + folder + "): " + std::strerror(error));
}
}  // namespace

SpillFile::SpillFile(const std::string& folder)
    : folder_(folder.empty() ? std::filesystem::temp_directory_path().string() : folder) {
#ifdef O_TMPFILE
  fd_ = ::open(folder_.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
#endif
  if (fd_ < 0) {  // a file system without O_TMPFILE (NFS, older kernels): a name unlinked at once
    std::string path = folder_ + "/.snowbake-spill-XXXXXX";
    fd_ = ::mkostemp(path.data(), O_CLOEXEC);
    if (fd_ < 0) fail("cannot set bytes aside on disk", folder_, errno);
    ::unlink(path.c_str());
  }
}

SpillFile::~SpillFile() {
  if (fd_ >= 0) ::close(fd_);
}

SpillFile::Extent SpillFile::write(const void* data, uint64_t bytes) {
  const Extent e{end_, bytes};
  const char* p = static_cast<const char*>(data);
  for (uint64_t done = 0; done < bytes;) {
    const ssize_t n = ::pwrite(fd_, p + done, bytes - done, static_cast<off_t>(end_ + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail("cannot set " + std::to_string(bytes) + " bytes aside on disk", folder_, n < 0 ? errno : ENOSPC);
    done += static_cast<uint64_t>(n);
  }
  end_ += bytes;
  return e;
}

void SpillFile::read(const Extent& e, void* data) const {
  char* p = static_cast<char*>(data);
  for (uint64_t done = 0; done < e.bytes;) {
    const ssize_t n = ::pread(fd_, p + done, e.bytes - done, static_cast<off_t>(e.offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail("cannot read back bytes set aside on disk", folder_, n < 0 ? errno : EIO);
    done += static_cast<uint64_t>(n);
  }
}

}  // namespace snow
