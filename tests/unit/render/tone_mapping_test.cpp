// The tone-mapping curves (components/tone_mapping.h) at sampled inputs, against values worked
// out by hand from their published formulas, and their shape: monotonic, black stays black,
// nothing above 1.
#include <gtest/gtest.h>

#include "components/tone_mapping.h"

namespace kaskad {
namespace {

TEST(ToneMapping, AcesFittedCurveAtSampledInputs) {
  auto f = [](float x) { return tone_map(ToneMapping::aces, glm::vec3(x)).r; };
  EXPECT_FLOAT_EQ(f(0.0f), 0.0f);
  EXPECT_NEAR(f(1.0f), 2.54f / 3.16f, 1e-6f);  // (2.51 + 0.03) / (2.43 + 0.59 + 0.14)
  EXPECT_NEAR(f(0.18f), 0.18f * (2.51f * 0.18f + 0.03f) / (0.18f * (2.43f * 0.18f + 0.59f) + 0.14f),
              1e-6f);
  EXPECT_EQ(f(1000.0f), 1.0f);  // the fit tends to 2.51 / 2.43 > 1: clamped
  float last = -1.0f;
  for (float x = 0.0f; x < 20.0f; x += 0.01f) {
    EXPECT_GE(f(x), last) << x;
    last = f(x);
  }
}

TEST(ToneMapping, KhrPbrNeutralAtSampledInputs) {
  auto f = [](glm::vec3 c) { return tone_map(ToneMapping::khr_pbr_neutral, c); };
  // Mid grey is only shifted down by the 0.04 offset.
  EXPECT_NEAR(f(glm::vec3(0.5f)).r, 0.46f, 1e-6f);
  // Dark values get the smaller offset x - 6.25 x^2: 0.05 -> 0.05 - 0.034375.
  EXPECT_NEAR(f(glm::vec3(0.05f)).r, 0.015625f, 1e-6f);
  // White: peak 0.96 is compressed to 1 - 0.24^2 / (0.96 + 0.24 - 0.76) = 0.869091.
  EXPECT_NEAR(f(glm::vec3(1.0f)).r, 1.0f - 0.0576f / 0.44f, 1e-5f);
  // A saturated colour keeps its hue below the compression start and stays under 1 above it.
  const glm::vec3 red = f(glm::vec3(0.6f, 0.1f, 0.1f));
  EXPECT_NEAR(red.r, 0.56f, 1e-6f);
  EXPECT_NEAR(red.g, 0.06f, 1e-6f);
  const glm::vec3 bright = f(glm::vec3(50.0f, 2.0f, 1.0f));
  EXPECT_LT(bright.r, 1.0f);
  EXPECT_GT(bright.r, bright.g);
  float last = -1.0f;
  for (float x = 0.0f; x < 20.0f; x += 0.01f) {
    const float y = f(glm::vec3(x)).r;
    EXPECT_GE(y, last) << x;
    EXPECT_LE(y, 1.0f) << x;
    last = y;
  }
  EXPECT_EQ(f(glm::vec3(0.0f)), glm::vec3(0.0f));
}

TEST(ToneMapping, NoneIsTheIdentity) {
  EXPECT_EQ(tone_map(ToneMapping::none, glm::vec3(3.0f, 0.5f, 0.0f)), glm::vec3(3.0f, 0.5f, 0.0f));
}

}  // namespace
}  // namespace kaskad
