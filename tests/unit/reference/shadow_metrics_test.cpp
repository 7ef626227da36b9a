// Shadow accuracy and stability metrics on hand-made images with known counts.
#include "runtime/reference/shadow_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace kaskad::reference {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// Per-pixel arrays of a width x height image; every pixel a receiver, reference and method lit.
struct Pixels {
  int width, height;
  std::vector<float> method, reference;
  std::vector<std::uint8_t> receiver;

  Pixels(int w, int h)
      : width(w),
        height(h),
        method(std::size_t(w) * h, 1.0f),
        reference(std::size_t(w) * h, 1.0f),
        receiver(std::size_t(w) * h, 1) {}
  std::size_t at(int x, int y) const { return std::size_t(y) * width + x; }
  ShadowMetrics metrics() const {
    return compare_shadows(width, height, method, reference, receiver);
  }
};

/// 10 x 10, reference shadowed for x < 5; the method equals it except for 3 false shadows and
/// 2 false lights, all away from the edge between columns 4 and 5.
Pixels half_shadowed() {
  Pixels p(10, 10);
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 5; ++x) p.reference[p.at(x, y)] = p.method[p.at(x, y)] = 0.0f;
  for (auto [x, y] : {std::pair{8, 1}, {8, 5}, {9, 9}}) p.method[p.at(x, y)] = 0.0f;
  for (auto [x, y] : {std::pair{1, 2}, {0, 7}}) p.method[p.at(x, y)] = 1.0f;
  return p;
}

TEST(ShadowMetrics, CountsFalseShadowsAndFalseLights) {
  const ShadowMetrics m = half_shadowed().metrics();
  EXPECT_EQ(m.all.pixels, 100u);
  EXPECT_EQ(m.all.misclassified, 5u);
  EXPECT_EQ(m.all.false_shadow, 3u);
  EXPECT_EQ(m.all.false_light, 2u);
  EXPECT_DOUBLE_EQ(m.all.misclassified_pct, 5.0);
  EXPECT_DOUBLE_EQ(m.all.false_shadow_pct, 3.0);
  EXPECT_DOUBLE_EQ(m.all.false_light_pct, 2.0);
  EXPECT_DOUBLE_EQ(m.all.rmse, std::sqrt(5.0 / 100.0));
  EXPECT_DOUBLE_EQ(m.all.mean_abs_error, 0.05);
  EXPECT_EQ(m.non_finite, 0u);
}

TEST(ShadowMetrics, EdgeBandIsTheOnePixelBorderOfReferenceShadows) {
  Pixels p = half_shadowed();
  ShadowMetrics m = p.metrics();
  // Columns 4 and 5 each have a neighbour on the other side: 20 pixels in the band.
  EXPECT_EQ(m.edge_pixels, 20u);
  EXPECT_EQ(m.outside_edges.pixels, 80u);
  EXPECT_EQ(m.outside_edges.misclassified, 5u);
  EXPECT_EQ(m.outside_edges.false_shadow, 3u);
  EXPECT_EQ(m.outside_edges.false_light, 2u);
  EXPECT_DOUBLE_EQ(m.outside_edges.misclassified_pct, 100.0 * 5 / 80);
  EXPECT_DOUBLE_EQ(m.outside_edges.rmse, std::sqrt(5.0 / 80.0));
  EXPECT_DOUBLE_EQ(m.outside_edges.mean_abs_error, 5.0 / 80.0);
  // An error on the edge (column 5: reference lit, method shadowed) counts only in `all`.
  p.method[p.at(5, 3)] = 0.0f;
  m = p.metrics();
  EXPECT_EQ(m.all.false_shadow, 4u);
  EXPECT_EQ(m.outside_edges.false_shadow, 3u);
  // An error next to the edge but not on it (column 6) counts in both.
  p.method[p.at(6, 3)] = 0.0f;
  m = p.metrics();
  EXPECT_EQ(m.all.false_shadow, 5u);
  EXPECT_EQ(m.outside_edges.false_shadow, 4u);
}

