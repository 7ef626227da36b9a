// World-space stability (runtime/app/stability.h): the shadow-points pass evaluates the forward
// pass's own shadow lookup at fixed world points, and a camera path measures flicker there.
#include <gtest/gtest.h>

#include <cmath>

#include "runtime/app/player.h"
#include "tests/render/player_fixture.h"
#include "runtime/app/stability.h"
#include "runtime/gpu/context.h"

namespace kaskad {
namespace {

class StabilityTest : public PlayerTest {
 protected:
  static Scene load(std::vector<std::string> sets) {
    sets.push_back("render.width=320");
    sets.push_back("render.height=180");
    auto scene = load_scene(content_dir() / "scenes" / "default.json", sets);
    EXPECT_TRUE(scene.ok()) << scene.error().to_string();
    return std::move(scene.value());
  }

  // The scene's AOVs after one frame, and receiver points taken from them.
  static StabilityPoints points_of(Scene& scene, Image* aov_out = nullptr) {
    auto t = render_frames(*player_, scene, {});
    EXPECT_TRUE(t.ok()) << t.error().to_string();
    const Image aov = player_->renderer->read_aovs();
    if (aov_out) *aov_out = aov;
    auto points = stability_points(aov, 3000);
    EXPECT_TRUE(points.ok()) << points.error().to_string();
    return points.ok() ? points.value() : StabilityPoints{};
  }

};

// The points pass and the forward pass run the same lookup on the same inputs (the AOV stores the
// interpolated position and the facing normal the forward pass used), so they agree per point.
TEST_F(StabilityTest, PointsPassMatchesTheForwardPassAtTheSamePoints) {
  struct Case {
    const char* scene;
    std::vector<std::string> sets;
  };
  const std::vector<Case> cases = {
      {"default", {"shadow.filter=none"}},
      {"default", {"shadow.filter=pcf3x3"}},
      {"two_suns", {"render.aov_shadow_light=1"}},  // the AOV shows the second light
      {"spot", {}},
      {"point", {"shadow.point_mode=cube"}},
      {"point", {"shadow.point_mode=dual_paraboloid"}},
      // The moments' filter follows the footprint from the point and normal alone, so the
      // points pass (no screen derivatives) reads what the forward pass reads.
      {"default", {"shadow.technique=vsm"}},
      {"spot", {"shadow.technique=evsm"}}};
  for (const Case& c : cases) {
    std::vector<std::string> sets = c.sets;
    sets.push_back("render.width=320");
    sets.push_back("render.height=180");
    auto loaded = load_scene(content_dir() / "scenes" / (std::string(c.scene) + ".json"), sets);
    ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
    Scene scene = std::move(loaded.value());
    Image aov;
    const StabilityPoints points = points_of(scene, &aov);
    ASSERT_GT(points.positions.size(), 1000u) << c.scene;
    auto values = player_->renderer->shadow_at_points(points.positions, points.normals);
    ASSERT_TRUE(values.ok()) << values.error().to_string();
    ASSERT_EQ(values->size(), points.positions.size());
    std::size_t same = 0, shadowed = 0;
    for (std::size_t i = 0; i < points.pixels.size(); ++i) {
      const glm::ivec2 px = points.pixels[i];
      const float forward = aov.at(px.x, px.y, 7);
      same += std::abs((*values)[i].x - forward) < 1e-4f && (*values)[i].y == aov.at(px.x, px.y, 9);
      shadowed += forward < 0.5f;
    }
    std::printf("[ %s %s ] %zu of %zu points agree (%zu shadowed)\n", c.scene,
                c.sets.empty() ? "" : c.sets[0].c_str(), same, points.positions.size(), shadowed);
    EXPECT_GT(shadowed, 20u) << c.scene;  // the comparison covers shadowed points too
    EXPECT_GE(double(same), 0.999 * double(points.positions.size())) << c.scene;
  }
}

TEST_F(StabilityTest, WithoutShadowsEveryPointIsLit) {
  Scene scene = load({"sun.light.cast_shadows=false"});
  const StabilityPoints points = points_of(scene);
  ASSERT_FALSE(points.positions.empty());
  auto values = player_->renderer->shadow_at_points(points.positions, points.normals);
  ASSERT_TRUE(values.ok()) << values.error().to_string();
  for (const glm::vec2& v : *values) {
    ASSERT_EQ(v.x, 1.0f);
    ASSERT_EQ(v.y, -1.0f);
  }
}

TEST_F(StabilityTest, MismatchedSizesAreAnError) {
  const std::vector<glm::vec3> p(3), n(2);
  EXPECT_FALSE(player_->renderer->shadow_at_points(p, n).ok());
}

// S2: a stabilised cascade does not flicker under camera translation (exactly 0); the crop fit,
// which follows the view frustum continuously, does. Band 0: no blend band between cascades.
TEST_F(StabilityTest, StableFitHasZeroFlickerUnderTranslationAndCropDoesNot) {
  for (const char* cascades : {"1", "4"}) {
    double flicker[2] = {0, 0};
    int k = 0;
    for (const char* fit : {"stable", "crop"}) {
      Scene scene = load({std::string("shadow.cascade_count=") + cascades,
                          std::string("shadow.fit_mode=") + fit, "shadow.blend_band=0"});
      const StabilityPoints points = points_of(scene);
      ASSERT_GT(points.positions.size(), 1000u);
      CameraPath path;
      path.frames = 12;
      auto run = measure_stability(*player_, scene, points, path);
      ASSERT_TRUE(run.ok()) << run.error().to_string();
      EXPECT_EQ(run->stats.frames, 12u);
      EXPECT_GT(run->step, 0.0f);
      std::printf("[ %s cascade(s), %s ] flicker %.6g, %.3f %% of samples changed\n", cascades,
                  fit, run->stats.flicker, run->stats.changed_pct);
      flicker[k++] = run->stats.flicker;
    }
    EXPECT_EQ(flicker[0], 0.0) << cascades << " stable cascade(s)";
    EXPECT_GT(flicker[1], 0.0) << cascades << " crop cascade(s)";
  }
}

// With the blend band the weight follows each point's view depth, which the camera's translation
// perturbs by float rounding only (the path keeps depths constant): changes stay far below one
// 8-bit step, and no sample counts as changed.
TEST_F(StabilityTest, BlendBandAddsOnlyRoundingNoise) {
  Scene scene = load({"shadow.cascade_count=4", "shadow.fit_mode=stable", "shadow.blend_band=0.2"});
  const StabilityPoints points = points_of(scene);
  CameraPath path;
  path.frames = 12;
  auto run = measure_stability(*player_, scene, points, path);
  ASSERT_TRUE(run.ok()) << run.error().to_string();
  std::printf("[ 4 stable cascades, band 0.2 ] flicker %.3g, %.3f %% changed\n", run->stats.flicker,
              run->stats.changed_pct);
  EXPECT_LT(run->stats.flicker, 1e-6);
  EXPECT_EQ(run->stats.changed_pct, 0.0);
}

}  // namespace
}  // namespace kaskad
