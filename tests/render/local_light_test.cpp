// Spot and point light shadows against the Embree reference: content/scenes/spot.json (one
// perspective map) and point.json (cube faces, dual-paraboloid hemispheres) are rendered headless
// and the visibility AOV is compared with RayTracer::shadow_reference() per pixel
// (reference::compare_shadows). Away from shadow edges at least 99% of the receivers must agree;
// a deliberately bad configuration must score worse, so the comparison can fail.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <set>

#include "components/light.h"
#include "components/transform.h"
#include "runtime/app/player.h"
#include "tests/render/player_fixture.h"
#include "runtime/gpu/context.h"
#include "runtime/reference/ray_tracer.h"
#include "runtime/reference/shadow_metrics.h"

namespace kaskad {
namespace {

std::string describe(const reference::ShadowMetrics& m) {
  const auto& s = m.outside_edges;
  return std::to_string(s.misclassified) + " of " + std::to_string(s.pixels) +
         " misclassified away from edges (" + std::to_string(s.false_shadow) + " false shadow, " +
         std::to_string(s.false_light) + " false light)";
}

struct Rendered {
  reference::ShadowMetrics metrics;
  ShadowData shadow;
  std::vector<ShadowData> extra;
  render::FrameStats stats;
  Image aov;
  std::set<int> layers_seen;  ///< AOV cascade (layer) values of receiver pixels
};

class LocalLightTest : public PlayerTest {
 protected:
  // Renders `scene_file` at 400x225 with overrides and compares with the ray-traced reference of
  // shadowed light `reference_of` (0 the first, k the k-th extra directional light).
  static Rendered render_and_compare(const char* scene_file, std::vector<std::string> sets,
                                     int reference_of = 0) {
    Rendered out;
    sets.push_back("render.width=400");
    sets.push_back("render.height=225");
    auto scene = load_scene(content_dir() / "scenes" / scene_file, sets);
    EXPECT_TRUE(scene.ok()) << scene.error().to_string();
    if (!scene.ok()) return out;
    RenderRun run;
    auto t = render_frames(*player_, *scene, run);
    EXPECT_TRUE(t.ok()) << t.error().to_string();
    if (!t.ok()) return out;
    out.shadow = t->last.shadow();
    if (t->last.shadows.size() > 1) out.extra.assign(t->last.shadows.begin() + 1, t->last.shadows.end());
    out.stats = t->last.stats;
    out.aov = player_->renderer->read_aovs();
    EXPECT_LE(reference_of, int(out.extra.size()));
    if (reference_of > int(out.extra.size())) return out;
    const ecs::Entity light =
        reference_of == 0 ? out.shadow.light : out.extra[std::size_t(reference_of - 1)].light;
    EXPECT_TRUE(light.valid());
    if (!light.valid()) return out;
    auto tracer = reference::RayTracer::build(*scene);
    EXPECT_TRUE(tracer.ok()) << tracer.error().to_string();
    if (!tracer.ok()) return out;
    const auto rlight = reference::reference_light(scene->world, light);
    auto ref = tracer->shadow_reference(out.aov, rlight, {});
    EXPECT_TRUE(ref.ok()) << ref.error().to_string();
    if (!ref.ok()) return out;
    auto m = reference::compare_shadows(out.aov, ref->image);
    EXPECT_TRUE(m.ok()) << m.error().to_string();
    if (m.ok()) out.metrics = *m;
    std::printf("%s: %s\n", scene_file, describe(out.metrics).c_str());
    const auto& names = ref->image.channel_names;
    const int receiver = int(std::find(names.begin(), names.end(), "receiver") - names.begin());
    EXPECT_LT(receiver, ref->image.channels);
    if (receiver >= ref->image.channels) return out;
    for (int y = 0; y < out.aov.height; ++y)
      for (int x = 0; x < out.aov.width; ++x)
        if (ref->image.at(x, y, receiver) > 0.5f) out.layers_seen.insert(int(out.aov.at(x, y, 9)));
    return out;
  }

};

// Enough receivers in shadow and in light that agreement means something.
void expect_meaningful(const Rendered& r) {
  const auto& s = r.metrics.outside_edges;
  EXPECT_GT(s.pixels, 20000u);
  EXPECT_LT(r.metrics.non_finite, 1u);
}

TEST_F(LocalLightTest, SpotLightAgreesWithRayCastsAwayFromEdges) {
  const Rendered r = render_and_compare("spot.json", {});
  EXPECT_EQ(r.shadow.projection, ShadowProjection::perspective);
  EXPECT_EQ(r.shadow.cascade_count, 1);
  expect_meaningful(r);
  EXPECT_LT(r.metrics.outside_edges.misclassified_pct, 1.0) << describe(r.metrics);
}

TEST_F(LocalLightTest, PointLightCubeMapAgreesWithRayCastsAwayFromEdges) {
  const Rendered r = render_and_compare("point.json", {"shadow.point_mode=\"cube\""});
  EXPECT_EQ(r.shadow.projection, ShadowProjection::cube);
  EXPECT_EQ(r.shadow.cascade_count, 6);
  expect_meaningful(r);
  // Stats: receiver pixels per layer are the AOV's cascade channel counted where the mask is 1
  // (drawn surfaces; the background is not a receiver); texel sizes are the system's.
  std::array<std::size_t, kMaxCascades> counted{};
  for (int y = 0; y < r.aov.height; ++y)
    for (int x = 0; x < r.aov.width; ++x)
      if (const int c = int(r.aov.at(x, y, 9)); c >= 0 && r.aov.at(x, y, 8) == 1.0f)
        ++counted[std::size_t(c)];
  EXPECT_EQ(r.stats.cascade_receiver_pixels, counted);
  for (int i = 0; i < 6; ++i)
    EXPECT_EQ(r.stats.layer_texel_size[std::size_t(i)], r.shadow.texel_size[std::size_t(i)]);
  EXPECT_GE(r.layers_seen.size(), 4u) << "the view should see receivers on several cube faces";
  EXPECT_LT(r.metrics.outside_edges.misclassified_pct, 1.0) << describe(r.metrics);
}

TEST_F(LocalLightTest, PointLightDualParaboloidAgreesWithRayCastsAwayFromEdges) {
  const Rendered r = render_and_compare("point.json", {"shadow.point_mode=\"dual_paraboloid\""});
  EXPECT_EQ(r.shadow.projection, ShadowProjection::dual_paraboloid);
  EXPECT_EQ(r.shadow.cascade_count, 2);
  expect_meaningful(r);
  EXPECT_EQ(r.layers_seen, (std::set<int>{0, 1})) << "both hemispheres should hold receivers";
  EXPECT_LT(r.metrics.outside_edges.misclassified_pct, 1.0) << describe(r.metrics);
}

// Without any bias the maps shadow their own receivers (acne), and the metric sees it.
TEST_F(LocalLightTest, UnbiasedMapsScoreWorse) {
  const std::vector<std::string> no_bias = {"shadow.constant_bias=0", "shadow.slope_bias=0",
                                            "shadow.normal_offset_bias=0"};
  for (const char* mode : {"cube", "dual_paraboloid"}) {
    std::vector<std::string> sets = no_bias;
    sets.push_back(std::string("shadow.point_mode=\"") + mode + "\"");
    const Rendered good = render_and_compare("point.json", {sets.back()});
    const Rendered bad = render_and_compare("point.json", sets);
    EXPECT_GT(bad.metrics.outside_edges.false_shadow_pct,
              2.0 * good.metrics.outside_edges.false_shadow_pct + 1.0)
        << mode << ": " << describe(bad.metrics);
  }
  const Rendered bad_spot = render_and_compare("spot.json", no_bias);
  EXPECT_GT(bad_spot.metrics.outside_edges.false_shadow_pct, 1.0) << describe(bad_spot.metrics);
}

// Two directional lights, each with its own cascades (4 and 2): the AOV shows either light's
// visibility (render.aov_shadow_light) and each agrees with that light's ray cast; read against
// the other light's reference it does not, so the comparison tells the lights apart.
TEST_F(LocalLightTest, TwoDirectionalLightsEachAgreeWithTheirRayCasts) {
  const Rendered sun = render_and_compare("two_suns.json", {"render.aov_shadow_light=0"}, 0);
  ASSERT_EQ(sun.extra.size(), 1u);
  EXPECT_EQ(sun.shadow.cascade_count, 4);
  EXPECT_EQ(sun.extra[0].cascade_count, 2);
  EXPECT_NE(sun.extra[0].light, sun.shadow.light);
  expect_meaningful(sun);
  EXPECT_LT(sun.metrics.outside_edges.misclassified_pct, 1.0) << describe(sun.metrics);
  const Rendered moon = render_and_compare("two_suns.json", {"render.aov_shadow_light=1"}, 1);
  expect_meaningful(moon);
  EXPECT_LT(moon.metrics.outside_edges.misclassified_pct, 1.0) << describe(moon.metrics);
  const Rendered crossed = render_and_compare("two_suns.json", {"render.aov_shadow_light=1"}, 0);
  EXPECT_GT(crossed.metrics.outside_edges.misclassified_pct, 5.0) << describe(crossed.metrics);
  // The first shadowed light a point light with paraboloid maps (another depth program): the
  // extra light's cascades are still right.
  for (const char* mode : {"cube", "dual_paraboloid"}) {
    const Rendered after_point = render_and_compare(
        "two_suns.json",
        {"render.aov_shadow_light=1", "sun.light.type=point", "sun.transform.translation=[1,4,1]",
         std::string("shadow.point_mode=") + mode},
        1);
    EXPECT_EQ(after_point.shadow.projection, std::string(mode) == "cube"
                                                 ? ShadowProjection::cube
                                                 : ShadowProjection::dual_paraboloid);
    ASSERT_EQ(after_point.extra.size(), 1u);
    EXPECT_LT(after_point.metrics.outside_edges.misclassified_pct, 1.0)
        << mode << ": " << describe(after_point.metrics);
  }
}

// The first shadowed light may be a spot or point light; shadowed lights beyond the cap and
// shadowed spot/point lights after the first are left without maps (a warning), never an error.
TEST_F(LocalLightTest, ExtraShadowedLightsAreCappedAndMustBeDirectional) {
  auto scene = load_scene(content_dir() / "scenes" / "two_suns.json",
                          {"render.width=160", "render.height=90", "moon.light.type=spot"});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  RenderRun run;
  auto t = render_frames(*player_, *scene, run);
  ASSERT_TRUE(t.ok()) << t.error().to_string();
  ASSERT_EQ(t->last.shadows.size(), 1u);  // the spot light (second) gets no view
  EXPECT_TRUE(t->last.shadow().light.valid());
}

// The layered shadow pass (one instanced draw per caster and light, gl_Layer from the vertex
// shader) writes exactly the maps of one pass per layer: cascades, extra lights, spot, cube.
TEST_F(LocalLightTest, LayeredPassWritesTheSameMapsAsOnePassPerLayer) {
  struct Case {
    const char* scene;
    std::vector<std::string> sets;
  };
  const Case cases[] = {{"default.json", {}},
                        {"default.json", {"shadow.fit_mode=\"crop\"", "shadow.cascade_count=8"}},
                        {"two_suns.json", {}},
                        {"spot.json", {}},
                        {"point.json", {}}};
  for (const Case& c : cases) {
    std::array<Image, 2> maps;
    std::array<int, 2> draws{};
    std::array<glm::ivec4, kMaxShadowLayers> rects{};  // what one pass per layer drew
    for (int layered = 0; layered < 2; ++layered) {
      std::vector<std::string> sets = c.sets;
      sets.push_back("render.width=160");
      sets.push_back("render.height=90");
      sets.push_back("shadow.map_size=512");
      sets.push_back(layered ? "shadow.layered=true" : "shadow.layered=false");
      auto scene = load_scene(content_dir() / "scenes" / c.scene, sets);
      ASSERT_TRUE(scene.ok()) << scene.error().to_string();
      RenderRun run;
      run.write_aovs = false;
      auto t = render_frames(*player_, *scene, run);
      ASSERT_TRUE(t.ok()) << t.error().to_string();
      maps[std::size_t(layered)] = player_->renderer->read_shadow_map();
      draws[std::size_t(layered)] = t->last.stats.shadow_draw_calls;
      if (!layered) rects = t->last.stats.layer_rect;
    }
    // The layered pass draws whole layers; one pass per layer only what lookups read.
    for (Image& m : maps) m.pixels = read_part(m, rects);
    ASSERT_EQ(maps[0].height, maps[1].height) << c.scene;
    ASSERT_EQ(maps[0].pixels.size(), maps[1].pixels.size()) << c.scene;
    std::size_t differ = 0, written = 0;
    for (std::size_t i = 0; i < maps[0].pixels.size(); ++i) {
      differ += maps[0].pixels[i] != maps[1].pixels[i];
      written += maps[0].pixels[i] < 1.0f;
    }
    EXPECT_EQ(differ, 0u) << c.scene;
    EXPECT_GT(written, 1000u) << c.scene << ": the maps should hold casters";
    EXPECT_LE(draws[1], draws[0]) << c.scene;
  }
}

}  // namespace
}  // namespace kaskad
