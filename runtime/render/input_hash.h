// FNV-1a over the bytes of plain values: what a cached result was made from (shadow-map layers,
// the main view's stored shadow visibility). Equal inputs give equal values; a value is never 0,
// which callers keep for "nothing stored".
#pragma once

#include <cstdint>
#include <cstring>
#include <type_traits>

namespace kaskad::render {

struct InputHash {
  std::uint64_t h = 14695981039346656037ull;
  template <typename T>
  InputHash& add(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));
    for (unsigned char b : bytes) h = (h ^ b) * 1099511628211ull;
    return *this;
  }
  std::uint64_t value() const { return h | 1u; }
};

}  // namespace kaskad::render
