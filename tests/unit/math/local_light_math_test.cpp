// Spot and point light shadow maths (runtime/math/local_light_math.h), without GL: depth ranges, the
// near plane that keeps every box inside the frustum, the spot frustum around its cone, cube face
// selection against each face's frustum, and the dual-paraboloid projection; plus the system's
// output for a spot and a point light.
#include "runtime/math/local_light_math.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <random>

#include "components/light.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "systems/shadow_cascade_system.h"

namespace kaskad {
namespace {

glm::vec3 ndc(const glm::mat4& view_proj, const glm::vec3& p) {
  const glm::vec4 c = view_proj * glm::vec4(p, 1.0f);
  return glm::vec3(c) / c.w;
}

bool inside(const glm::vec3& n, float eps = 1e-5f) {
  return std::abs(n.x) <= 1 + eps && std::abs(n.y) <= 1 + eps && std::abs(n.z) <= 1 + eps;
}

TEST(LocalLightMath, NearFarHoldsEveryBoxWithinRange) {
  const glm::vec3 light(0, 2, 0);
  const Aabb boxes[] = {Aabb::from_corners({1, 0, -1}, {3, 1, 1}),    // nearest point (1, 1, 0)
                        Aabb::from_corners({-5, -1, -5}, {5, 0, 5}),  // ground, 2 m below
                        Aabb::from_corners({50, 0, 0}, {51, 1, 1})};  // far away
  const NearFar all = local_light_near_far(light, boxes);
  ASSERT_FALSE(all.empty);
  EXPECT_NEAR(all.near, std::sqrt(2.0f), 1e-6f);
  EXPECT_NEAR(all.far, glm::length(glm::vec3(51, -2, 1)), 1e-4f);
  // A range leaves the far box out and clamps far.
  const NearFar ranged = local_light_near_far(light, boxes, 10.0f);
  EXPECT_NEAR(ranged.far, glm::length(glm::vec3(5, -3, 5)), 1e-4f);
  EXPECT_TRUE(local_light_near_far(light, std::span<const Aabb>(boxes + 2, 1), 10.0f).empty);
  // Inside a box: near 0, and the plane used stays at far / 1000.
  const Aabb room = Aabb::from_corners({-4, 0, -4}, {4, 4, 4});
  const NearFar in_room = local_light_near_far(light, std::span<const Aabb>(&room, 1));
  EXPECT_EQ(in_room.near, 0.0f);
  EXPECT_NEAR(local_light_near(in_room), in_room.far * 1e-3f, 1e-6f);
}

TEST(LocalLightMath, WidenedFieldOfViewLeavesTheBorderFree) {
  // The cone's edge lands border texels inside the map edge.
  const int size = 512;
  const float border = 3.5f;
  const float t = widen_tan_half_fov(1.0f, size, border);
  EXPECT_NEAR(1.0f / t * 0.5f * size, 0.5f * size - border, 1e-3f);
  EXPECT_GE(spot_tan_half_fov(89.9f, size, border), spot_tan_half_fov(45.0f, size, border));
  EXPECT_LE(spot_tan_half_fov(90.0f, size, border), std::tan(glm::radians(89.0f)) * 1.0001f);
}

TEST(LocalLightMath, SpotFrustumHoldsItsConeAndEveryBoxPointNearIt) {
  const glm::vec3 pos(1, 5, 2), dir = glm::normalize(glm::vec3(0.2f, -1, -0.3f));
  const float cone = 35.0f;
  const float tan_half = spot_tan_half_fov(cone, 1024, 3.5f);
  const float near = local_light_near({1.0f, 20.0f, false}, tan_half);
  const PerspectiveShadow m = fit_spot_shadow(pos, dir, tan_half, near, 20.0f, 1024);
  // Points on the cone's rim at several distances lie inside the map, a border away from its edge.
  const glm::vec3 side = glm::normalize(glm::cross(dir, glm::vec3(1, 0, 0)));
  for (float d : {1.0f, 5.0f, 19.0f})
    for (int k = 0; k < 16; ++k) {
      const float a = float(k) * 0.3927f;
      const glm::vec3 across = glm::rotate(glm::mat4(1.0f), a, dir) * glm::vec4(side, 0.0f);
      const glm::vec3 p =
          pos + d * (std::cos(glm::radians(cone)) * dir + std::sin(glm::radians(cone)) * across);
      const glm::vec3 n = ndc(m.view_proj(), p);
      EXPECT_TRUE(inside(n)) << d << " " << k;
      EXPECT_LE(std::max(std::abs(n.x), std::abs(n.y)), 1.0f - 2.0f * 3.5f / 1024 + 1e-4f);
    }
  // A point 1 m away (the nearest box) toward the frustum's corner is not clipped by near.
  const glm::vec3 right = glm::normalize(glm::cross(dir, light_up_vector(dir)));
  const glm::vec3 up = glm::cross(right, dir);
  const glm::vec3 corner = glm::normalize(dir + 0.99f * tan_half * (right + up));
  EXPECT_TRUE(inside(ndc(m.view_proj(), pos + corner)));
  EXPECT_NEAR(m.texel_at_unit_distance, 2.0f * tan_half / 1024.0f, 1e-7f);
}

TEST(LocalLightMath, CubeFaceOfEveryDirectionHoldsIt) {
  const glm::vec3 pos(-2, 1, 3);
  const float tan_half = cube_tan_half_fov(256, 3.5f);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::array<int, kCubeFaces> hits{};
  for (int i = 0; i < 2000; ++i) {
    glm::vec3 d(u(rng), u(rng), u(rng));
    if (glm::length(d) < 1e-3f) continue;
    const float dist = 0.5f + 10.0f * (u(rng) + 1.0f);
    const int f = cube_face_of(d);
    ++hits[std::size_t(f)];
    const PerspectiveShadow m = cube_face_shadow(pos, f, tan_half, 0.25f, 25.0f, 256);
    const glm::vec3 n = ndc(m.view_proj(), pos + dist * glm::normalize(d));
    EXPECT_TRUE(inside(n)) << "face " << f;
    // The face's own frustum holds it with the border to spare.
    EXPECT_LE(std::max(std::abs(n.x), std::abs(n.y)), 1.0f - 2.0f * 3.5f / 256 + 1e-4f);
  }
  for (int h : hits) EXPECT_GT(h, 200);
  EXPECT_EQ(cube_face_of({1, 1, 0.5f}), 0);  // tie x/y: x
  EXPECT_EQ(cube_face_of({0, -2, 1}), 3);
  EXPECT_EQ(cube_face_of({0.1f, 0.2f, -3}), 5);
}

TEST(LocalLightMath, ParaboloidProjectionCoversEachHemisphere) {
  const glm::vec3 pos(0, 2, 0), dir(1, 0, 0);
  const auto views = paraboloid_views(pos, dir);
  const float margin = paraboloid_margin(512, 3.5f);
  EXPECT_NEAR(margin, 7.0f / 512, 1e-7f);
  // The axis maps to the centre, the rim to radius 1 / (1 + margin), depth linear in distance.
  const glm::vec3 centre =
      paraboloid_project(glm::vec3(views[0] * glm::vec4(pos + 3.0f * dir, 1)), 1.0f, 5.0f, margin);
  EXPECT_NEAR(glm::length(glm::vec2(centre)), 0.0f, 1e-6f);
  EXPECT_NEAR(centre.z, 0.0f, 1e-6f);
  const glm::vec3 rim = paraboloid_project({0, 2, 0}, 1.0f, 5.0f, margin);
  EXPECT_NEAR(glm::length(glm::vec2(rim)), 1.0f / (1.0f + margin), 1e-6f);
  EXPECT_NEAR(rim.z, -0.5f, 1e-6f);
  // Hemisphere 1 looks the other way, and both views are rotations (winding kept).
  const glm::vec3 back = glm::vec3(views[1] * glm::vec4(pos - 2.0f * dir, 1));
  EXPECT_NEAR(back.z, -2.0f, 1e-5f);
  for (const glm::mat4& v : views) EXPECT_NEAR(glm::determinant(glm::mat3(v)), 1.0f, 1e-5f);
  // Every direction lands inside the disk of the hemisphere it belongs to.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < 1000; ++i) {
    const glm::vec3 d = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)) + glm::vec3(1e-4f));
    const glm::vec3 v0 = glm::vec3(views[0] * glm::vec4(pos + 4.0f * d, 1));
    const int h = v0.z <= 0.0f ? 0 : 1;
    const glm::vec3 v = glm::vec3(views[std::size_t(h)] * glm::vec4(pos + 4.0f * d, 1));
    EXPECT_LE(v.z, 1e-5f);
    EXPECT_LE(glm::length(glm::vec2(paraboloid_project(v, 1.0f, 5.0f, margin))),
              1.0f / (1.0f + margin) + 1e-5f);
  }
  // Texel size at the centre: 2 / size map units, (1/2) / (1 + margin) map units per radian.
  EXPECT_NEAR(paraboloid_texel_at_unit_distance(512, margin), 4.0f * (1 + margin) / 512, 1e-9f);
}

