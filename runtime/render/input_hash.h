// A 64-bit hash of plain values: what a cached result was made from (shadow-map layers, the main
// view's stored shadow visibility). Equal inputs give equal values; a value is never 0, which
// callers keep for "nothing stored".
//
// The bytes are taken 8 at a time, each word folded in by a 64x64 -> 128-bit multiply by a
// constant whose halves are xored (after wyhash's mixing step): a frame hashes every caster's
// matrix, and a byte-at-a-time hash (FNV-1a) of 10,000 casters cost about a millisecond. Good
// enough for cache keys of non-adversarial data, not a cryptographic hash.
#pragma once

#include <cstdint>
#include <cstring>
#include <type_traits>

namespace kaskad::render {

struct InputHash {
  std::uint64_t h = 0x243f6a8885a308d3ull;

  template <typename T>
  InputHash& add(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));
    std::size_t i = 0;
    // Compiled only for types of 8 bytes or more: GCC's ASan build warned of an 8-byte read from
    // smaller ones in the loop that never runs for them.
    if constexpr (sizeof(T) >= 8) {
      for (; i + 8 <= sizeof(T); i += 8) {
        std::uint64_t word;
        std::memcpy(&word, bytes + i, 8);
        fold(word);
      }
    }
    if (i < sizeof(T)) {  // the last 1-7 bytes, with their count in the top byte
      std::uint64_t word = std::uint64_t(sizeof(T) - i) << 56;
      std::memcpy(&word, bytes + i, sizeof(T) - i);
      fold(word);
    }
    return *this;
  }
  std::uint64_t value() const { return h | 1u; }

 private:
  __extension__ using Wide = unsigned __int128;  // GCC's and Clang's, on 64-bit targets

  void fold(std::uint64_t word) {
    const Wide r = Wide(h ^ word ^ 0xa0761d6478bd642full) * 0xe7037ed1a0b428dbull;
    h = std::uint64_t(r) ^ std::uint64_t(r >> 64);
  }
};

}  // namespace kaskad::render
