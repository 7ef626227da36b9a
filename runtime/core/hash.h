// The one hash of Kaskad's cache keys and signatures: XXH3, 64 bits (libxxhash, compiled inline
// here). What a cached result was made from (shadow-map layers, stored visibility, a probe's
// surroundings, the reference's geometry) and the shader binary cache's file names. XXH3's output
// is fixed by its specification, so a value is the same across runs, builds and machines. For
// equality of non-adversarial inputs, not a cryptographic hash.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <type_traits>

#define XXH_INLINE_ALL
#include <xxhash.h>

namespace kaskad {

/// XXH3-64 of `size` bytes at `data`, seeded: hash_bytes(b, n, hash_bytes(a, m)) chains a then b.
inline std::uint64_t hash_bytes(const void* data, std::size_t size, std::uint64_t seed = 0) {
  return XXH3_64bits_withSeed(data, size, seed);
}
inline std::uint64_t hash_bytes(std::string_view text, std::uint64_t seed = 0) {
  return hash_bytes(text.data(), text.size(), seed);
}

/// An order-dependent hash of plain values fed one at a time: equal sequences give equal
/// values, and each value's size counts (a 4-byte 0 and an 8-byte 0 differ). value() is never 0,
/// which callers keep for "nothing stored".
class Hash {
 public:
  template <typename T>
  Hash& add(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>, "Hash::add takes the bytes of plain values");
    return add_bytes(&v, sizeof v);
  }
  Hash& add_bytes(const void* data, std::size_t size) {
    h_ = hash_bytes(data, size, h_);
    return *this;
  }
  std::uint64_t value() const { return h_ | 1u; }

 private:
  std::uint64_t h_ = 0;
};

}  // namespace kaskad