TEST(ShadowMetrics, BandUsesAllEightNeighboursAndOnlyReceivers) {
  Pixels p(5, 5);
  p.reference[p.at(2, 2)] = 0.0f;  // one shadowed pixel: itself and its 8 neighbours are edges
  EXPECT_EQ(p.metrics().edge_pixels, 9u);
  p.reference[p.at(0, 0)] = 0.0f;  // a corner: itself and 3 neighbours, (1, 1) already counted
  EXPECT_EQ(p.metrics().edge_pixels, 12u);
  // Non-receivers neither count nor make edges.
  p.receiver[p.at(2, 2)] = 0;
  p.receiver[p.at(0, 0)] = 0;
  const ShadowMetrics m = p.metrics();
  EXPECT_EQ(m.edge_pixels, 0u);
  EXPECT_EQ(m.all.pixels, 23u);
  EXPECT_EQ(m.outside_edges.pixels, 23u);
}

TEST(ShadowMetrics, FractionalVisibilityAndTheThreshold) {
  Pixels p(4, 1);
  p.reference = {0.6f, 0.49f, 0.5f, 0.2f};
  p.method = {0.4f, 0.5f, 0.7f, 0.3f};
  const ShadowMetrics m = p.metrics();
  EXPECT_EQ(m.all.false_shadow, 1u);  // 0.4 < 0.5 <= 0.6
  EXPECT_EQ(m.all.false_light, 1u);   // 0.5 counts as lit
  EXPECT_EQ(m.all.misclassified, 2u);
  const double d[] = {0.2, 0.01, 0.2, 0.1};
  double sq = 0, ab = 0;
  for (double v : d) {
    sq += v * v;
    ab += v;
  }
  EXPECT_NEAR(m.all.rmse, std::sqrt(sq / 4), 1e-6);
  EXPECT_NEAR(m.all.mean_abs_error, ab / 4, 1e-6);
}

TEST(ShadowMetrics, NonFiniteAndEmptyInputs) {
  Pixels p(3, 3);
  p.method[p.at(1, 1)] = kNaN;
  p.reference[p.at(0, 0)] = 0.0f;
  p.reference[p.at(2, 2)] = std::numeric_limits<float>::infinity();
  const ShadowMetrics m = p.metrics();
  EXPECT_EQ(m.non_finite, 2u);
  EXPECT_EQ(m.all.pixels, 7u);
  EXPECT_EQ(m.all.false_light, 1u);
  EXPECT_EQ(m.edge_pixels, 3u);  // (0,0), (1,0), (0,1); (1,1) is not counted
  EXPECT_TRUE(std::isfinite(m.all.rmse));

  const ShadowMetrics none = Pixels(0, 0).metrics();
  EXPECT_EQ(none.all.pixels, 0u);
  EXPECT_EQ(none.all.rmse, 0.0);
  EXPECT_EQ(none.all.misclassified_pct, 0.0);
  Pixels no_receivers(4, 4);
  no_receivers.receiver.assign(16, 0);
  no_receivers.method.assign(16, 0.0f);
  const ShadowMetrics empty = no_receivers.metrics();
  EXPECT_EQ(empty.all.pixels, 0u);
  EXPECT_EQ(empty.all.misclassified, 0u);
  EXPECT_EQ(empty.all.false_shadow_pct, 0.0);
}

