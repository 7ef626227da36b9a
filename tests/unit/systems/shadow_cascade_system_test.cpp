// ShadowCascadeSystem's CPU side: split end clamped to the farthest visible receiver, skipped
// empty cascades, per-cascade caster lists, NaN transforms rejected, the basic fit reproduced.
// No GL.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <limits>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "components/light.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "systems/shadow_cascade_system.h"

namespace kaskad {
namespace {

// A camera at the origin looking down -z (fov 20 degrees, square), near 1, far 100.
CameraState camera(ecs::World& w, float fov_deg = 20.0f) {
  CameraState c;
  c.entity = w.create();
  c.camera.fov_y_deg = fov_deg;
  c.camera.near = 1.0f;
  c.camera.far = 100.0f;
  c.aspect = 1.0f;
  c.view = glm::mat4(1.0f);
  c.proj = glm::perspective(glm::radians(fov_deg), 1.0f, 1.0f, 100.0f);
  return c;
}

ecs::Entity sun(ecs::World& w, const ShadowSettings& s, glm::vec3 dir = {0.3f, -1.0f, -0.2f}) {
  const ecs::Entity e = w.create();
  Light l;
  l.cast_shadows = true;
  w.emplace<Light>(e, l);
  // Local -z along dir: a rotation taking (0,0,-1) to dir.
  const glm::vec3 d = glm::normalize(dir);
  WorldTransform wt;
  wt.matrix = glm::inverse(glm::lookAt(glm::vec3(0.0f), d, std::abs(d.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0)));
  w.emplace<WorldTransform>(e, wt);
  w.emplace<ShadowSettings>(e, s);
  return e;
}

ecs::Entity mesh(ecs::World& w, const Aabb& b, bool cast = true, bool receive = true) {
  const ecs::Entity e = w.create();
  MeshRenderer mr;
  mr.mesh = MeshId{0};
  mr.cast_shadows = cast;
  mr.receive_shadows = receive;
  w.emplace<MeshRenderer>(e, mr);
  w.emplace<WorldBounds>(e, WorldBounds{b});
  return e;
}

bool contains(const std::vector<ecs::Entity>& v, ecs::Entity e) {
  return std::find(v.begin(), v.end(), e) != v.end();
}

TEST(ShadowCascadeSystem, CascadesSpanTheVisibleReceiversQuantisedOutwards) {
  ecs::World w;
  ShadowSettings s;
  s.max_distance = 100.0f;
  sun(w, s);
  // A receiver from 2 m to 20 m in front of the camera, and one far behind it (not visible).
  mesh(w, Aabb::from_corners({-1, -1, -20}, {1, 0, -2}));
  mesh(w, Aabb::from_corners({-1, -1, 40}, {1, 0, 60}));
  ShadowCascadeState state;
  const ShadowData d = update_shadow_cascades(w, camera(w), state);
  ASSERT_TRUE(d.light.valid()) << d.error;
  EXPECT_EQ(d.cascade_count, 4);
  EXPECT_FLOAT_EQ(d.near_requested, 1.0f);
  EXPECT_FLOAT_EQ(d.far_requested, 100.0f);
  // [2, 20] on the 2^(1/4) grid: 2 stays, 20 rounds up to 2^4.5.
  EXPECT_FLOAT_EQ(d.near_used, 2.0f);
  EXPECT_NEAR(d.far_used, std::exp2(4.5f), 1e-3f);
  EXPECT_FLOAT_EQ(d.splits[0], d.near_used);
  EXPECT_FLOAT_EQ(d.splits[4], d.far_used);
  for (int i = 0; i < 4; ++i) EXPECT_LT(d.splits[std::size_t(i)], d.splits[std::size_t(i) + 1]);
  // auto: log splits (S0 eq. (2)) over the range.
  EXPECT_NEAR(d.splits[2], std::sqrt(d.near_used * d.far_used), 1e-3f);
  // max_distance still wins when it is nearer.
  w.get<ShadowSettings>(d.light).max_distance = 10.0f;
  const ShadowData d2 = update_shadow_cascades(w, camera(w), state);
  EXPECT_FLOAT_EQ(d2.far_requested, 10.0f);
  EXPECT_FLOAT_EQ(d2.far_used, 10.0f);
}

TEST(ShadowCascadeSystem, TheRangeFollowsTheModelAtAnyScale) {
  // The same receiver scaled by 10^k, seen by a camera scaled with it: the range scales too.
  for (int k = -3; k <= 4; ++k) {
    const float u = std::pow(10.0f, float(k));
    ecs::World w;
    sun(w, ShadowSettings{});
    mesh(w, Aabb::from_corners(glm::vec3(-1, -1, -20) * u, glm::vec3(1, 0, -2) * u));
    ShadowCascadeState state;
    CameraState cs = camera(w);
    cs.camera.near = 0.5f * u;
    cs.camera.far = 1000.0f * u;
    cs.proj = glm::perspective(glm::radians(cs.camera.fov_y_deg), cs.aspect, cs.camera.near,
                               cs.camera.far);
    const ShadowData d = update_shadow_cascades(w, cs, state);
    ASSERT_TRUE(d.light.valid()) << d.error;
    // [2, 20] u, rounded outwards by less than one 2^(1/4) step.
    EXPECT_LE(d.near_used / u, 2.0f * 1.0001f) << "k " << k;
    EXPECT_GT(d.near_used / u, 2.0f / 1.19f) << "k " << k;
    EXPECT_GE(d.far_used / u, 20.0f * 0.9999f) << "k " << k;
    EXPECT_LT(d.far_used / u, 20.0f * 1.19f) << "k " << k;
    for (int i = 0; i < 4; ++i) EXPECT_FALSE(d.skipped[std::size_t(i)]) << "k " << k;
  }
}

TEST(ShadowCascadeSystem, VisibleReceiverDepthsClipBoxesToTheFrustum) {
  const glm::mat4 view(1.0f), proj = glm::perspective(glm::radians(20.0f), 1.0f, 1.0f, 100.0f);
  const Aabb behind = Aabb::from_corners({-1, -1, 5}, {1, 1, 9});
  const Aabb aside = Aabb::from_corners({50, -1, -30}, {52, 1, -20});
  const Aabb front = Aabb::from_corners({-1, -1, -30}, {1, 1, -20});
  EXPECT_TRUE(visible_receiver_depths(view, proj * view, std::array{behind, aside}).empty());
  const DepthRange r = visible_receiver_depths(view, proj * view, std::array{behind, front});
  EXPECT_FLOAT_EQ(r.near, 20.0f);
  EXPECT_FLOAT_EQ(r.far, 30.0f);
  // Clipped to far.
  const Aabb long_box = Aabb::from_corners({-1, -1, -300}, {1, 1, -20});
  EXPECT_NEAR(visible_receiver_depths(view, proj * view, std::array{long_box}).far, 100.0f, 1e-3f);
  // A wide ground 1 m below the eye: seen from where the lower frustum plane meets it,
  // 1 / tan(10 deg), to the far plane; its box reaches the camera but is not seen there.
  const Aabb ground = Aabb::from_corners({-1000, -1, -1000}, {1000, -1, 1000});
  const DepthRange g = visible_receiver_depths(view, proj * view, std::array{ground});
  EXPECT_NEAR(g.near, 1.0f / std::tan(glm::radians(10.0f)), 1e-3f);
  EXPECT_NEAR(g.far, 100.0f, 1e-3f);
}

// Many boxes at once give exactly the union of each box's own range: boxes skipped because
// their corners lie within the range found so far (the fast path for large scenes) change
// nothing, whatever the order.
TEST(ShadowCascadeSystem, VisibleReceiverDepthsOfManyBoxesIsTheUnionOfEach) {
  const glm::mat4 view = glm::lookAt(glm::vec3(3, 4, 10), glm::vec3(0), glm::vec3(0, 1, 0));
  const glm::mat4 proj = glm::perspective(glm::radians(50.0f), 1.5f, 0.3f, 60.0f);
  std::uint32_t seed = 12345;
  auto next = [&] {  // a small LCG: the same boxes on every platform
    seed = seed * 1664525u + 1013904223u;
    return float(seed >> 8) / float(1u << 24);
  };
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Aabb> boxes;
    for (int i = 0; i < 60; ++i) {
      const glm::vec3 c(next() * 120 - 60, next() * 10 - 5, next() * 120 - 90);
      const glm::vec3 h(next() * 6 + 0.01f, next() * 3 + 0.01f, next() * 6 + 0.01f);
      boxes.push_back(Aabb::from_corners(c - h, c + h));
    }
    DepthRange each{std::numeric_limits<float>::max(), 0.0f};
    for (const Aabb& b : boxes) {
      const DepthRange one = visible_receiver_depths(view, proj * view, std::array{b});
      if (one.empty()) continue;
      each.near = std::min(each.near, one.near);
      each.far = std::max(each.far, one.far);
    }
    const DepthRange all = visible_receiver_depths(view, proj * view, boxes);
    ASSERT_FALSE(all.empty());
    EXPECT_EQ(all.near, each.near) << "trial " << trial;
    EXPECT_EQ(all.far, each.far) << "trial " << trial;
  }
}

TEST(ShadowCascadeSystem, TheRangeKeepsLastFramesWhileItStillFits) {
  ecs::World w;
  sun(w, ShadowSettings{});
  const ecs::Entity box = mesh(w, Aabb::from_corners({-1, -1, -20}, {1, 0, -2.7f}));
  ShadowCascadeState state;
  const ShadowData first = update_shadow_cascades(w, camera(w), state);
  ASSERT_TRUE(first.light.valid()) << first.error;
  // [2.7, 20] -> [2^1.25 = 2.38, 2^4.5 = 22.6]. The receiver's near end moves past the grid
  // point 2^1.5 = 2.83: a fresh fit takes [2.83, 22.6], the carried range stays while it fits.
  w.get<WorldBounds>(box).box = Aabb::from_corners({-1, -1, -20.5f}, {1, 0, -2.95f});
  ShadowCascadeState no_history;
  EXPECT_NEAR(update_shadow_cascades(w, camera(w), no_history).near_used, 2.83f, 0.01f);
  const ShadowData second = update_shadow_cascades(w, camera(w), state);
  EXPECT_NEAR(first.near_used, 2.38f, 0.01f);
  EXPECT_EQ(second.near_used, first.near_used);
  EXPECT_EQ(second.far_used, first.far_used);
  EXPECT_EQ(second.splits, first.splits);
  // Past the carried range it must follow: the new far is seen.
  w.get<WorldBounds>(box).box = Aabb::from_corners({-1, -1, -30}, {1, 0, -2.95f});
  const ShadowData third = update_shadow_cascades(w, camera(w), state);
  EXPECT_GE(third.far_used, 30.0f);
  // Much tighter than the carried range: it shrinks again.
  w.get<WorldBounds>(box).box = Aabb::from_corners({-1, -1, -8}, {1, 0, -2.95f});
  const ShadowData fourth = update_shadow_cascades(w, camera(w), state);
  EXPECT_LT(fourth.far_used, 10.0f);
  ShadowCascadeState fresh;
  EXPECT_EQ(update_shadow_cascades(w, camera(w), fresh).far_used, fourth.far_used);
}

TEST(ShadowCascadeSystem, VisibleReceiverDepthsMatchDenseSamplingOfRandomBoxes) {
  // Invariant: the exact range holds every sampled point of box and frustum, and no sampled
  // point lies more than a sample spacing inside either end.
  const glm::mat4 view = glm::lookAt(glm::vec3(0, 2, 0), glm::vec3(3, 0, -10), glm::vec3(0, 1, 0));
  const glm::mat4 proj = glm::perspective(glm::radians(40.0f), 1.6f, 0.5f, 60.0f);
  std::uint32_t seed = 12345;
  auto rnd = [&](float lo, float hi) {
    seed = seed * 1664525u + 1013904223u;
    return lo + (hi - lo) * float(seed >> 8) / float(1u << 24);
  };
  int compared = 0;
  for (int n = 0; n < 200; ++n) {
    const glm::vec3 c{rnd(-30, 30), rnd(-10, 10), rnd(-70, 5)};
    const glm::vec3 h{rnd(0.1f, 15), rnd(0.0f, 5), rnd(0.1f, 15)};
    const Aabb box = Aabb::from_corners(c - h, c + h);
    const DepthRange exact = visible_receiver_depths(view, proj * view, std::array{box});
    constexpr int kSteps = 24;
    float lo = std::numeric_limits<float>::max(), hi = 0.0f;
    for (int i = 0; i <= kSteps; ++i)
      for (int j = 0; j <= kSteps; ++j)
        for (int k = 0; k <= kSteps; ++k) {
          const glm::vec3 p = box.min + (box.max - box.min) * glm::vec3(i, j, k) / float(kSteps);
          const glm::vec4 q = proj * view * glm::vec4(p, 1.0f);
          if (std::abs(q.x) > q.w || std::abs(q.y) > q.w || std::abs(q.z) > q.w) continue;
          const float d = -(view * glm::vec4(p, 1.0f)).z;
          lo = std::min(lo, d);
          hi = std::max(hi, d);
        }
    if (hi == 0.0f) continue;  // no sample inside: nothing to compare
    ++compared;
    ASSERT_FALSE(exact.empty()) << n;
    const float spacing = 1.01f * glm::length(box.max - box.min) / float(kSteps);
    EXPECT_LE(exact.near, lo + 1e-3f) << n;
    EXPECT_GE(exact.far, hi - 1e-3f) << n;
    EXPECT_GE(exact.near, lo - spacing) << n;
    EXPECT_LE(exact.far, hi + spacing) << n;
  }
  EXPECT_GT(compared, 50);
}

TEST(ShadowCascadeSystem, QuantisedRangesAreStableUnderSmallChanges) {
  const DepthRange a = quantize_depth_range({3.0f, 700.0f});
  EXPECT_LE(a.near, 3.0f);
  EXPECT_GE(a.far, 700.0f);
  EXPECT_GT(a.near, 3.0f / 1.19f);
  EXPECT_LT(a.far, 700.0f * 1.19f);
  // A few per cent either way lands on the same grid points.
  const DepthRange b = quantize_depth_range({3.05f, 690.0f});
  EXPECT_EQ(a.near, b.near);
  EXPECT_EQ(a.far, b.far);
}

TEST(ShadowCascadeSystem, CascadesWithoutReceiversAreSkippedAndCastersCulledPerCascade) {
  ecs::World w;
  ShadowSettings s;
  // Receivers span [1.5, 53]: on the 2^(1/4) grid [1.41, 53.8], so 1.41, 14.5, 27.6, 40.7, 53.8.
  s.split_scheme = SplitScheme::uniform;
  s.cascade_count = 4;
  sun(w, s, {0.0f, -1.0f, 0.0f});
  const ecs::Entity near_box = mesh(w, Aabb::from_corners({-0.3f, -0.3f, -2.0f}, {0.3f, 0.3f, -1.5f}));
  const ecs::Entity far_box = mesh(w, Aabb::from_corners({-0.3f, -0.3f, -53.0f}, {0.3f, 0.3f, -52.0f}));
  const ecs::Entity no_cast = mesh(w, Aabb::from_corners({-0.3f, -0.3f, -52.0f}, {0.3f, 0.3f, -51.0f}), false, true);
  ShadowCascadeState state;
  const ShadowData d = update_shadow_cascades(w, camera(w), state);
  ASSERT_TRUE(d.light.valid()) << d.error;
  EXPECT_NEAR(d.far_used, std::exp2(5.75f), 1e-3f);  // 53 on the 2^(1/4) grid
  EXPECT_FALSE(d.skipped[0]);
  EXPECT_TRUE(d.skipped[1]);
  EXPECT_TRUE(d.skipped[2]);
  EXPECT_FALSE(d.skipped[3]);
  EXPECT_TRUE(d.casters[1].empty());
  EXPECT_TRUE(d.casters[2].empty());
  EXPECT_TRUE(contains(d.casters[0], near_box));
  EXPECT_FALSE(contains(d.casters[0], far_box));
  EXPECT_TRUE(contains(d.casters[3], far_box));
  EXPECT_FALSE(contains(d.casters[3], near_box));
  for (const auto& list : d.casters) EXPECT_FALSE(contains(list, no_cast));  // not a caster
  EXPECT_EQ(d.cascade_mask(near_box), 0b0001);
  EXPECT_EQ(d.cascade_mask(far_box), 0b1000);
  for (int i = 0; i < 4; ++i) EXPECT_GT(d.texel_size[std::size_t(i)], 0.0f);
}

TEST(ShadowCascadeSystem, CullCastersKeepsBoxesOverlappingTheLightVolume) {
  const glm::mat4 vp = glm::ortho(-1.0f, 1.0f, -1.0f, 1.0f, 0.0f, 10.0f);  // looks down -z
  const std::array boxes{Aabb::from_corners({-0.5f, -0.5f, -2}, {0.5f, 0.5f, -1}),   // inside
                         Aabb::from_corners({0.9f, 0.9f, -2}, {3, 3, -1}),            // straddles a corner
                         Aabb::from_corners({2, -0.5f, -2}, {3, 0.5f, -1}),           // right of it
                         Aabb::from_corners({-0.5f, -0.5f, -30}, {0.5f, 0.5f, -20}),  // beyond far
                         Aabb{}};                                      // empty
  EXPECT_EQ(cull_casters(vp, boxes), (std::vector<std::uint32_t>{0, 1}));
}

// may_shadow(): a face plane of the caster's box that faces the light, with every receiver on
// its lit side, proves the caster cannot shadow them.
TEST(ShadowCascadeSystem, MayShadowKeepsEveryCasterThatCanReachAReceiver) {
  const glm::vec3 sun = glm::normalize(glm::vec3(0.5f, -0.6f, -0.45f));  // travels down
  const Aabb ground = Aabb::from_corners({-20, 0, -20}, {20, 0, 20});     // flat, at y = 0
  const Aabb above = Aabb::from_corners({-5, 0, -5}, {5, 3, 5});          // boxes resting on it
  const Aabb dipping = Aabb::from_corners({-5, -0.02f, -5}, {5, 3, 5});   // one dips below
  // The ground cannot shadow what rests on it, itself included (it is flat).
  EXPECT_FALSE(may_shadow(ground, above, sun));
  Aabb both = above;
  both.expand(ground);
  EXPECT_FALSE(may_shadow(ground, both, sun));
  EXPECT_TRUE(may_shadow(ground, dipping, sun));  // 2 cm below the plane can be in its shadow
  // A box resting on the ground shadows it.
  EXPECT_TRUE(may_shadow(Aabb::from_corners({0, 0, 0}, {1, 1, 1}), ground, sun));
  // A box is its own receiver: never left out of a layer it serves.
  EXPECT_TRUE(may_shadow(above, above, sun));
  // Under a light from below, the ground may shadow what lies above it.
  EXPECT_TRUE(may_shadow(ground, above, -sun));
  // Light along the plane: only a receiver strictly beside the caster is out of reach.
  const glm::vec3 grazing(1.0f, 0.0f, 0.0f);
  EXPECT_TRUE(may_shadow(ground, above, grazing));
  EXPECT_FALSE(may_shadow(ground, Aabb::from_corners({-5, 0.5f, -5}, {5, 3, 5}), grazing));
  // Nothing to shadow; an empty caster box proves nothing.
  EXPECT_FALSE(may_shadow(ground, Aabb{}, sun));
  EXPECT_TRUE(may_shadow(Aabb{}, above, sun));
}

// receiver_rect(): the receivers inside the camera slice, clipped to the slice's light-space
// bounds, grown by the margin, within [-1, 1]^2; empty when none meets the slice.
TEST(ShadowCascadeSystem, ReceiverRectCoversTheReceiversInTheSlice) {
  // Light looking down -y onto x/z: NDC x = world x / 10, NDC y = -world z / 10.
  const glm::mat4 vp = glm::ortho(-10.0f, 10.0f, -10.0f, 10.0f, 0.0f, 40.0f) *
                       glm::lookAt(glm::vec3(0, 20, 0), glm::vec3(0), glm::vec3(0, 0, -1));
  // A camera slice seen from above: near face z = -2, x in [-1, 1]; far face z = -8, x in
  // [-4, 4]; y in [0, 2] (corners in slice_corners_world() order).
  const std::array<glm::vec3, 8> slice{glm::vec3(-1, 2, -2), glm::vec3(1, 2, -2),
                                       glm::vec3(1, 0, -2),  glm::vec3(-1, 0, -2),
                                       glm::vec3(-4, 2, -8), glm::vec3(4, 2, -8),
                                       glm::vec3(4, 0, -8),  glm::vec3(-4, 0, -8)};
  const std::array receivers{
      Aabb::from_corners({-1, 0, -5}, {1, 1, -3}),          // inside
      Aabb::from_corners({3, 0, -8}, {6, 1, -7}),           // half outside in x
      Aabb::from_corners({3, 0, -2.5f}, {3.5f, 1, -2.2f}),  // in the slice's bounds, beside it
      Aabb::from_corners({-1, 0, 5}, {1, 1, 7}),            // behind the camera
      Aabb::from_corners({-1, 5, -5}, {1, 6, -3})};         // above the slice
  Aabb touched;
  const glm::vec4 r = receiver_rect(vp, slice, receivers, 0.0f, &touched);
  EXPECT_NEAR(r.x, -0.1f, 1e-5f);  // x from -1 (first box) ..
  EXPECT_NEAR(r.z, 0.4f, 1e-5f);   // .. to 4 (the second, clipped to the slice's bounds)
  EXPECT_NEAR(r.y, 0.3f, 1e-5f);   // z from -3 ..
  EXPECT_NEAR(r.w, 0.8f, 1e-5f);   // .. to -8
  EXPECT_EQ(touched.min, glm::vec3(-1, 0, -8));
  EXPECT_EQ(touched.max, glm::vec3(6, 1, -3));
  const glm::vec4 grown = receiver_rect(vp, slice, receivers, 0.7f);
  EXPECT_NEAR(grown.x, -0.8f, 1e-5f);
  EXPECT_EQ(grown.z, 1.0f);  // within the map
  // Only boxes outside the slice: empty.
  const glm::vec4 none = receiver_rect(vp, slice, std::span(receivers).subspan(2), 0.5f);
  EXPECT_GT(none.x, none.z);
}

// The default scene's sun over a ground plane and boxes resting on it: the ground is left out of
// the cascades whose receivers all lie on or above it, and each cascade's read rectangle lies in
// the map; with both switches off, every caster in every cascade and whole layers.
TEST(ShadowCascadeSystem, GroundLeftOutWhereAllReceiversRestOnIt) {
  for (bool on : {true, false}) {
    ecs::World w;
    ShadowSettings s;
    s.cull_by_receivers = on;
    s.scissor_to_receivers = on;
    sun(w, s, {0.5f, -0.6f, -0.45f});
    const ecs::Entity ground = mesh(w, Aabb::from_corners({-60, -6, -120}, {60, -6, 0}));
    const ecs::Entity box = mesh(w, Aabb::from_corners({-1, -6, -12}, {1, -4, -10}));
    CameraState cam = camera(w, 40.0f);
    ShadowCascadeState state;
    const ShadowData d = update_shadow_cascades(w, cam, state);
    ASSERT_TRUE(d.light.valid()) << d.error;
    for (int i = 0; i < d.cascade_count; ++i) {
      const auto c = std::size_t(i);
      if (d.skipped[c]) continue;
      EXPECT_NE(contains(d.casters[c], ground), on) << "cascade " << i;
      const glm::vec4 r = d.read_rect[c];
      if (on) {
        EXPECT_TRUE(r.x >= -1.0f && r.y >= -1.0f && r.z <= 1.0f && r.w <= 1.0f) << i;
        EXPECT_LT((r.z - r.x) * (r.w - r.y), 4.0f) << "cascade " << i << " is read whole";
      } else {
        EXPECT_EQ(r, glm::vec4(-1, -1, 1, 1));
      }
    }
    EXPECT_TRUE(contains(d.casters[0], box) || contains(d.casters[1], box));
  }
}

TEST(ShadowCascadeSystem, NanLightTransformIsRejectedWithAnError) {
  ecs::World w;
  const ecs::Entity l = sun(w, ShadowSettings{});
  mesh(w, Aabb::from_corners({-1, -1, -20}, {1, 0, -2}));
  w.get<WorldTransform>(l).matrix[1][2] = std::numeric_limits<float>::quiet_NaN();
  ShadowCascadeState state;
  const ShadowData d = update_shadow_cascades(w, camera(w), state);
  EXPECT_FALSE(d.light.valid());
  EXPECT_NE(d.error.find("NaN"), std::string::npos) << d.error;
  EXPECT_EQ(state.last_errors[0], d.error);
}

TEST(ShadowCascadeSystem, NonFiniteBoundsAreLeftOutAndTheRestShadowed) {
  ecs::World w;
  sun(w, ShadowSettings{});
  const ecs::Entity good = mesh(w, Aabb::from_corners({-1, -1, -20}, {1, 0, -2}));
  Aabb bad = Aabb::from_corners({-1, -1, -20}, {1, 0, -2});
  bad.max.x = std::numeric_limits<float>::infinity();
  const ecs::Entity broken = mesh(w, bad);
  ShadowCascadeState state;
  const ShadowData d = update_shadow_cascades(w, camera(w), state);
  ASSERT_TRUE(d.light.valid());
  EXPECT_NE(d.error.find("non-finite"), std::string::npos) << d.error;
  EXPECT_TRUE(contains(d.casters[0], good));
  for (const auto& list : d.casters) EXPECT_FALSE(contains(list, broken));
  for (int i = 0; i < d.cascade_count; ++i)
    EXPECT_TRUE(validate_transform(d.view_proj[std::size_t(i)]).empty());
}

TEST(ShadowCascadeSystem, NanCameraIsRejectedWithAnError) {
  ecs::World w;
  sun(w, ShadowSettings{});
  mesh(w, Aabb::from_corners({-1, -1, -20}, {1, 0, -2}));
  CameraState c = camera(w);
  c.view[3][0] = std::numeric_limits<float>::infinity();
  ShadowCascadeState state;
  const ShadowData d = update_shadow_cascades(w, c, state);
  EXPECT_FALSE(d.light.valid());
  EXPECT_NE(d.error.find("camera"), std::string::npos) << d.error;
}

TEST(ShadowCascadeSystem, SceneFitIsTheBasicMap) {
  ecs::World w;
  ShadowSettings s;
  s.cascade_count = 1;
  s.fit_mode = FitMode::scene;
  sun(w, s);
  mesh(w, Aabb::from_corners({-20, 0, -20}, {20, 0, 20}));
  mesh(w, Aabb::from_corners({-1, 0, -1}, {1, 2, 1}));
  ShadowCascadeState state;
  const ShadowData d = update_shadow_cascades(w, camera(w), state);
  const BasicShadow basic = update_basic_shadow(w);
  ASSERT_TRUE(d.light.valid());
  EXPECT_EQ(d.cascade_count, 1);
  EXPECT_EQ(d.view_proj[0], basic.projection.view_proj());  // bit-exact
  EXPECT_EQ(d.splits[0], 0.0f);
  EXPECT_EQ(d.splits[1], std::numeric_limits<float>::max());
}

TEST(ShadowCascadeSystem, NoShadowedLightOrNoGeometryGivesNoShadow) {
  ecs::World w;
  mesh(w, Aabb::from_corners({-1, -1, -20}, {1, 0, -2}));
  ShadowCascadeState state;
  EXPECT_FALSE(update_shadow_cascades(w, camera(w), state).light.valid());
  ecs::World empty;
  sun(empty, ShadowSettings{});
  const ShadowData d = update_shadow_cascades(empty, camera(empty), state);
  EXPECT_FALSE(d.light.valid());
  EXPECT_TRUE(d.error.empty());
}

}  // namespace
}  // namespace kaskad

