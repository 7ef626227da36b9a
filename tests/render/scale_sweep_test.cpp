// Shadows at any scale, as a new user gets them: third-party glTF models opened directly (the
// auto camera and sun, or the file's own camera; the automatic ground), their root scaled by
// 10^k for k = -3..4, every setting at its default. The visibility AOV must agree with the
// Embree reference on at least 99.5% of the receiver pixels away from shadow edges, and every
// cascade must hold receivers. Before the cascade range followed the visible receivers, most of
// these rows had no shadow at all (a fixed 100-unit max_distance).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <cstdio>
#include <string>

#include "components/light.h"
#include "components/transform.h"
#include "runtime/app/player.h"
#include "runtime/reference/ray_tracer.h"
#include "runtime/reference/shadow_metrics.h"
#include "tests/render/player_fixture.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

struct Case {
  const char* model;  ///< below content/models
  int k;              ///< the root is scaled by 10^k
};

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  const std::string m = info.param.model;
  char k[16];
  std::snprintf(k, sizeof k, "_k%s%d", info.param.k < 0 ? "m" : "", std::abs(info.param.k));
  return m.substr(0, m.find('/')) + k;
}

class ScaleSweepTest : public PlayerTest, public ::testing::WithParamInterface<Case> {};

TEST_P(ScaleSweepTest, ShadowsAgreeWithTheReferenceAtDefaultSettings) {
  const Case c = GetParam();
  const float s = std::pow(10.0f, float(c.k));
  char scale[96];
  std::snprintf(scale, sizeof scale, "model.transform.scale=[%g,%g,%g]", double(s), double(s),
                double(s));
  auto scene = load_scene(content_dir() / "models" / c.model,
                          {scale, "render.width=320", "render.height=180"});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  ASSERT_EQ(scene->render.ground, GroundMode::on);
  RenderRun run;
  run.frames = 2;
  auto t = render_frames(*player_, *scene, run);
  ASSERT_TRUE(t.ok()) << t.error().to_string();
  const ShadowData& sh = t->last.shadow();
  ASSERT_TRUE(sh.light.valid()) << "no shadowed light: " << sh.error;
  const Image aov = player_->renderer->read_aovs();
  auto tracer = reference::RayTracer::build(*scene);
  ASSERT_TRUE(tracer.ok()) << tracer.error().to_string();
  const auto light = reference::reference_light(scene->world, sh.light);
  auto ref = tracer->shadow_reference(aov, light, {});
  ASSERT_TRUE(ref.ok()) << ref.error().to_string();
  auto m = reference::compare_shadows(aov, ref->image);
  ASSERT_TRUE(m.ok()) << m.error().to_string();

  std::string splits;
  for (int i = 0; i <= sh.cascade_count; ++i) {
    char b[32];
    std::snprintf(b, sizeof b, "%s%.3g", i ? " " : "", double(sh.splits[std::size_t(i)]));
    splits += b;
  }
  // One row of the scale-sweep table: model, scale, misclassified % (all, away from edges),
  // splits, median frame ms (summarised in docs/design/cascades.md).
  std::printf("| %s | 1e%d | %.3f | %.3f | %s | %.1f |\n", c.model, c.k, m->all.misclassified_pct,
              m->outside_edges.misclassified_pct, splits.c_str(), t->median_ms());

  // Enough receivers, some in shadow, for agreement to mean something.
  EXPECT_GT(m->outside_edges.pixels, 2000u);
  const auto& names = ref->image.channel_names;
  const int receiver = int(std::find(names.begin(), names.end(), "receiver") - names.begin());
  const int visibility = int(std::find(names.begin(), names.end(), "visibility") - names.begin());
  ASSERT_LT(receiver, ref->image.channels);
  ASSERT_LT(visibility, ref->image.channels);
  std::size_t shadowed = 0;
  for (int y = 0; y < aov.height; ++y)
    for (int x = 0; x < aov.width; ++x)
      shadowed += ref->image.at(x, y, receiver) > 0.5f && ref->image.at(x, y, visibility) < 0.5f;
  EXPECT_GT(shadowed, 100u) << "no shadow to compare";
  EXPECT_LE(m->outside_edges.misclassified_pct, 0.5)
      << m->outside_edges.misclassified << " of " << m->outside_edges.pixels
      << " misclassified away from edges (" << m->outside_edges.false_shadow << " false shadow, "
      << m->outside_edges.false_light << " false light); splits " << splits;
  for (int i = 0; i < sh.cascade_count; ++i)
    EXPECT_GT(t->last.stats.cascade_receiver_pixels[std::size_t(i)], 0u)
        << "cascade " << i << " holds no receiver pixel; splits " << splits;
}

std::vector<Case> cases() {
  std::vector<Case> out;
  for (const char* model :
       {"Box/glTF-Binary/Box.glb", "Fox/glTF/Fox.gltf", "CesiumMilkTruck/glTF/CesiumMilkTruck.gltf",
        "2CylinderEngine/glTF-Draco/2CylinderEngine.gltf"})
    for (int k = -3; k <= 4; ++k) out.push_back({model, k});
  return out;
}

INSTANTIATE_TEST_SUITE_P(Models, ScaleSweepTest, ::testing::ValuesIn(cases()), case_name);

}  // namespace
}  // namespace kaskad

namespace kaskad {
namespace {

class AspectTest : public PlayerTest {};

// A camera with aspect 1 rendered at 16:9: the output is fitted to 180x180 and a sphere in the
// middle of the view stays round (its mask is as wide as it is tall), never stretched 1.78x.
TEST_F(AspectTest, ACameraWithItsOwnAspectIsFittedNotStretched) {
  const std::filesystem::path dir = testing_util::test_tmp();
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / "square_camera.json";
  std::FILE* f = std::fopen(file.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fputs(R"({"entities": [
    {"name": "ball", "primitive": {"shape": "sphere", "segments": 64}},
    {"name": "sun", "transform": {"direction": [0, -1, -0.2]}, "light": {"type": "directional"}},
    {"name": "camera", "transform": {"translation": [0, 0, 4], "look_at": [0, 0, 0]},
     "camera": {"fov_y_deg": 30, "aspect": 1, "active": true}}]})",
             f);
  std::fclose(f);
  auto scene = load_scene(file, {"render.width=320", "render.height=180"});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  EXPECT_EQ(scene->render.width, 180);
  EXPECT_EQ(scene->render.height, 180);
  auto t = render_frames(*player_, *scene, {});
  ASSERT_TRUE(t.ok()) << t.error().to_string();
  const Image aov = player_->renderer->read_aovs();
  ASSERT_EQ(aov.width, 180);
  int x0 = aov.width, x1 = -1, y0 = aov.height, y1 = -1;
  for (int y = 0; y < aov.height; ++y)
    for (int x = 0; x < aov.width; ++x)
      if (aov.at(x, y, 8) > 0.5f) {
        x0 = std::min(x0, x);
        x1 = std::max(x1, x);
        y0 = std::min(y0, y);
        y1 = std::max(y1, y);
      }
  ASSERT_GT(x1, x0);
  EXPECT_NEAR(double(x1 - x0), double(y1 - y0), 1.0) << "the sphere is not round";
  // The glTF camera of 2CylinderEngine (aspectRatio 1) the same way.
  auto engine = load_scene(content_dir() / "models/2CylinderEngine/glTF-Draco/2CylinderEngine.gltf",
                           {"render.width=320", "render.height=180"});
  ASSERT_TRUE(engine.ok()) << engine.error().to_string();
  EXPECT_EQ(engine->render.width, engine->render.height);
}

}  // namespace
}  // namespace kaskad