TEST(ShadowMetrics, FromImagesByChannelName) {
  const Pixels p = half_shadowed();
  Image aov;
  aov.width = 10;
  aov.height = 10;
  aov.channel_names = {"P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z", "Z", "visibility", "mask"};
  aov.channels = 9;
  aov.pixels.assign(100 * 9, 0.0f);
  Image ref;
  ref.width = 10;
  ref.height = 10;
  ref.channel_names = {"receiver", "visibility"};  // reordered, as an EXR may come back
  ref.channels = 2;
  ref.pixels.assign(100 * 2, 0.0f);
  for (int i = 0; i < 100; ++i) {
    aov.pixels[i * 9 + 7] = p.method[i];
    ref.pixels[i * 2 + 0] = 1.0f;
    ref.pixels[i * 2 + 1] = p.reference[i];
  }
  const auto m = compare_shadows(aov, ref);
  ASSERT_TRUE(m.ok()) << m.error().to_string();
  EXPECT_EQ(m->all.false_shadow, 3u);
  EXPECT_EQ(m->all.false_light, 2u);
  EXPECT_EQ(m->edge_pixels, 20u);

  Image wrong = ref;
  wrong.channel_names = {"mask", "visibility"};
  ASSERT_FALSE(compare_shadows(aov, wrong).ok());
  EXPECT_NE(compare_shadows(aov, wrong).error().message.find("'receiver'"), std::string::npos);
  Image no_vis = aov;
  no_vis.channel_names[7] = "V";
  EXPECT_FALSE(compare_shadows(no_vis, ref).ok());
  Image smaller = ref;
  smaller.height = 5;
  smaller.pixels.resize(50 * 2);
  const auto mismatch = compare_shadows(aov, smaller);
  ASSERT_FALSE(mismatch.ok());
  EXPECT_NE(mismatch.error().message.find("10x5"), std::string::npos);
  Image broken = aov;
  broken.pixels.pop_back();
  EXPECT_FALSE(compare_shadows(broken, ref).ok());
}

TEST(ShadowStability, FlickerAndChangedPoints) {
  const std::vector<std::vector<float>> frames = {
      {1, 1, 0, 0},
      {1, 0, 0, 0},
      {1, 0, 0, 1},
  };
  const StabilityStats s = shadow_stability(frames);
  EXPECT_EQ(s.frames, 3u);
  EXPECT_EQ(s.points, 4u);
  EXPECT_EQ(s.samples, 8u);
  EXPECT_DOUBLE_EQ(s.flicker, 0.25);
  EXPECT_DOUBLE_EQ(s.changed_pct, 25.0);
  ASSERT_EQ(s.flicker_per_frame.size(), 2u);
  EXPECT_DOUBLE_EQ(s.flicker_per_frame[0], 0.25);
  EXPECT_DOUBLE_EQ(s.flicker_per_frame[1], 0.25);
}

TEST(ShadowStability, SmallChangesFlickerWithoutCountingAsChanges) {
  const float tiny = 0.5f / 255.0f;
  const StabilityStats s = shadow_stability({{0.5f, 0.5f}, {0.5f + tiny, 0.9f}});
  EXPECT_NEAR(s.flicker, (tiny + 0.4) / 2, 1e-6);
  EXPECT_DOUBLE_EQ(s.changed_pct, 50.0);
  EXPECT_DOUBLE_EQ(shadow_stability({{0.5f, 0.5f}, {0.5f + tiny, 0.9f}}, 0.0f).changed_pct, 100.0);
}

TEST(ShadowStability, HiddenPointsAndDegenerateInputs) {
  // Point 1 is off screen in frame 1: both of its pairs are left out.
  const StabilityStats s = shadow_stability({{0, 1}, {1, kNaN}, {1, 0}});
  EXPECT_EQ(s.samples, 2u);
  EXPECT_DOUBLE_EQ(s.flicker, 0.5);
  EXPECT_DOUBLE_EQ(s.changed_pct, 50.0);
  const StabilityStats none = shadow_stability({});
  EXPECT_EQ(none.frames, 0u);
  EXPECT_EQ(none.flicker, 0.0);
  const StabilityStats one = shadow_stability({{0, 1, 0}});
  EXPECT_EQ(one.samples, 0u);
  EXPECT_TRUE(one.flicker_per_frame.empty());
  EXPECT_DEATH(shadow_stability({{1, 0}, {1}}), "every frame must have 2 points");
}

}  // namespace
}  // namespace kaskad::reference