// The system for spot and point lights: projection, layer count, skipped layers, caster lists.
ecs::Entity light(ecs::World& w, LightType type, glm::vec3 pos, glm::vec3 dir,
                  PointShadowMode mode = PointShadowMode::cube) {
  const ecs::Entity e = w.create();
  Light l;
  l.type = type;
  l.outer_cone_deg = 30.0f;
  l.cast_shadows = true;
  w.emplace<Light>(e, l);
  WorldTransform wt;
  wt.matrix = glm::inverse(glm::lookAt(pos, pos + dir, light_up_vector(dir)));
  w.emplace<WorldTransform>(e, wt);
  ShadowSettings s;
  s.point_mode = mode;
  w.emplace<ShadowSettings>(e, s);
  return e;
}

// A square camera at (0, 5, 12) looking at the origin, near 0.5, far 60.
CameraState overview_camera(ecs::World& w) {
  CameraState cam;
  cam.entity = w.create();
  cam.camera.near = 0.5f;
  cam.camera.far = 60.0f;
  cam.view = glm::lookAt(glm::vec3(0, 5, 12), glm::vec3(0), glm::vec3(0, 1, 0));
  cam.proj = glm::perspective(glm::radians(cam.camera.fov_y_deg), 1.0f, 0.5f, 60.0f);
  return cam;
}

