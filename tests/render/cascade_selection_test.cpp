// The shader's cascade selection (select_cascade() in content/shaders/shadow.glsl) against the CPU
// helpers of runtime/math/cascade_math.h, through the shadow-points pass (the forward pass's own
// lookup): for points spread through and around the camera's view, the cascade the shader picks
// is the one select_cascade_by_depth() or select_cascade_by_map() picks. Points within a hair of
// a split distance or a map border are left out (rounding may go either way there). The blend
// weight the lookup used (blend_weight() in shadow.glsl, reported by the pass) is the one
// cascade_blend_weight() or cascade_blend_weight_map() gives.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "runtime/app/player.h"
#include "runtime/math/cascade_math.h"
#include "tests/render/player_fixture.h"

namespace kaskad {
namespace {

class CascadeSelectionTest : public PlayerTest {};

TEST_F(CascadeSelectionTest, ShaderPicksTheCascadeTheCpuHelpersPick) {
  for (const std::string selection : {"depth", "map_bounds"}) {
    SCOPED_TRACE(selection);
    auto scene = load_scene(content_dir() / "scenes" / "default.json",
                            {"render.width=160", "render.height=90", "shadow.selection=" + selection});
    ASSERT_TRUE(scene.ok()) << scene.error().to_string();
    RenderRun run;
    run.write_aovs = false;
    auto t = render_frames(*player_, *scene, run);
    ASSERT_TRUE(t.ok()) << t.error().to_string();
    const ShadowData& sh = t->last.shadow();
    const int n = sh.cascade_count;
    ASSERT_EQ(n, 4);
    const std::span<const float> D(sh.splits.data(), std::size_t(n) + 1);
    const std::span<const glm::mat4> maps(sh.view_proj.data(), std::size_t(n));
    // The shader keeps the PCF kernel's reach plus the normal offset free (map_border()).
    const float border = 2.0f * (1.5f + sh.settings.normal_offset_bias) / float(sh.settings.map_size);
    const glm::mat4 view = t->last.camera.view;
    const glm::mat4 world = glm::inverse(view);

    // Points in view space: depth from 5 m behind the camera to 40% past the last split, spread
    // sideways a little wider than the view.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<glm::vec3> points, normals;
    std::vector<int> expected;
    std::vector<float> expected_weight;
    const float band = sh.settings.blend_band;
    ASSERT_GT(band, 0.0f);
    std::array<int, 5> per_cascade{};  // -1 .. 3
    while (points.size() < 6000) {
      const float depth = -5.0f + unit(rng) * (1.4f * D[std::size_t(n)] + 5.0f);
      const float spread = 0.6f * (std::abs(depth) + 1.0f);
      const glm::vec3 pv((2.0f * unit(rng) - 1.0f) * spread * 1.8f,
                         (2.0f * unit(rng) - 1.0f) * spread, -depth);
      const glm::vec3 p = glm::vec3(world * glm::vec4(pv, 1.0f));
      int want;
      if (selection == "depth") {
        bool near_split = false;
        for (float d : D) near_split = near_split || std::abs(depth - d) < 1e-3f * d;
        if (near_split) continue;
        // The shader counts anything nearer than D[0] (the camera near plane) as cascade 0.
        want = depth < D[0] ? 0 : select_cascade_by_depth(D, depth);
        expected_weight.push_back(cascade_blend_weight(D, want, depth, band));
      } else {
        bool near_edge = false;
        for (const glm::mat4& m : maps) {
          const glm::vec4 clip = m * glm::vec4(p, 1.0f);
          const glm::vec3 ndc = glm::vec3(clip) / clip.w;
          near_edge = near_edge || std::abs(std::abs(ndc.x) - (1.0f - border)) < 1e-4f ||
                      std::abs(std::abs(ndc.y) - (1.0f - border)) < 1e-4f ||
                      std::abs(std::abs(ndc.z) - 1.0f) < 1e-4f;
        }
        if (near_edge) continue;
        want = select_cascade_by_map(maps, p, border);
        float w = 0.0f;
        if (want >= 0 && want + 1 < n) {
          const glm::vec4 clip = maps[std::size_t(want)] * glm::vec4(p, 1.0f);
          w = cascade_blend_weight_map(glm::vec3(clip) / clip.w, band, border);
        }
        expected_weight.push_back(w);
      }
      points.push_back(p);
      normals.emplace_back(0.0f, 1.0f, 0.0f);
      expected.push_back(want);
      ++per_cascade[std::size_t(want + 1)];
    }
    // The points reach every cascade and beyond.
    for (int c = -1; c < n; ++c) EXPECT_GT(per_cascade[std::size_t(c + 1)], 50) << "cascade " << c;

    std::vector<float> weights;
    auto got = player_->renderer->shadow_at_points(points, normals, &weights);
    ASSERT_TRUE(got.ok()) << got.error().to_string();
    ASSERT_EQ(got->size(), points.size());
    ASSERT_EQ(weights.size(), points.size());
    int wrong = 0, wrong_weight = 0, in_band = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const int shader = int(std::lround((*got)[i].y));
      if (shader != expected[i] && wrong++ < 5)
        ADD_FAILURE() << "point (" << points[i].x << ", " << points[i].y << ", " << points[i].z
                      << "): shader cascade " << shader << ", CPU " << expected[i];
      if (shader != expected[i]) continue;
      if (expected_weight[i] > 0.0f && expected_weight[i] < 1.0f) ++in_band;
      if (std::abs(weights[i] - expected_weight[i]) > 2e-3f && wrong_weight++ < 5)
        ADD_FAILURE() << "point (" << points[i].x << ", " << points[i].y << ", " << points[i].z
                      << ") in cascade " << shader << ": shader blend weight " << weights[i]
                      << ", CPU " << expected_weight[i];
    }
    EXPECT_EQ(wrong, 0) << "of " << points.size() << " points";
    EXPECT_EQ(wrong_weight, 0) << "of " << points.size() << " points";
    EXPECT_GT(in_band, 50);  // the blend bands are crossed, not just their outsides
  }
}

}  // namespace
}  // namespace kaskad
