// FNV-1a 64-bit: a small, stable content hash for input fingerprints in the manifest and cache
// keys (not cryptographic).
#pragma once
#include <cstdint>
#include <cstdio>
#include <string>
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

}  // namespace snow