ecs::Entity box(ecs::World& w, const Aabb& b, bool cast, bool receive) {
  const ecs::Entity e = w.create();
  MeshRenderer mr;
  mr.mesh = MeshId{0};
  mr.cast_shadows = cast;
  mr.receive_shadows = receive;
  w.emplace<MeshRenderer>(e, mr);
  w.emplace<WorldBounds>(e, WorldBounds{b});
  return e;
}

TEST(ShadowCascadeSystem, SpotAndPointLightsGetTheirMaps) {
  for (LightType type : {LightType::spot, LightType::point}) {
    for (PointShadowMode mode : {PointShadowMode::cube, PointShadowMode::dual_paraboloid}) {
      if (type == LightType::spot && mode != PointShadowMode::cube) continue;
      ecs::World w;
      const ecs::Entity l = light(w, type, {0, 4, 0}, {0, -1, 0}, mode);
      const ecs::Entity ground =
          box(w, Aabb::from_corners({-10, -0.1f, -10}, {10, 0, 10}), false, true);
      const ecs::Entity blocker =
          box(w, Aabb::from_corners({-0.5f, 1, -0.5f}, {0.5f, 2, 0.5f}), true, true);
      // Far to the side, outside the spot's cone; a caster above the light.
      const ecs::Entity side = box(w, Aabb::from_corners({30, 0, 0}, {31, 1, 1}), true, false);
      const ecs::Entity above =
          box(w, Aabb::from_corners({-0.5f, 6, -0.5f}, {0.5f, 7, 0.5f}), true, false);
      ShadowCascadeState state;
      CameraState cam;  // local lights do not need the camera
      const ShadowData d = update_shadow_cascades(w, cam, state);
      ASSERT_EQ(d.light, l) << d.error;
      EXPECT_GT(d.splits[0], 0.0f);
      EXPECT_LT(d.splits[0], 2.0f);  // the blocker's top is 2 m below the light
      EXPECT_GT(d.splits[1], glm::length(glm::vec3(31, 4, 1)));
      auto drawn_anywhere = [&](ecs::Entity e) { return d.cascade_mask(e) != 0; };
      EXPECT_TRUE(drawn_anywhere(blocker));
      EXPECT_FALSE(drawn_anywhere(ground));  // not a caster
      if (type == LightType::spot) {
        EXPECT_EQ(d.projection, ShadowProjection::perspective);
        EXPECT_EQ(d.cascade_count, 1);
        EXPECT_FALSE(drawn_anywhere(side));
        EXPECT_FALSE(drawn_anywhere(above));
      } else if (mode == PointShadowMode::cube) {
        EXPECT_EQ(d.projection, ShadowProjection::cube);
        EXPECT_EQ(d.cascade_count, 6);
        EXPECT_EQ(d.cascade_mask(blocker), 1u << 3);  // -Y only
        // +Y sees no receiver (the caster above receives nothing): skipped, nothing drawn.
        EXPECT_TRUE(d.skipped[2]);
        EXPECT_FALSE(drawn_anywhere(above));
        EXPECT_TRUE(drawn_anywhere(side));
      } else {
        EXPECT_EQ(d.projection, ShadowProjection::dual_paraboloid);
        EXPECT_EQ(d.cascade_count, 2);
        EXPECT_GT(d.paraboloid_margin, 0.0f);
        EXPECT_EQ(d.cascade_mask(blocker), 1u);  // the lower hemisphere only
        EXPECT_FALSE(d.skipped[0]);
      }
    }
  }
}

