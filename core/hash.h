// FNV-1a 64-bit: a small, stable content hash for input fingerprints in the manifest and cache
// keys (not cryptographic).
#pragma once
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>
#include <string_view>

namespace snow {

class Fnv1a64 {
 public:
  Fnv1a64& add(const void* data, size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) {
      h_ ^= p[i];
      h_ *= 0x100000001b3ull;
    }
    return *this;
  }
  Fnv1a64& add(std::string_view s) { return add(s.data(), s.size()); }
  uint64_t value() const { return h_; }
  std::string hex() const {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h_));
    return buf;
  }

 private:
  uint64_t h_ = 0xcbf29ce484222325ull;
};

// The FNV-1a 64 hex digest of a file's bytes (of nothing when it cannot be read).
inline std::string hashFileFnv1a64(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  Fnv1a64 h;
  std::vector<char> buf(1 << 16);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    h.add(buf.data(), static_cast<size_t>(in.gcount()));
  }
  return h.hex();
}

}  // namespace snow
