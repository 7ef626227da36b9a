// The one hash of cache keys and signatures (runtime/core/hash.h): equal inputs hash equal, every
// changed bit changes the value, order and value sizes count, and a value is never 0.
#include <gtest/gtest.h>

#include <cstdint>
#include <set>
#include <string>

#include "runtime/core/hash.h"

namespace kaskad {
namespace {

struct Odd {
  std::uint8_t bytes[13];
};

TEST(Hash, EqualInputsHashEqualAndEveryBitCounts) {
  Odd x{};
  for (int i = 0; i < 13; ++i) x.bytes[i] = std::uint8_t(i * 37);
  const std::uint64_t base = Hash().add(x).add(2.5f).value();
  EXPECT_EQ(Hash().add(x).add(2.5f).value(), base);
  EXPECT_NE(base, 0u);
  std::set<std::uint64_t> seen{base};
  for (int byte = 0; byte < 13; ++byte)
    for (int bit = 0; bit < 8; ++bit) {
      Odd y = x;
      y.bytes[byte] ^= std::uint8_t(1u << bit);
      const std::uint64_t h = Hash().add(y).add(2.5f).value();
      EXPECT_NE(h, 0u);
      EXPECT_TRUE(seen.insert(h).second) << "byte " << byte << " bit " << bit;
    }
  // Order and grouping count.
  EXPECT_NE(Hash().add(1.0f).add(2.0f).value(), Hash().add(2.0f).add(1.0f).value());
  EXPECT_NE(Hash().add(std::uint32_t(0)).value(), Hash().add(std::uint64_t(0)).value());
}

TEST(Hash, TextsChainAndAreStable) {
  // Names of cache files: the value of a text is fixed (XXH3's specification), so a binary
  // cached by one build is found by the next. The empty input's XXH3-64 with seed 0 is
  // 0x2d06800538d394c2 (the reference implementation's test vector).
  EXPECT_EQ(hash_bytes(std::string_view()), 0x2d06800538d394c2ull);
  const std::string a(300, 'a'), b = "void main() {}";
  EXPECT_EQ(hash_bytes(b, hash_bytes(a)), hash_bytes(b, hash_bytes(a)));
  EXPECT_NE(hash_bytes(b, hash_bytes(a)), hash_bytes(a, hash_bytes(b)));
  EXPECT_NE(hash_bytes(a + "x"), hash_bytes(a + "y"));  // past XXH3's 240-byte short path
}

}  // namespace
}  // namespace kaskad
