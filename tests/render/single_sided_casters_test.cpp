// The shadow pass and the ray-traced reference follow one rule for the faces of casters
// (caster_face_blocks(), components/shadow_settings.h), checked on content/scenes/
// toon_outline.json (written with its model by scripts/make_inverted_hull.py): toon models
// enclosed by single-sided inverted hulls (their outlines, triangles facing inwards), one of
// them under a mirroring transform and one with a double-sided hull, and two planes facing
// down, away from the light: one double-sided (casts), one single-sided (casts only with cull
// front or none). Each object's part of the ground is compared on its own (world x and z
// bands), so a case that breaks names itself.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "runtime/reference/ray_tracer.h"
#include "runtime/reference/shadow_metrics.h"
#include "tests/render/player_fixture.h"

namespace kaskad {
namespace {

/// A part of the scene, as a box of world x and z around an object and the shadow it casts.
struct Region {
  const char* name;
  float x0, x1, z0, z1;
};
// The toons stand at x = -2.6, 0, 2.6 (z = 0) and the planes float at z = 2.6; the light comes
// from +x, +z, so shadows fall towards -x, -z.
constexpr Region kRegions[] = {
    {"toon (single-sided hull)", -4.6f, -1.3f, -2.0f, 1.5f},
    {"toon_mirrored", -1.3f, 1.3f, -2.0f, 1.5f},
    {"toon_double (double-sided hull)", 1.3f, 4.6f, -2.0f, 1.5f},
    {"awning_double_sided", -3.5f, 0.0f, 1.5f, 4.0f},
    {"awning_single_sided", 0.0f, 3.5f, 1.5f, 4.0f},
};

struct RegionResult {
  reference::ShadowMetrics metrics;
  std::size_t reference_shadowed = 0;  ///< receivers the reference has in shadow
};

class SingleSidedCastersTest : public PlayerTest {
 protected:
  /// Renders toon_outline.json with `sets` and compares its visibility with the reference,
  /// region by region.
  static std::vector<RegionResult> compare(std::vector<std::string> sets) {
    sets.push_back("render.width=480");
    sets.push_back("render.height=270");
    std::vector<RegionResult> out(std::size(kRegions));
    auto scene = load_scene(content_dir() / "scenes" / "toon_outline.json", sets);
    EXPECT_TRUE(scene.ok()) << scene.error().to_string();
    if (!scene.ok()) return out;
    RenderRun run;
    auto t = render_frames(*player_, *scene, run);
    EXPECT_TRUE(t.ok()) << t.error().to_string();
    if (!t.ok()) return out;
    const Image aov = player_->renderer->read_aovs();
    auto tracer = reference::RayTracer::build(*scene);
    EXPECT_TRUE(tracer.ok()) << tracer.error().to_string();
    if (!tracer.ok()) return out;
    const auto light = reference::reference_light(scene->world, t->last.shadow().light);
    auto ref = tracer->shadow_reference(aov, light, {});
    EXPECT_TRUE(ref.ok()) << ref.error().to_string();
    if (!ref.ok()) return out;

    const int w = aov.width, h = aov.height;
    const int method_ch = aov.channel("visibility"), px = aov.channel("P.X"),
              pz = aov.channel("P.Z");
    const int ref_ch = ref->image.channel("visibility"),
              receiver_ch = ref->image.channel("receiver");
    EXPECT_TRUE(method_ch >= 0 && px >= 0 && pz >= 0 && ref_ch >= 0 && receiver_ch >= 0);
    if (method_ch < 0 || px < 0 || pz < 0 || ref_ch < 0 || receiver_ch < 0) return out;
    std::vector<float> method(std::size_t(w) * h), truth(method.size());
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        method[std::size_t(y) * w + x] = aov.at(x, y, method_ch);
        truth[std::size_t(y) * w + x] = ref->image.at(x, y, ref_ch);
      }
    for (std::size_t r = 0; r < std::size(kRegions); ++r) {
      const Region& g = kRegions[r];
      std::vector<std::uint8_t> receiver(method.size(), 0);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const float wx = aov.at(x, y, px), wz = aov.at(x, y, pz);
          const bool inside = wx >= g.x0 && wx < g.x1 && wz >= g.z0 && wz < g.z1;
          const std::size_t i = std::size_t(y) * w + x;
          receiver[i] = inside && ref->image.at(x, y, receiver_ch) > 0.5f ? 1 : 0;
          if (receiver[i] && truth[i] < reference::kShadowThreshold) ++out[r].reference_shadowed;
        }
      out[r].metrics = reference::compare_shadows(w, h, method, truth, receiver);
      const auto& s = out[r].metrics.outside_edges;
      std::printf("%-34s %6zu receivers away from edges, %5zu misclassified (%.2f%%: %zu false "
                  "shadow, %zu false light), %zu shadowed in the reference\n",
                  g.name, s.pixels, s.misclassified, s.misclassified_pct, s.false_shadow,
                  s.false_light, out[r].reference_shadowed);
    }
    return out;
  }

  /// Every region agrees with the reference away from shadow edges (a shadow pass and a
  /// reference that follow different rules for a case disagree on most of its region).
  static void expect_agreement(const std::vector<RegionResult>& results) {
    for (std::size_t r = 0; r < std::size(kRegions); ++r) {
      const auto& s = results[r].metrics.outside_edges;
      EXPECT_GT(s.pixels, 2000u) << kRegions[r].name;
      EXPECT_LT(s.misclassified_pct, 1.0) << kRegions[r].name;
    }
  }
};

// The default cull (back): the single-sided hulls' upper halves face away from the light and
// cast nothing, so the bodies inside are lit (the pass; the reference used to shadow them
// whole); the lower halves face it and shadow the ground. The double-sided hull and plane cast
// from both faces; the single-sided plane, facing away, casts nothing.
TEST_F(SingleSidedCastersTest, DirectionalLightAgreesWithTheReference) {
  const auto r = compare({});
  expect_agreement(r);
  // Meaningful: shadows the cases are about exist where the rule says.
  EXPECT_GT(r[3].reference_shadowed, 1000u) << "the double-sided plane casts";
  EXPECT_EQ(r[4].reference_shadowed, 0u) << "the single-sided plane facing away casts nothing";
}

// A spot light at the same place: "faces the light" is per triangle, towards its position.
TEST_F(SingleSidedCastersTest, SpotLightAgreesWithTheReference) {
  const auto r = compare({"sun.light.type=\"spot\"", "sun.light.intensity=150"});
  expect_agreement(r);
  EXPECT_GT(r[3].reference_shadowed, 1000u);
  EXPECT_EQ(r[4].reference_shadowed, 0u);
}

// Cull front: single-sided casters cast with their back faces only, so the hulls' upper halves
// and the single-sided plane now cast, in the pass and the reference alike.
TEST_F(SingleSidedCastersTest, CullFrontAgreesWithTheReference) {
  const auto r = compare({"shadow.cull=\"front\""});
  expect_agreement(r);
  EXPECT_GT(r[4].reference_shadowed, 1000u) << "the single-sided plane casts with its back face";
}

}  // namespace
}  // namespace kaskad