TEST(ShadowCascadeSystem, SeveralDirectionalLightsEachGetCascadesUpToTheCap) {
  ecs::World w;
  box(w, Aabb::from_corners({-10, -0.1f, -10}, {10, 0, 10}), false, true);
  box(w, Aabb::from_corners({-0.5f, 1, -0.5f}, {0.5f, 2, 0.5f}), true, true);
  std::vector<ecs::Entity> suns;
  for (int i = 0; i < 5; ++i) {
    const float a = 0.7f * float(i);
    suns.push_back(light(w, LightType::directional, {0, 10, 0},
                         glm::normalize(glm::vec3(std::cos(a), -1.5f, std::sin(a)))));
    ShadowSettings& s = w.get<ShadowSettings>(suns.back());
    s.cascade_count = 1 + i;
    s.map_size = 512 << i;  // extra lights take the first one's
  }
  const CameraState cam = overview_camera(w);
  ShadowCascadeState state;
  const std::vector<ShadowData> all = update_shadows(w, cam, state);
  ASSERT_EQ(all.size(), std::size_t(kMaxShadowedLights));
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].light, suns[i]) << all[i].error;
    EXPECT_EQ(all[i].cascade_count, int(i) + 1);
    EXPECT_EQ(all[i].settings.map_size, 512);
    // Each light's own direction: its cascade matrices differ from the first light's.
    if (i > 0) {
      EXPECT_NE(all[i].view_proj[0], all[0].view_proj[0]);
    }
  }
  EXPECT_NE(state.last_notice.find("only the first 4"), std::string::npos) << state.last_notice;
  // The shared map size applies before fitting: the second light's texel sizes (and the stable
  // fit's snapping) are those of the same light fitted alone with a 512^2 map.
  {
    ecs::World alone;
    box(alone, Aabb::from_corners({-10, -0.1f, -10}, {10, 0, 10}), false, true);
    box(alone, Aabb::from_corners({-0.5f, 1, -0.5f}, {0.5f, 2, 0.5f}), true, true);
    const float a = 0.7f;
    const ecs::Entity sun = light(alone, LightType::directional, {0, 10, 0},
                                  glm::normalize(glm::vec3(std::cos(a), -1.5f, std::sin(a))));
    alone.get<ShadowSettings>(sun).cascade_count = 2;
    alone.get<ShadowSettings>(sun).map_size = 512;
    ShadowCascadeState alone_state;
    const std::vector<ShadowData> single = update_shadows(alone, cam, alone_state);
    for (int c = 0; c < 2; ++c) {
      EXPECT_EQ(all[1].texel_size[std::size_t(c)], single[0].texel_size[std::size_t(c)]) << c;
      EXPECT_EQ(all[1].view_proj[std::size_t(c)], single[0].view_proj[std::size_t(c)]) << c;
    }
  }
  // Lights 2.. asked for other map sizes: the notice names the field (with the light count).
  EXPECT_NE(state.last_notice.find("map_size differ from the first shadowed light's"),
            std::string::npos)
      << state.last_notice;
  // A spot light after the first shadowed light gets no maps.
  w.get<Light>(suns[1]).type = LightType::spot;
  const std::vector<ShadowData> some = update_shadows(w, cam, state);
  ASSERT_EQ(some.size(), std::size_t(kMaxShadowedLights));
  EXPECT_EQ(some[1].light, suns[2]);
}

