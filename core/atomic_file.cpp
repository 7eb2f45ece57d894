#include "atomic_file.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace snow {

namespace fs = std::filesystem;

std::string temporaryPathFor(const std::string& finalPath) {
  const fs::path p(finalPath);
  // Appended piecewise: GCC 12's -Wrestrict misreads `"." + std::string&&` (a false positive).
  std::string name = ".";
  name += p.stem().string();
  name += ".tmp";
  name += std::to_string(::getpid());
  name += p.extension().string();
  return (p.parent_path() / name).string();
}

void writeAtomically(const std::string& finalPath, const std::function<void(const std::string&)>& write) {
  const std::string temp = temporaryPathFor(finalPath);
  try {
    write(temp);
    std::error_code ec;
    fs::rename(temp, finalPath, ec);
    if (ec) throw std::runtime_error("cannot rename " + temp + " to " + finalPath + ": " + ec.message());
  } catch (...) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw;
  }
}

void writeStreamAtomically(const std::string& finalPath, const std::function<void(std::ostream& out)>& write) {
  writeAtomically(finalPath, [&](const std::string& temp) {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + temp);
    write(out);
    out.flush();
    if (!out) throw std::runtime_error("write failed: " + temp);
  });
}

void writeTextAtomically(const std::string& finalPath, const std::string& bytes) {
  writeStreamAtomically(finalPath, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

}  // namespace snow
