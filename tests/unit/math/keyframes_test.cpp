// Keyframe tracks (runtime/math/keyframes.h) against glTF 2.0 Appendix C: clamped ends, step,
// linear and slerped rotations, cubic Hermite splines with their tangents, and the checks that
// refuse a track that cannot be sampled.
#include "runtime/math/keyframes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/quaternion.hpp>

namespace kaskad {
namespace {

KeyTrack track(KeyInterpolation interpolation, std::vector<float> times,
               std::vector<glm::vec4> values, KeyKind kind = KeyKind::vector) {
  KeyTrack t;
  t.interpolation = interpolation;
  t.kind = kind;
  t.times = std::move(times);
  t.values = std::move(values);
  return t;
}

void expect_near(const glm::vec4& a, const glm::vec4& b, float eps = 1e-5f) {
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(a[i], b[i], eps) << "component " << i;
}

TEST(Keyframes, StepAndLinearAreClampedAtBothEnds) {
  const KeyTrack lin = track(KeyInterpolation::linear, {1, 3}, {{0, 0, 0, 0}, {4, 2, 0, 0}});
  ASSERT_EQ(validate_track(lin), "");
  expect_near(sample(lin, -5), {0, 0, 0, 0});
  expect_near(sample(lin, 1), {0, 0, 0, 0});
  expect_near(sample(lin, 2.5f), {3, 1.5f, 0, 0});
  expect_near(sample(lin, 3), {4, 2, 0, 0});
  expect_near(sample(lin, 99), {4, 2, 0, 0});
  KeyTrack step = lin;
  step.interpolation = KeyInterpolation::step;
  expect_near(sample(step, 2.999f), {0, 0, 0, 0});  // the earlier key holds until the next
  expect_near(sample(step, 3), {4, 2, 0, 0});
}

// Rotations slerp along the shorter arc: a key given as -q turns the same way as q, and every
// sample has unit length.
TEST(Keyframes, RotationsSlerpTheShortWay) {
  const glm::quat a = glm::angleAxis(0.0f, glm::vec3(0, 1, 0));
  const glm::quat b = glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0));
  auto v = [](const glm::quat& q) { return glm::vec4(q.x, q.y, q.z, q.w); };
  const KeyTrack rot =
      track(KeyInterpolation::linear, {0, 1}, {v(a), -v(b)}, KeyKind::rotation);
  const glm::quat mid = glm::angleAxis(glm::radians(45.0f), glm::vec3(0, 1, 0));
  const glm::vec4 s = sample(rot, 0.5f);
  EXPECT_NEAR(std::abs(glm::dot(s, v(mid))), 1.0f, 1e-5f);
  for (float t = 0; t <= 1.0f; t += 0.125f) EXPECT_NEAR(glm::length(sample(rot, t)), 1.0f, 1e-5f);
}

// Hermite: with zero tangents the curve eases (value 0.5 at the middle, 0.15625 a quarter in);
// with tangents equal to the slope it is the straight line, whatever the interval's length.
TEST(Keyframes, CubicSplinesUseTheirTangentsScaledByTheInterval) {
  const glm::vec4 zero(0.0f), one(1.0f, 0, 0, 0), slope(0.5f, 0, 0, 0);  // 1 over 2 s
  const KeyTrack eased =
      track(KeyInterpolation::cubic_spline, {0, 2}, {zero, zero, zero, zero, one, zero});
  ASSERT_EQ(validate_track(eased), "");
  expect_near(sample(eased, 1), {0.5f, 0, 0, 0});
  expect_near(sample(eased, 0.5f), {0.15625f, 0, 0, 0});
  const KeyTrack straight =
      track(KeyInterpolation::cubic_spline, {0, 2}, {slope, zero, slope, slope, one, slope});
  for (float t = 0; t <= 2.0f; t += 0.25f) expect_near(sample(straight, t), {t / 2, 0, 0, 0});
  expect_near(sample(straight, 5), one);  // clamped to the last key's value, not its tangent
}

TEST(Keyframes, TracksThatCannotBeSampledAreRefused) {
  EXPECT_EQ(validate_track(track(KeyInterpolation::linear, {}, {})), "no keys");
  EXPECT_EQ(validate_track(track(KeyInterpolation::linear, {0, 0}, {{}, {}})),
            "key 1: times must increase strictly");
  EXPECT_EQ(validate_track(track(KeyInterpolation::linear, {0, NAN}, {{}, {}})),
            "key 1: time is not finite");
  EXPECT_EQ(validate_track(track(KeyInterpolation::cubic_spline, {0, 1}, {{}, {}})),
            "2 values for 2 keys (3 per key expected)");
  EXPECT_EQ(validate_track(track(KeyInterpolation::step, {0}, {{INFINITY, 0, 0, 0}})),
            "value 0 is not finite");
}

}  // namespace
}  // namespace kaskad
