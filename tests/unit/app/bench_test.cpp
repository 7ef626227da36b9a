// The sweep spec of `kaskad bench`: products, alternatives and the bound on their size, checked
// before anything is allocated for them.
#include <gtest/gtest.h>

#include <string>

#include "runtime/app/bench.h"

namespace kaskad {
namespace {

std::string values(int n) {
  std::string s;
  for (int i = 1; i <= n; ++i) {
    if (i > 1) s += ',';
    s += std::to_string(i);
  }
  return s;
}

TEST(BenchSweep, ProductsAndAlternativesExpandInOrder) {
  auto configs = parse_sweep("shadow.cascade_count=1,2;shadow.filter=none,pcf3x3|shadow.map_size=512");
  ASSERT_TRUE(configs.ok()) << configs.error().to_string();
  ASSERT_EQ(configs->size(), 5u);
  EXPECT_EQ((*configs)[1].label, "cascade_count=1 filter=pcf3x3");
  EXPECT_EQ((*configs)[4].sets, std::vector<std::string>{"shadow.map_size=512"});
}

// A million configurations (100 x 100 x 100) is refused at once, naming the key that crosses
// the limit; exactly the limit is fine.
TEST(BenchSweep, ASweepOfMoreThanTheLimitIsRefusedBeforeItExpands) {
  auto huge = parse_sweep("shadow.constant_bias=" + values(100) + ";shadow.slope_bias=" +
                          values(100) + ";shadow.map_size=" + values(100));
  ASSERT_FALSE(huge.ok());
  EXPECT_EQ(huge.error().file, "--sweep");
  EXPECT_EQ(huge.error().where, "shadow.map_size");
  EXPECT_NE(huge.error().message.find("more than " + std::to_string(kMaxSweepConfigurations)),
            std::string::npos)
      << huge.error().message;
  ASSERT_EQ(kMaxSweepConfigurations, 10000u);
  EXPECT_TRUE(parse_sweep("a=" + values(100) + ";b=" + values(100)).ok());
  std::string alternatives = "a=" + values(100) + ";b=" + values(100);
  auto twice = parse_sweep(alternatives + "|c=1");
  ASSERT_FALSE(twice.ok());
  EXPECT_NE(twice.error().message.find("more than"), std::string::npos);
}

}  // namespace
}  // namespace kaskad