// Settings shared by every shadowed light (one texture array, one set of frame features) come
// from the first; a later light that asks otherwise is told which fields (logged once).
TEST(ShadowCascadeSystem, SharedSettingsOfLaterLightsAreNamedInTheNotice) {
  ecs::World w;
  box(w, Aabb::from_corners({-10, -0.1f, -10}, {10, 0, 10}), false, true);
  box(w, Aabb::from_corners({-0.5f, 1, -0.5f}, {0.5f, 2, 0.5f}), true, true);
  light(w, LightType::directional, {0, 10, 0}, glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f)));
  const ecs::Entity second =
      light(w, LightType::directional, {0, 10, 0}, glm::normalize(glm::vec3(-0.3f, -1.0f, 0.1f)));
  const CameraState cam = overview_camera(w);
  ShadowCascadeState state;
  ASSERT_EQ(update_shadows(w, cam, state).size(), 2u);
  EXPECT_EQ(state.last_notice, "");  // same settings: nothing to say
  ShadowSettings& s = w.get<ShadowSettings>(second);
  s.filter = ShadowFilter::none;
  s.layered = !s.layered;
  s.debug_cascades = true;
  s.cascade_count = 2;  // per light: not named
  const std::vector<ShadowData> out = update_shadows(w, cam, state);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].settings.filter, out[0].settings.filter);
  EXPECT_EQ(out[1].cascade_count, 2);
  // The light is named (by its entity index) and exactly the differing shared fields are listed.
  EXPECT_NE(state.last_notice.find(std::to_string(second.index)), std::string::npos)
      << state.last_notice;
  EXPECT_NE(state.last_notice.find(": its filter, debug_cascades, layered differ from the first "
                                   "shadowed light's, whose values apply (one shared texture "
                                   "array, one set of shader features)"),
            std::string::npos)
      << state.last_notice;
}

// A camera at `eye` looking ahead and a little down (near 0.5, far 80, aspect 1.5), for the
// tests that move it between fits.
CameraState walking_camera(ecs::World& w, glm::vec3 eye) {
  CameraState cam;
  cam.entity = w.create();
  cam.camera.near = 0.5f;
  cam.camera.far = 80.0f;
  cam.aspect = 1.5f;
  cam.view = glm::lookAt(eye, eye + glm::vec3(0, -0.3f, -1), glm::vec3(0, 1, 0));
  cam.proj = glm::perspective(glm::radians(cam.camera.fov_y_deg), 1.5f, 0.5f, 80.0f);
  return cam;
}