namespace kaskad {
namespace {

// cull_casters() keeps exactly the boxes the 8-corner test keeps (a box is out when all its
// corners lie beyond one clip plane), for orthographic maps whose quick test rejects from the
// box's NDC bounds, near the origin and 4 km from it, with boxes placed across every edge of
// the clip volume; and for a perspective map, which takes the corner test alone.
TEST(CasterCulling, KeepsWhatTheCornerTestKeepsAtEveryEdge) {
  std::mt19937 gen(7u);
  auto uniform = [&](float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(gen); };
  auto corner_test = [](const glm::mat4& m, const Aabb& b) {
    for (int axis = 0; axis < 3; ++axis)
      for (float sign : {-1.0f, 1.0f}) {
        bool all_out = true;
        for (int i = 0; i < 8; ++i) {
          const glm::vec4 c = m * glm::vec4((i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y,
                                            (i & 4) ? b.max.z : b.min.z, 1.0f);
          all_out = all_out && sign * c[axis] > c.w;
        }
        if (all_out) return false;
      }
    return true;
  };
  int kept = 0, culled = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const glm::vec3 origin = trial % 2 ? glm::vec3(0.0f)
                                       : glm::vec3(uniform(-4000, 4000), uniform(-50, 50), uniform(-4000, 4000));
    const glm::vec3 dir = glm::normalize(glm::vec3(uniform(-1, 1), uniform(-1.0f, -0.2f), uniform(-1, 1)));
    const glm::mat4 view = glm::lookAt(origin - 100.0f * dir, origin, glm::vec3(0, 1, 0));
    const float w = uniform(5, 60);
    const glm::mat4 vp = trial % 8 == 7 ? glm::perspective(0.8f, 1.0f, 1.0f, 200.0f) * view
                                        : glm::ortho(-w, w, -w, w, 1.0f, 200.0f) * view;
    const glm::mat4 inv = glm::inverse(vp);
    std::vector<Aabb> boxes;
    for (int i = 0; i < 300; ++i) {
      // A point on or near a face of the clip volume, the box around it small or large.
      glm::vec3 ndc(uniform(-1.2f, 1.2f), uniform(-1.2f, 1.2f), uniform(-1.2f, 1.2f));
      ndc[i % 3] = (i % 2 ? 1.0f : -1.0f) * (1.0f + uniform(-0.02f, 0.02f));
      const glm::vec4 p = inv * glm::vec4(ndc, 1.0f);
      const glm::vec3 centre = glm::vec3(p) / p.w;
      const glm::vec3 half(uniform(0.01f, 2.0f), uniform(0.01f, 2.0f), uniform(0.01f, 2.0f));
      boxes.push_back(Aabb::from_corners(centre - half, centre + half));
    }
    boxes.push_back(Aabb{});  // empty: never kept
    std::vector<std::uint32_t> expected;
    for (std::uint32_t i = 0; i < boxes.size(); ++i)
      if (!boxes[i].empty() && corner_test(vp, boxes[i])) expected.push_back(i);
    EXPECT_EQ(cull_casters(vp, boxes), expected) << trial;
    kept += int(expected.size());
    culled += int(boxes.size() - expected.size());
  }
  EXPECT_GT(kept, 2000);
  EXPECT_GT(culled, 2000);
}

}  // namespace
}  // namespace kaskad
