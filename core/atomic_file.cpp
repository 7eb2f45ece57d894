#include "atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <stdexcept>

namespace snow {

namespace fs = std::filesystem;

namespace {

std::string hostName() {
  char host[256] = "host";
  ::gethostname(host, sizeof host - 1);
  host[sizeof host - 1] = '\0';
  return host;
}

// fsync of the file at `path`, opened again (Linux flushes the file's pages whoever wrote them).
void syncFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error("cannot open " + path + " to sync it: " + std::strerror(errno));
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0) throw std::runtime_error("cannot fsync " + path + ": " + std::strerror(err));
}

void syncFolder(const fs::path& folder) {
  const int fd = ::open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;  // some shared file systems refuse to open folders: the rename still stands
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

std::string temporaryPathFor(const std::string& finalPath) {
  static const std::string host = hostName();
  thread_local std::mt19937_64 nonces{(static_cast<uint64_t>(std::random_device{}()) << 32) ^ std::random_device{}()};
  char nonce[17];
  std::snprintf(nonce, sizeof nonce, "%016llx", static_cast<unsigned long long>(nonces()));
  const fs::path p(finalPath);
  // Appended piecewise: GCC 12's -Wrestrict misreads `"." + std::string&&` (a false positive).
  std::string name = ".";
  name += p.stem().string();
  name += ".tmp-";
  name += host;
  name += "-";
  name += std::to_string(::getpid());
  name += "-";
  name += nonce;
  name += p.extension().string();
  return (p.parent_path() / name).string();
}

bool isTemporaryFileName(const std::string& fileName) {
  static const std::regex temporary(R"(\..*\.tmp-.+-[0-9]+-[0-9a-f]{16}(\.[^.]*)?)");
  return std::regex_match(fileName, temporary);
}

void writeAtomically(const std::string& finalPath, const std::function<void(const std::string&)>& write, Durability durability) {
  const std::string temp = temporaryPathFor(finalPath);
  try {
    write(temp);
    if (durability == Durability::Durable) syncFile(temp);
    std::error_code ec;
    fs::rename(temp, finalPath, ec);
    if (ec) throw std::runtime_error("cannot rename " + temp + " to " + finalPath + ": " + ec.message());
  } catch (...) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw;
  }
  if (durability == Durability::Durable) syncFolder(fs::path(finalPath).parent_path());
}

void writeStreamAtomically(const std::string& finalPath, const std::function<void(std::ostream& out)>& write, Durability durability) {
  writeAtomically(
      finalPath,
      [&](const std::string& temp) {
        std::ofstream out(temp, std::ios::binary | std::ios::trunc);
        if (!out) throw std::runtime_error("cannot write " + temp);
        write(out);
        out.close();  // a full disk or quota often shows only here, on shared storage too
        if (!out) throw std::runtime_error("write failed: " + temp);
      },
      durability);
}

void writeTextAtomically(const std::string& finalPath, const std::string& bytes) {
  writeStreamAtomically(finalPath, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

}  // namespace snow