// freeze_cascades keeps the splits and matrices while the camera moves, and unfreezing fits
// them to the camera again.
TEST(ShadowCascadeSystem, FrozenCascadesKeepTheirMatricesWhileTheCameraMoves) {
  ecs::World w;
  box(w, Aabb::from_corners({-50, -0.1f, -50}, {50, 0, 50}), false, true);
  const ecs::Entity blocker =
      box(w, Aabb::from_corners({-0.5f, 0, -0.5f}, {0.5f, 2, 0.5f}), true, true);
  const ecs::Entity sun =
      light(w, LightType::directional, {0, 10, 0}, glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f)));
  auto camera_at = [&](glm::vec3 eye) { return walking_camera(w, eye); };
  auto same_matrices = [](const ShadowData& a, const ShadowData& b) {
    for (int i = 0; i < a.cascade_count; ++i)
      if (a.view_proj[std::size_t(i)] != b.view_proj[std::size_t(i)]) return false;
    return a.splits == b.splits;
  };
  ShadowCascadeState state;
  const ShadowData before = update_shadow_cascades(w, camera_at({0, 3, 8}), state);
  ASSERT_TRUE(before.light.valid()) << before.error;
  // Unfrozen, a camera 20 m away gets other cascades.
  ShadowCascadeState other;
  EXPECT_FALSE(same_matrices(before, update_shadow_cascades(w, camera_at({20, 3, 30}), other)));
  w.get<ShadowSettings>(sun).freeze_cascades = true;
  const ShadowData frozen = update_shadow_cascades(w, camera_at({20, 3, 30}), state);
  EXPECT_TRUE(same_matrices(before, frozen));
  const ShadowData still = update_shadow_cascades(w, camera_at({-15, 6, 2}), state);
  EXPECT_TRUE(same_matrices(before, still));
  EXPECT_NE(still.cascade_mask(blocker), 0u);  // casters are culled against the frozen volumes
  w.get<ShadowSettings>(sun).freeze_cascades = false;
  const ShadowData moved = update_shadow_cascades(w, camera_at({-15, 6, 2}), state);
  EXPECT_FALSE(same_matrices(before, moved));
}

// far_cascade_interval k: cascade i >= 1 keeps last frame's fit except on frames where
// (frame + i) % k == 0; cascade 0 is fitted every frame; a camera that moves away from what a
// kept map covers gets that cascade refitted at once; k = 1 keeps nothing.
TEST(ShadowCascadeSystem, FarCascadesAreRefittedEveryKthFrameStaggered) {
  ecs::World w;
  box(w, Aabb::from_corners({-50, -0.1f, -50}, {50, 0, 50}), false, true);
  box(w, Aabb::from_corners({-0.5f, 0, -0.5f}, {0.5f, 2, 0.5f}), true, true);
  const ecs::Entity sun =
      light(w, LightType::directional, {0, 10, 0}, glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f)));
  auto camera_at = [&](glm::vec3 eye) { return walking_camera(w, eye); };
  w.get<ShadowSettings>(sun).far_cascade_interval = 3;
  ShadowCascadeState state;
  std::vector<std::uint32_t> held;
  ShadowData last;
  for (int f = 0; f < 7; ++f) {
    // A camera creeping sideways: each fit differs a little, each kept map still covers it.
    const ShadowData d = update_shadow_cascades(w, camera_at({0.01f * float(f), 3, 8}), state);
    ASSERT_TRUE(d.light.valid()) << d.error;
    ASSERT_EQ(d.cascade_count, 4);
    held.push_back(d.held);
    for (int i = 0; i < 4; ++i)
      if ((d.held >> i) & 1u) {
        EXPECT_EQ(d.view_proj[std::size_t(i)], last.view_proj[std::size_t(i)]) << f << " " << i;
        EXPECT_EQ(d.casters[std::size_t(i)], last.casters[std::size_t(i)]);
      }
    last = d;
  }
  // Frame 0 has nothing to keep; then cascade i is refitted when (f + i) % 3 == 0.
  EXPECT_EQ(held[0], 0u);
  for (int f = 1; f < 7; ++f) {
    std::uint32_t expected = 0;
    for (int i = 1; i < 4; ++i)
      if ((f + i) % 3 != 0) expected |= 1u << i;
    EXPECT_EQ(held[std::size_t(f)], expected) << "frame " << f;
  }
  // A jump far away: no kept map covers the new slices, all are refitted.
  EXPECT_EQ(update_shadow_cascades(w, camera_at({30, 3, -20}), state).held, 0u);
  // Off: nothing kept.
  w.get<ShadowSettings>(sun).far_cascade_interval = 1;
  ShadowCascadeState fresh;
  for (int f = 0; f < 3; ++f)
    EXPECT_EQ(update_shadow_cascades(w, camera_at({0.01f * float(f), 3, 8}), fresh).held, 0u);
}

}  // namespace
}  // namespace kaskad
