// The Embree reference against analytic visibility on primitive scenes built by hand (no GL).
#include "runtime/reference/ray_tracer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <type_traits>

#include <glm/gtc/matrix_transform.hpp>

#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "runtime/assets/primitives.h"
#include "runtime/assets/material_file.h"
#include "runtime/reference/shadow_metrics.h"

namespace kaskad::reference {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

static_assert(!std::is_copy_constructible_v<RayTracer> && !std::is_copy_assignable_v<RayTracer>);
static_assert(std::is_nothrow_move_constructible_v<RayTracer> &&
              std::is_nothrow_move_assignable_v<RayTracer>);

glm::mat4 trs(glm::vec3 t, glm::vec3 s = glm::vec3(1.0f)) {
  return glm::scale(glm::translate(glm::mat4(1.0f), t), s);
}

/// Adds a primitive entity to a hand-made scene (WorldTransform set directly).
ecs::Entity add(Scene& scene, PrimitiveShape shape, const glm::mat4& matrix,
                bool cast_shadows = true, bool receive_shadows = true, int segments = 32) {
  const MeshId mesh = scene.assets.add_mesh(make_primitive(shape, segments));
  const ecs::Entity e = scene.world.create();
  scene.world.emplace<MeshRenderer>(e, MeshRenderer{mesh, cast_shadows, receive_shadows});
  scene.world.emplace<WorldTransform>(e, WorldTransform{matrix});
  return e;
}

RayTracer build(const Scene& scene) {
  auto tracer = RayTracer::build(scene);
  if (!tracer.ok()) ADD_FAILURE() << tracer.error().to_string();
  return std::move(tracer).value();
}

/// An AOV image as Renderer::read_aovs() writes it; every pixel background (mask 0).
Image empty_aov(int width, int height) {
  Image img;
  img.width = width;
  img.height = height;
  img.channel_names = {"P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z", "Z", "visibility", "mask"};
  img.channels = int(img.channel_names.size());
  img.pixels.assign(std::size_t(width) * height * img.channels, 0.0f);
  return img;
}

void set_pixel(Image& aov, int x, int y, glm::vec3 p, glm::vec3 n) {
  for (int c = 0; c < 3; ++c) {
    aov.at(x, y, c) = p[c];
    aov.at(x, y, 3 + c) = n[c];
  }
  aov.at(x, y, 6) = 1.0f;  // Z
  aov.at(x, y, 7) = 1.0f;  // visibility
  aov.at(x, y, 8) = 1.0f;  // mask
}

/// An AOV of ground points (y = 0, normal +Y) on a square grid over [-half, half]^2 in XZ.
Image ground_aov(int n, float half) {
  Image aov = empty_aov(n, n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      set_pixel(aov, x, y, {-half + 2 * half * x / (n - 1), 0.0f, -half + 2 * half * y / (n - 1)},
                {0, 1, 0});
  return aov;
}

glm::vec3 aov_position(const Image& aov, int x, int y) {
  return {aov.at(x, y, 0), aov.at(x, y, 1), aov.at(x, y, 2)};
}

ShadowReference reference(const RayTracer& tracer, const Image& aov, const ReferenceLight& light,
                          ReferenceOptions options = {}) {
  auto r = tracer.shadow_reference(aov, light, options);
  if (!r.ok()) ADD_FAILURE() << r.error().to_string();
  return std::move(r).value();
}

ReferenceLight directional(glm::vec3 direction) {
  ReferenceLight l;
  l.type = LightType::directional;
  l.direction = glm::normalize(direction);
  return l;
}

ReferenceLight positional(LightType type, glm::vec3 position, glm::vec3 direction = {0, -1, 0}) {
  ReferenceLight l;
  l.type = type;
  l.position = position;
  l.direction = glm::normalize(direction);
  return l;
}

// Analytic occluders -----------------------------------------------------------------------------

/// Whether the ray o + t d (d unit, 0 < t < tmax) passes within `radius` of `centre`.
bool ray_hits_sphere(glm::vec3 o, glm::vec3 d, float tmax, glm::vec3 centre, float radius) {
  const float t = std::clamp(glm::dot(centre - o, d), 0.0f, tmax);
  return glm::length(o + t * d - centre) < radius;
}

/// Whether the segment o -> o + tmax d (d unit) meets the box [lo, hi] (slab test).
bool ray_hits_box(glm::vec3 o, glm::vec3 d, float tmax, glm::vec3 lo, glm::vec3 hi) {
  float t0 = 0.0f, t1 = tmax;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12f) {
      if (o[a] < lo[a] || o[a] > hi[a]) return false;
      continue;
    }
    float ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

/// Compares the reference with an analytic occlusion test over the image: `inside(p, shrink)`
/// tells whether the analytic occluder grown by `shrink` (negative: shrunk) blocks the ray from
/// ground point p. Pixels within `band` of the silhouette (blocked by the grown occluder but not
/// the shrunk one) are skipped. Returns the number of shadowed pixels checked.
int expect_matches_analytic(const ShadowReference& ref, const Image& aov,
                            const std::function<bool(glm::vec3, float)>& blocked, float band) {
  int shadowed = 0, compared = 0;
  for (int y = 0; y < aov.height; ++y) {
    for (int x = 0; x < aov.width; ++x) {
      const glm::vec3 p = aov_position(aov, x, y);
      const bool surely_blocked = blocked(p, -band);
      const bool maybe_blocked = blocked(p, band);
      if (surely_blocked != maybe_blocked) continue;  // silhouette band
      ++compared;
      const float expected = surely_blocked ? 0.0f : 1.0f;
      EXPECT_EQ(ref.image.at(x, y, 0), expected) << "pixel " << x << "," << y;
      shadowed += surely_blocked ? 1 : 0;
    }
  }
  EXPECT_GT(compared, aov.width * aov.height * 8 / 10);  // the band is thin
  return shadowed;
}

// Hard shadows -----------------------------------------------------------------------------------

TEST(RayTracer, EmptySceneIsLitEverywhere) {
  Scene scene;
  const RayTracer tracer = build(scene);
  EXPECT_EQ(tracer.occluder_triangles(), 0u);
  EXPECT_TRUE(tracer.bounds().empty());
  EXPECT_GT(tracer.ray_offset(), 0.0f);
  EXPECT_FALSE(tracer.occluded({0, 0, 0}, {0, 1, 0}, 1e30f));
  EXPECT_FALSE(tracer.trace_mirror({0, 0, 0}, {0, 1, 0}, {1, -1, 0}));
  const Image aov = ground_aov(8, 2.0f);
  for (const ReferenceLight& light :
       {directional({0.2f, -1, 0.1f}), positional(LightType::point, {0, 3, 0})}) {
    const ShadowReference ref = reference(tracer, aov, light);
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) {
        EXPECT_EQ(ref.image.at(x, y, 0), 1.0f);
        EXPECT_EQ(ref.image.at(x, y, 1), 1.0f);
      }
  }
  ReferenceLight area = positional(LightType::point, {0, 3, 0});
  area.size = 2.0f;
  EXPECT_EQ(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, area, 64, 1), 1.0f);
}

TEST(RayTracer, SphereAbovePlaneUnderDirectionalLightCastsTheAnalyticEllipse) {
  Scene scene;
  const glm::vec3 centre{0.3f, 2.0f, -0.2f};
  const float radius = 0.5f;  // unit sphere: diameter 1
  const int segments = 64;
  add(scene, PrimitiveShape::plane, trs({0, 0, 0}, {20, 1, 20}));
  add(scene, PrimitiveShape::sphere, trs(centre), true, true, segments);
  const RayTracer tracer = build(scene);
  const ReferenceLight light = directional({0.6f, -1.0f, 0.35f});
  const Image aov = ground_aov(121, 3.0f);
  const ShadowReference ref = reference(tracer, aov, light);

  // The tessellated sphere lies between the analytic sphere and one shrunk by the chord sag
  // r (1 - cos(pi / segments)) (inscribed vertices); plus a float margin.
  const float band = radius * (1.0f - std::cos(3.14159265f / segments)) + 2e-3f;
  const int shadowed = expect_matches_analytic(
      ref, aov,
      [&](glm::vec3 p, float grow) {
        return ray_hits_sphere(p, -light.direction, 1e30f, centre, radius + grow);
      },
      band);
  // The ellipse: area pi r^2 / cos(angle to the vertical), 1/20 of the grid spacing squared.
  const float cos_theta = -light.direction.y;
  const float cell = 6.0f / 120.0f;
  const float expected_pixels = 3.14159265f * radius * radius / cos_theta / (cell * cell);
  EXPECT_NEAR(float(shadowed), expected_pixels, 0.1f * expected_pixels);
  // Every ground pixel faces the light: all are receivers.
  for (int y = 0; y < aov.height; ++y)
    for (int x = 0; x < aov.width; ++x) ASSERT_EQ(ref.image.at(x, y, 1), 1.0f);
  EXPECT_GE(ref.rays, std::uint64_t(aov.width) * aov.height);
}

TEST(RayTracer, BoxUnderPointLightCastsTheAnalyticShadow) {
  Scene scene;
  add(scene, PrimitiveShape::plane, trs({0, 0, 0}, {20, 1, 20}));
  const glm::vec3 lo{-0.5f, 0.5f, -0.3f}, hi{0.5f, 1.5f, 0.7f};
  add(scene, PrimitiveShape::box, trs(0.5f * (lo + hi), hi - lo));
  const RayTracer tracer = build(scene);
  const glm::vec3 light_pos{0.4f, 4.0f, 0.2f};
  const ReferenceLight light = positional(LightType::point, light_pos);
  const Image aov = ground_aov(101, 4.0f);
  const ShadowReference ref = reference(tracer, aov, light);
  const int shadowed = expect_matches_analytic(
      ref, aov,
      [&](glm::vec3 p, float grow) {
        const glm::vec3 d = light_pos - p;
        return ray_hits_box(p, glm::normalize(d), glm::length(d), lo - grow, hi + grow);
      },
      2e-3f);
  EXPECT_GT(shadowed, 100);
  // The caster's own top face sees the light.
  EXPECT_EQ(tracer.hard_visibility({0, 1.5f + 1e-3f, 0.2f}, {0, 1, 0}, light), 1.0f);
}

TEST(RayTracer, SpotLightShadowAndCone) {
  Scene scene;
  add(scene, PrimitiveShape::plane, trs({0, 0, 0}, {20, 1, 20}));
  const glm::vec3 lo{-0.4f, 1.0f, -0.4f}, hi{0.4f, 1.2f, 0.4f};
  add(scene, PrimitiveShape::box, trs(0.5f * (lo + hi), hi - lo));
  const RayTracer tracer = build(scene);
  ReferenceLight light = positional(LightType::spot, {0.5f, 5.0f, 0}, {0, -1, 0});
  light.outer_cone_deg = 30.0f;
  const Image aov = ground_aov(81, 4.0f);
  const ShadowReference ref = reference(tracer, aov, light);
  const int shadowed = expect_matches_analytic(
      ref, aov,
      [&](glm::vec3 p, float grow) {
        const glm::vec3 d = light.position - p;
        return ray_hits_box(p, glm::normalize(d), glm::length(d), lo - grow, hi + grow);
      },
      2e-3f);
  EXPECT_GT(shadowed, 20);
  // Receivers: inside the 30 degree cone (radius 5 tan 30 = 2.89 around (0.5, 0)) only.
  const float cone_radius = 5.0f * std::tan(glm::radians(30.0f));
  for (int y = 0; y < aov.height; ++y) {
    for (int x = 0; x < aov.width; ++x) {
      const glm::vec3 p = aov_position(aov, x, y);
      const float r = glm::length(glm::vec2(p.x - 0.5f, p.z));
      if (std::abs(r - cone_radius) < 0.05f) continue;
      EXPECT_EQ(ref.image.at(x, y, 1), r < cone_radius ? 1.0f : 0.0f) << p.x << "," << p.z;
    }
  }
  // Range: only points within 5.5 m of the light receive it.
  light.range = 5.5f;
  const ShadowReference ranged = reference(tracer, aov, light);
  for (int y = 0; y < aov.height; ++y) {
    for (int x = 0; x < aov.width; ++x) {
      const float d = glm::length(light.position - aov_position(aov, x, y));
      if (std::abs(d - 5.5f) < 0.02f) continue;
      EXPECT_EQ(ranged.image.at(x, y, 1), d < 5.5f && ref.image.at(x, y, 1) == 1.0f ? 1.0f : 0.0f);
    }
  }
}

TEST(RayTracer, OnlyCastersOccludeAndNonReceiversAreNotCounted) {
  Scene scene;
  const ecs::Entity ground = add(scene, PrimitiveShape::plane, trs({0, 0, 0}, {20, 1, 20}));
  add(scene, PrimitiveShape::box, trs({-1, 1, 0}), /*cast_shadows=*/false);
  add(scene, PrimitiveShape::box, trs({1, 1, 0}), /*cast_shadows=*/true, /*receive=*/false);
  const RayTracer tracer = build(scene);
  EXPECT_EQ(tracer.occluder_triangles(), 2u + 12u);  // plane + the casting box
  EXPECT_EQ(tracer.surface_triangles(), 2u + 24u);
  const ReferenceLight sun = directional({0, -1, 0});
  EXPECT_EQ(tracer.hard_visibility({-1, 0, 0}, {0, 1, 0}, sun), 1.0f);  // non-caster
  EXPECT_EQ(tracer.hard_visibility({1, 0, 0}, {0, 1, 0}, sun), 0.0f);   // caster
  // The non-caster is still a surface (mirror rays see it).
  const auto hit = tracer.intersect({-1, 3, 0}, {0, -1, 0});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->position.y, 1.5f, 1e-5f);

  // Pixel 0 on the ground, pixel 1 on top of the non-receiving box.
  Image aov = empty_aov(2, 1);
  set_pixel(aov, 0, 0, {3, 0, 3}, {0, 1, 0});
  set_pixel(aov, 1, 0, {1, 1.5f, 0.1f}, {0, 1, 0});
  const ShadowReference ref = reference(tracer, aov, sun);
  EXPECT_EQ(ref.image.at(0, 0, 1), 1.0f);
  EXPECT_EQ(ref.image.at(1, 0, 1), 0.0f);
  EXPECT_EQ(ref.image.at(1, 0, 0), 1.0f);  // still traced: the box top is lit
  ReferenceOptions all;
  all.respect_receive_shadows = false;
  EXPECT_EQ(reference(tracer, aov, sun, all).image.at(1, 0, 1), 1.0f);
  (void)ground;
}

TEST(RayTracer, FacingAwayIsShadowedAndGrazingIsNoReceiver) {
  Scene scene;
  add(scene, PrimitiveShape::plane, trs({0, 0, 0}, {20, 1, 20}));
  const RayTracer tracer = build(scene);
  Image aov = empty_aov(3, 1);
  set_pixel(aov, 0, 0, {0, 0, 0}, {0, 1, 0});
  set_pixel(aov, 1, 0, {0, 0, 0}, {0, -1, 0});  // seen from below: the normal faces down
  set_pixel(aov, 2, 0, {0, 0, 0}, {0, 1, 0});
  // The light 2 degrees above the horizon: N . L = sin 2 deg = 0.035 < 0.05.
  const float a = glm::radians(2.0f);
  const ShadowReference grazing =
      reference(tracer, aov, directional({-std::cos(a), -std::sin(a), 0}));
  EXPECT_EQ(grazing.image.at(0, 0, 0), 1.0f);
  EXPECT_EQ(grazing.image.at(0, 0, 1), 0.0f);
  EXPECT_EQ(grazing.image.at(1, 0, 0), 0.0f);  // faces away
  EXPECT_EQ(grazing.image.at(1, 0, 1), 0.0f);
  const ShadowReference high = reference(tracer, aov, directional({-0.5f, -1, 0}));
  EXPECT_EQ(high.image.at(0, 0, 1), 1.0f);
  EXPECT_EQ(high.image.at(1, 0, 1), 0.0f);
}

TEST(RayTracer, LightAndNormalVectorsNeedNotBeUnit) {
  Scene scene;
  add(scene, PrimitiveShape::box, trs({0, 2, 0}));
  const RayTracer tracer = build(scene);
  ReferenceLight sun;
  sun.direction = {0, -5, 0};
  sun.right = {3, 1, 0};  // not perpendicular either
  EXPECT_EQ(tracer.hard_visibility({0, 0, 0}, {0, 1, 0}, sun), 0.0f);
  EXPECT_EQ(tracer.hard_visibility({3, 0, 0}, {0, 1, 0}, sun), 1.0f);
  sun.angular_size_deg = 4.0f;
  EXPECT_EQ(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, sun, 16, 1), 0.0f);
  sun.direction = {0, 0, 0};  // no direction at all: straight down
  EXPECT_EQ(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, sun, 16, 1), 0.0f);
  const auto hit = tracer.trace_mirror({0, 0, 0}, {0, 10, 0}, {0, -1, 0});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance, 1.5f, 1e-3f);
}

TEST(RayTracer, DegenerateTrianglesAndNonFiniteInputNeverCrash) {
  Scene scene;
  MeshData mesh;
  mesh.name = "broken";
  mesh.positions = {{0, 1, 0},   {0, 1, 0},    {0, 1, 0},   // degenerate: one point
                    {-1, 1, 0},  {1, 1, 0},    {3, 1, 0},   // degenerate: collinear
                    {0, 1, 0},   {kNaN, 1, 0}, {0, 1, 1},   // non-finite vertex
                    {-1, 2, -1}, {-1, 2, 1},   {1, 2, 0}};  // a proper triangle
  mesh.indices = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  const MeshId id = scene.assets.add_mesh(mesh);
  const ecs::Entity e = scene.world.create();
  scene.world.emplace<MeshRenderer>(e, MeshRenderer{id, true, true});
  scene.world.emplace<WorldTransform>(e, WorldTransform{glm::mat4(1.0f)});
  const ecs::Entity no_mesh = scene.world.create();  // a MeshRenderer without a mesh is skipped
  scene.world.emplace<MeshRenderer>(no_mesh, MeshRenderer{});
  scene.world.emplace<WorldTransform>(no_mesh, WorldTransform{});
  const RayTracer tracer = build(scene);
  EXPECT_EQ(tracer.occluder_triangles(), 3u);                 // the non-finite one is dropped
  EXPECT_TRUE(tracer.occluded({0, 0, 0}, {0, 1, 0}, 10.0f));  // the proper triangle at y = 2
  EXPECT_FALSE(tracer.occluded({0, 0, 0}, {kNaN, 1, 0}, 10.0f));
  EXPECT_FALSE(tracer.occluded({0, 0, 0}, {0, 0, 0}, 10.0f));
  EXPECT_FALSE(tracer.occluded({0, 0, 0}, {0, 1, 0}, -1.0f));
  EXPECT_FALSE(tracer.intersect({kNaN, 0, 0}, {0, 1, 0}));

  // AOV pixels: NaN with mask 0 (background), NaN with mask 1 (broken), a zero normal.
  Image aov = empty_aov(4, 1);
  for (int c = 0; c < 6; ++c) aov.at(0, 0, c) = kNaN;
  set_pixel(aov, 1, 0, {kNaN, 0, 0}, {0, 1, 0});
  set_pixel(aov, 2, 0, {0, 0, 0}, {0, 0, 0});
  set_pixel(aov, 3, 0, {0, 0, 0}, {0, 1, 0});
  aov.at(3, 0, 8) = kNaN;  // NaN mask
  ReferenceLight area = positional(LightType::point, {0, 4, 0});
  area.size = 1.0f;
  for (const ReferenceLight& light : {directional({0, -1, 0}), area}) {
    const ShadowReference ref = reference(tracer, aov, light);
    for (int x = 0; x < 4; ++x) {
      EXPECT_EQ(ref.image.at(x, 0, 0), 1.0f) << x;
      EXPECT_EQ(ref.image.at(x, 0, 1), 0.0f) << x;
    }
  }
}

TEST(RayTracer, ContentErrorsAreReported) {
  {
    Scene scene;
    const ecs::Entity e = scene.world.create();
    scene.world.emplace<MeshRenderer>(e, MeshRenderer{MeshId{7}, true, true});
    scene.world.emplace<WorldTransform>(e, WorldTransform{});
    const auto tracer = RayTracer::build(scene);
    ASSERT_FALSE(tracer.ok());
    EXPECT_NE(tracer.error().message.find("mesh 7"), std::string::npos) << tracer.error().message;
  }
  {
    Scene scene;
    MeshData mesh;
    mesh.name = "bad_indices";
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
    mesh.indices = {0, 1, 5};
    const MeshId id = scene.assets.add_mesh(mesh);
    const ecs::Entity e = scene.world.create();
    scene.world.emplace<MeshRenderer>(e, MeshRenderer{id, true, true});
    scene.world.emplace<WorldTransform>(e, WorldTransform{});
    const auto tracer = RayTracer::build(scene);
    ASSERT_FALSE(tracer.ok());
    EXPECT_NE(tracer.error().to_string().find("bad_indices"), std::string::npos);
    EXPECT_NE(tracer.error().message.find("index 5"), std::string::npos);
  }
  Scene scene;
  const RayTracer tracer = build(scene);
  Image aov = empty_aov(2, 2);
  aov.channel_names[8] = "alpha";
  const auto missing = tracer.shadow_reference(aov, directional({0, -1, 0}));
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("'mask'"), std::string::npos);
  aov.pixels.pop_back();
  EXPECT_FALSE(tracer.shadow_reference(aov, directional({0, -1, 0})).ok());
  // Unnamed 9-channel images are read in Renderer::read_aovs() order.
  Image unnamed = ground_aov(4, 1.0f);
  unnamed.channel_names.clear();
  EXPECT_TRUE(tracer.shadow_reference(unnamed, directional({0, -1, 0})).ok());
}

TEST(RayTracer, MovedTracerKeepsWorking) {
  Scene scene;
  add(scene, PrimitiveShape::box, trs({0, 1, 0}));
  RayTracer a = build(scene);
  RayTracer b = std::move(a);
  EXPECT_TRUE(b.occluded({0, 0, 0}, {0, 1, 0}, 10.0f));
  RayTracer c = build(Scene{});
  c = std::move(b);
  EXPECT_TRUE(c.occluded({0, 0, 0}, {0, 1, 0}, 10.0f));
}

TEST(RayTracer, ReferenceLightFromAComponent) {
  Light spot;
  spot.type = LightType::spot;
  spot.outer_cone_deg = 25.0f;
  spot.range = 12.0f;
  // Rotated -90 degrees about +X: local -Z turns to world -Y (a spot pointing down), +X stays.
  const glm::mat4 m = glm::rotate(glm::translate(glm::mat4(1.0f), {1, 5, 2}), glm::radians(-90.0f),
                                  glm::vec3(1, 0, 0));
  const ReferenceLight l = reference_light(spot, m);
  EXPECT_EQ(l.type, LightType::spot);
  EXPECT_NEAR(glm::length(l.position - glm::vec3(1, 5, 2)), 0.0f, 1e-6f);
  EXPECT_NEAR(glm::length(l.direction - glm::vec3(0, -1, 0)), 0.0f, 1e-6f);
  EXPECT_NEAR(glm::length(l.right - glm::vec3(1, 0, 0)), 0.0f, 1e-6f);
  EXPECT_EQ(l.outer_cone_deg, 25.0f);
  EXPECT_EQ(l.range, 12.0f);
  EXPECT_FALSE(l.is_area());
  Light sun;  // directional: no cone, no range
  sun.range = 3.0f;
  const ReferenceLight s = reference_light(sun, glm::mat4(1.0f));
  EXPECT_NEAR(glm::length(s.direction - glm::vec3(0, 0, -1)), 0.0f, 1e-6f);
  EXPECT_EQ(s.outer_cone_deg, 180.0f);
  EXPECT_EQ(s.range, 0.0f);
  EXPECT_FALSE(s.is_area());
  // The component's angular size makes the sun an area light; spot/point lights ignore it.
  sun.angular_size_deg = 0.53f;
  EXPECT_EQ(reference_light(sun, glm::mat4(1.0f)).angular_size_deg, 0.53f);
  EXPECT_TRUE(reference_light(sun, glm::mat4(1.0f)).is_area());
  spot.angular_size_deg = 2.0f;
  EXPECT_FALSE(reference_light(spot, m).is_area());
  // An area light: its rectangle (width along +X, height along +Y) and its cone.
  Light panel;
  panel.type = LightType::area;
  panel.size = {2.0f, 0.5f};
  panel.outer_cone_deg = 60.0f;
  const ReferenceLight a = reference_light(panel, m);
  EXPECT_TRUE(a.is_area());
  EXPECT_EQ(a.size, 2.0f);
  EXPECT_EQ(a.height, 0.5f);
  EXPECT_EQ(a.outer_cone_deg, 60.0f);
}

// Area lights ------------------------------------------------------------------------------------

/// Visible fraction of a square light (side `size`, centred at height `light_h` above (0, 0),
/// parallel to the ground) from ground point p, with a parallel square occluder of side `a`
/// centred at `c` (height c.y): the occluder projected from p onto the light's plane is a square of
/// side a * s centred at p + (c - p) * s, s = light_h / c.y; blocked = overlap area / light area.
/// The light square is axis-aligned, as is the occluder.
float parallel_square_visibility(glm::vec2 p, float size, float light_h, glm::vec3 c, float a) {
  const float s = light_h / c.y;
  const glm::vec2 centre = p + (glm::vec2(c.x, c.z) - p) * s;
  const float half = 0.5f * a * s;
  auto overlap = [&](float c0, float h0, float c1, float h1) {
    return std::max(0.0f, std::min(c0 + h0, c1 + h1) - std::max(c0 - h0, c1 - h1));
  };
  const float blocked =
      overlap(centre.x, half, 0.0f, 0.5f * size) * overlap(centre.y, half, 0.0f, 0.5f * size);
  return 1.0f - blocked / (size * size);
}

TEST(RayTracer, AreaLightFullyBlockedAndUnblocked) {
  Scene scene;
  add(scene, PrimitiveShape::plane, trs({0, 2, 0}, {30, 1, 30}));  // a large blocker
  const RayTracer tracer = build(scene);
  ReferenceLight square = positional(LightType::point, {0, 5, 0});
  square.size = 2.0f;
  ReferenceLight sun = directional({0, -1, 0});
  sun.angular_size_deg = 10.0f;
  EXPECT_EQ(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, square, 256, 7), 0.0f);
  EXPECT_EQ(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, sun, 256, 7), 0.0f);
  // Above the blocker nothing is in the way.
  EXPECT_EQ(tracer.area_light_visibility({0, 3, 0}, {0, 1, 0}, square, 256, 7), 1.0f);
  EXPECT_EQ(tracer.area_light_visibility({0, 3, 0}, {0, 1, 0}, sun, 256, 7), 1.0f);
}

TEST(RayTracer, AreaLightHalfBlockedByAnEdgeThroughTheMiddle) {
  Scene scene;
  // Half-plane x < 0 at y = 2.5 (a 40 x 40 plane whose edge is the line x = 0).
  add(scene, PrimitiveShape::plane, trs({-20, 2.5f, 0}, {40, 1, 40}));
  const RayTracer tracer = build(scene);
  ReferenceLight square = positional(LightType::spot, {0, 5, 0});
  square.size = 2.0f;
  // Strata edges on the blocker's edge: exactly half of the samples.
  EXPECT_NEAR(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, square, 256, 3), 0.5f, 1e-6f);
  // Rotated 30 degrees about the axis: the edge cuts strata; Monte Carlo tolerance.
  square.right = {std::cos(glm::radians(30.0f)), 0, std::sin(glm::radians(30.0f))};
  for (std::uint32_t seed : {1u, 2u, 3u})
    EXPECT_NEAR(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, square, 256, seed), 0.5f, 0.03f);
  // A cone of directions around straight down, blocked for every direction with x < 0.
  ReferenceLight sun = directional({0, -1, 0});
  sun.angular_size_deg = 10.0f;
  EXPECT_NEAR(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, sun, 256, 5), 0.5f, 0.03f);
  sun.right = glm::normalize(glm::vec3(1, 0, 1));
  EXPECT_NEAR(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, sun, 256, 5), 0.5f, 0.03f);
}

// A rectangular emitter (an area light's size): a half-plane whose edge runs along the light's
// width hides the half of its height; turned to run along the height, the half of its width.
// A thin bar over the middle hides the fraction of the rectangle it covers, which differs with
// the rectangle's orientation: proves the sampling uses height along direction x right.
TEST(RayTracer, RectangularAreaLightIsSampledOverItsWidthAndHeight) {
  Scene scene;
  // A bar 0.4 wide along x (infinite along z) halfway up: its shadow on the light plane seen
  // from the origin is 0.8 wide along x.
  add(scene, PrimitiveShape::plane, trs({0, 2, 0}, {0.4f, 1, 40}));
  const RayTracer tracer = build(scene);
  ReferenceLight panel = positional(LightType::area, {0, 4, 0});
  panel.right = {1, 0, 0};  // width along x
  panel.size = 2.0f;
  panel.height = 0.5f;
  // Width 2 along x: the bar's 0.8 hides 0.8 / 2 of it.
  EXPECT_NEAR(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, panel, 4096, 3), 1.0f - 0.4f,
              0.01f);
  // Width along z instead: the height (0.5) lies along x, and the bar's 0.8 covers all of it.
  panel.right = {0, 0, 1};
  EXPECT_NEAR(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, panel, 4096, 3), 0.0f, 0.01f);
}

TEST(RayTracer, AreaLightBehindAParallelSquareMatchesTheOverlapArea) {
  Scene scene;
  const glm::vec3 c{0.3f, 2.0f, -0.2f};
  const float a = 0.8f;
  add(scene, PrimitiveShape::plane, trs(c, {a, 1, a}));  // parallel square occluder
  const RayTracer tracer = build(scene);
  ReferenceLight light = positional(LightType::point, {0, 4, 0});
  light.size = 2.0f;
  // S1's case worked by hand: p = origin, projection side 1.6 centred at (0.6, -0.4):
  // overlap 1.2 x 1.4 = 1.68 of 4, visibility 0.58.
  EXPECT_NEAR(parallel_square_visibility({0, 0}, 2.0f, 4.0f, c, a), 0.58f, 1e-6f);
  for (const glm::vec2 p : {glm::vec2(0, 0), glm::vec2(0.5f, 0.1f), glm::vec2(-0.6f, -0.9f),
                            glm::vec2(1.2f, 0.4f), glm::vec2(0.3f, -0.2f)}) {
    const float expected = parallel_square_visibility(p, 2.0f, 4.0f, c, a);
    // 256 samples: about 20 strata cut by the projected edges, sigma about 0.008.
    EXPECT_NEAR(tracer.area_light_visibility({p.x, 0, p.y}, {0, 1, 0}, light, 256, 11), expected,
                0.03f)
        << p.x << "," << p.y;
    EXPECT_NEAR(tracer.area_light_visibility({p.x, 0, p.y}, {0, 1, 0}, light, 4096, 11), expected,
                0.005f)
        << p.x << "," << p.y;
  }
}

TEST(RayTracer, AreaSamplesBelowTheHorizonAreBlocked) {
  const RayTracer tracer = build(Scene{});
  // A wall point facing +X; the light's centre lies in the wall's plane, so half of it is behind.
  ReferenceLight square = positional(LightType::point, {0, 0, 3}, {0, 0, -1});
  square.size = 2.0f;
  EXPECT_NEAR(tracer.area_light_visibility({0, 0, 0}, {1, 0, 0}, square, 256, 1), 0.5f, 1e-6f);
  ReferenceLight sun = directional({0, 0, -1});
  sun.angular_size_deg = 10.0f;
  EXPECT_NEAR(tracer.area_light_visibility({0, 0, 0}, {1, 0, 0}, sun, 256, 1), 0.5f, 1e-6f);
  EXPECT_EQ(tracer.area_light_visibility({0, 0, 0}, {0, 0, -1}, square, 256, 1),
            0.0f);  // faces away
  EXPECT_EQ(tracer.area_light_visibility({0, 0, 0}, {0, 0, 1}, square, 256, 1), 1.0f);
}

TEST(RayTracer, ConeOfDirectionsIsSampledUniformlyBySolidAngle) {
  // A sphere straight above the point subtends a cone of half-angle asin(R / D); the sun's cone
  // has half-angle 10 degrees. Blocked fraction = (1 - cos a) / (1 - cos 10 deg) (solid angles).
  Scene scene;
  const float distance = 10.0f, alpha = glm::radians(5.0f);
  const float radius = distance * std::sin(alpha);
  add(scene, PrimitiveShape::sphere, trs({0, distance, 0}, glm::vec3(2.0f * radius)), true, true,
      256);
  const RayTracer tracer = build(scene);
  ReferenceLight sun = directional({0, -1, 0});
  sun.angular_size_deg = 20.0f;
  const float blocked = (1.0f - std::cos(alpha)) / (1.0f - std::cos(glm::radians(10.0f)));
  EXPECT_NEAR(blocked, 0.2505f, 1e-3f);
  EXPECT_NEAR(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, sun, 1024, 4), 1.0f - blocked,
              0.02f);
}

TEST(RayTracer, CastersBeyondTheLightDoNotShadow) {
  Scene scene;
  add(scene, PrimitiveShape::plane, trs({0, 3, 0}, {20, 1, 20}));  // a ceiling above the light
  const RayTracer tracer = build(scene);
  ReferenceLight lamp = positional(LightType::point, {0, 2, 0});
  EXPECT_EQ(tracer.hard_visibility({0.5f, 0, 0.5f}, {0, 1, 0}, lamp), 1.0f);
  lamp.size = 1.0f;
  EXPECT_EQ(tracer.area_light_visibility({0.5f, 0, 0.5f}, {0, 1, 0}, lamp, 64, 1), 1.0f);
  // A light just under the ceiling, 1 mm below it: the ray stops short of the light.
  lamp = positional(LightType::spot, {0, 2.999f, 0});
  EXPECT_EQ(tracer.hard_visibility({0.5f, 0, 0.5f}, {0, 1, 0}, lamp), 1.0f);
  // The directional light is behind the ceiling: shadowed.
  EXPECT_EQ(tracer.hard_visibility({0.5f, 0, 0.5f}, {0, 1, 0}, directional({0, -1, 0})), 0.0f);
}

TEST(RayTracer, AreaReferenceIsDeterministicAndThreadIndependent) {
  Scene scene;
  add(scene, PrimitiveShape::plane, trs({0, 0, 0}, {20, 1, 20}));
  add(scene, PrimitiveShape::sphere, trs({0, 1, 0}));
  const RayTracer tracer = build(scene);
  ReferenceLight light = positional(LightType::point, {0.5f, 4, 0.3f});
  light.size = 1.5f;
  const Image aov = ground_aov(24, 2.0f);
  ReferenceOptions one, two;
  one.threads = 1;
  one.area_samples = 64;
  two.threads = 2;
  two.area_samples = 64;
  const ShadowReference a = reference(tracer, aov, light, one);
  const ShadowReference b = reference(tracer, aov, light, two);
  EXPECT_EQ(a.image.pixels, b.image.pixels);
  EXPECT_EQ(a.rays, b.rays);
  // Penumbra values between 0 and 1 exist, and the umbra under the sphere is 0.
  int fractional = 0;
  for (std::size_t i = 0; i < a.image.pixels.size(); i += 2) {
    EXPECT_GE(a.image.pixels[i], 0.0f);
    EXPECT_LE(a.image.pixels[i], 1.0f);
    fractional += (a.image.pixels[i] > 0.0f && a.image.pixels[i] < 1.0f) ? 1 : 0;
  }
  EXPECT_GT(fractional, 20);
  EXPECT_EQ(tracer.area_light_visibility({0.05f, 0, 0.05f}, {0, 1, 0}, light, 64, 9), 0.0f);
  // A different seed changes penumbra values, not the umbra.
  ReferenceOptions other = two;
  other.seed = 99;
  EXPECT_NE(reference(tracer, aov, light, other).image.pixels, a.image.pixels);
}

// Mirror rays ------------------------------------------------------------------------------------

TEST(RayTracer, MirrorRayHitsTheRightObject) {
  Scene scene;
  const ecs::Entity ground = add(scene, PrimitiveShape::plane, trs({0, 0, 0}, {20, 1, 20}));
  const ecs::Entity box = add(scene, PrimitiveShape::box, trs({3, 3.2f, 0}), false);
  const ecs::Entity sphere = add(scene, PrimitiveShape::sphere, trs({-3, 3, 0}));
  const RayTracer tracer = build(scene);
  // Seen from up-left at 45 degrees: R = (1, 1, 0) / sqrt 2, entering the box through its bottom
  // face y = 2.7 at x = 2.7.
  const auto hit = tracer.trace_mirror({0, 0, 0}, {0, 1, 0}, {1, -1, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->entity, box);
  // (The origin sits ray_offset() above the ground: a fraction of a millimetre.)
  EXPECT_NEAR(glm::length(hit->position - glm::vec3(2.7f, 2.7f, 0)), 0.0f, 1e-3f);
  EXPECT_NEAR(glm::length(hit->normal - glm::vec3(0, -1, 0)), 0.0f, 1e-5f);
  EXPECT_NEAR(hit->distance, 2.7f * std::sqrt(2.0f), 1e-3f);
  // The other way: the sphere (centre (-3, 3), radius 0.5) is on the line y = -x.
  const auto hit2 = tracer.trace_mirror({0, 0, 0}, {0, 1, 0}, {-1, -1, 0});
  ASSERT_TRUE(hit2);
  EXPECT_EQ(hit2->entity, sphere);
  EXPECT_NEAR(hit2->distance, 3.0f * std::sqrt(2.0f) - 0.5f, 0.01f);
  EXPECT_GT(glm::dot(hit2->normal, glm::vec3(1, -1, 0)), 0.9f);  // faces back along the ray
  // A normal given facing away from the eye is flipped first: same reflection.
  const auto flipped = tracer.trace_mirror({0, 0, 0}, {0, -1, 0}, {1, -1, 0});
  ASSERT_TRUE(flipped);
  EXPECT_EQ(flipped->entity, box);
  // Straight up into the empty sky: a miss; straight down onto the ground from above: the ground.
  EXPECT_FALSE(tracer.trace_mirror({5, 0, 5}, {0, 1, 0}, {0, -1, 0}));
  const auto down = tracer.intersect({5, 1, 5}, {0, -2, 0});
  ASSERT_TRUE(down);
  EXPECT_EQ(down->entity, ground);
  EXPECT_NEAR(down->distance, 1.0f, 1e-5f);
  EXPECT_FALSE(tracer.intersect({5, 1, 5}, {0, -2, 0}, 0.4f));  // tmax in direction lengths
}

// Reference and metrics together ----------------------------------------------------------------

TEST(RayTracer, ReferenceComparedWithItselfHasNoErrors) {
  Scene scene;
  add(scene, PrimitiveShape::plane, trs({0, 0, 0}, {20, 1, 20}));
  add(scene, PrimitiveShape::box, trs({0, 1, 0}));
  const RayTracer tracer = build(scene);
  Image aov = ground_aov(64, 3.0f);
  const ReferenceLight light = directional({0.5f, -1, 0.2f});
  const ShadowReference ref = reference(tracer, aov, light);
  for (int y = 0; y < aov.height; ++y)
    for (int x = 0; x < aov.width; ++x) aov.at(x, y, 7) = ref.image.at(x, y, 0);
  const auto same = compare_shadows(aov, ref.image);
  ASSERT_TRUE(same.ok());
  EXPECT_EQ(same->all.pixels, std::size_t(64 * 64));
  EXPECT_EQ(same->all.misclassified, 0u);
  EXPECT_EQ(same->all.rmse, 0.0);
  EXPECT_GT(same->edge_pixels, 0u);
  // A method that loses the caster (everything lit): every shadowed pixel is a false light.
  for (int y = 0; y < aov.height; ++y)
    for (int x = 0; x < aov.width; ++x) aov.at(x, y, 7) = 1.0f;
  const auto lost = compare_shadows(aov, ref.image);
  ASSERT_TRUE(lost.ok());
  EXPECT_GT(lost->all.false_light, 100u);
  EXPECT_EQ(lost->all.false_shadow, 0u);
}

// Alpha cut-outs (glTF MASK): a card at y = 1 whose texture is transparent on its left half
// (u < 0.5) and opaque on its right half; rays straight up from the ground pass through the left
// half only. The base colour's alpha scales the texture's, as in forward.frag.
TEST(RayTracerAlpha, CutOutsLetRaysThroughWhereTheRasteriserDiscards) {
  auto card_scene = [](AlphaMode mode, float factor_alpha) {
    Scene scene;
    TextureData tex;
    tex.name = "half";
    tex.width = 4;
    tex.height = 1;
    tex.rgba8 = {255, 255, 255, 0, 255, 255, 255, 0, 255, 255, 255, 255, 255, 255, 255, 255};
    scene.assets.textures.push_back(tex);
    const ecs::Entity card = add(scene, PrimitiveShape::plane, trs({0, 1, 0}, {2, 1, 2}));
    Material m;
    m.alpha_mode = mode;
    m.alpha_cutoff = 0.5f;
    m.base_color = {1, 1, 1, factor_alpha};
    m.base_color_texture = TextureId{0};
    m.features = derive_material_features(m);
    scene.world.emplace<Material>(card, m);
    return scene;
  };
  ReferenceLight above;
  above.direction = {0, -1, 0};  // shines down: shadow rays go up
  const glm::vec3 up(0, 1, 0);
  {
    const Scene scene = card_scene(AlphaMode::mask, 1.0f);
    const RayTracer tracer = build(scene);
    EXPECT_EQ(tracer.alpha_masked_geometries(), 1u);
    EXPECT_EQ(tracer.hard_visibility({-0.6f, 0, 0.3f}, up, above), 1.0f);  // u = 0.2: cut away
    EXPECT_EQ(tracer.hard_visibility({0.6f, 0, -0.3f}, up, above), 0.0f);  // u = 0.8: opaque
    EXPECT_FALSE(tracer.intersect({-0.6f, 0, 0}, up).has_value());
    EXPECT_TRUE(tracer.intersect({0.6f, 0, 0}, up).has_value());
  }
  {
    const Scene scene = card_scene(AlphaMode::mask, 0.4f);  // 0.4 x 1 < cutoff: the whole card is cut
    const RayTracer tracer = build(scene);
    EXPECT_EQ(tracer.hard_visibility({0.6f, 0, 0}, up, above), 1.0f);
  }
  {
    const Scene scene = card_scene(AlphaMode::opaque, 1.0f);  // opaque material: the texture's alpha is unused
    const RayTracer tracer = build(scene);
    EXPECT_EQ(tracer.alpha_masked_geometries(), 0u);
    EXPECT_EQ(tracer.hard_visibility({-0.6f, 0, 0}, up, above), 0.0f);
  }
  // A blended caster casts where alpha >= alpha_cutoff, as the depth pass draws it (the
  // shadow rule of components/material.h's AlphaMode).
  {
    const Scene scene = card_scene(AlphaMode::blend, 1.0f);
    const RayTracer tracer = build(scene);
    EXPECT_EQ(tracer.alpha_masked_geometries(), 1u);
    EXPECT_EQ(tracer.hard_visibility({-0.6f, 0, 0.3f}, up, above), 1.0f);  // alpha 0: no shadow
    EXPECT_EQ(tracer.hard_visibility({0.6f, 0, -0.3f}, up, above), 0.0f);  // alpha 1: shadow
  }
  {
    const Scene scene = card_scene(AlphaMode::blend, 0.4f);  // 0.4 < 0.5 everywhere
    const RayTracer tracer = build(scene);
    EXPECT_EQ(tracer.hard_visibility({0.6f, 0, 0}, up, above), 1.0f);
  }
}

// Caster faces (caster_face_blocks(), components/shadow_settings.h) ---------------------------

/// A 2 x 2 plane at height `y` whose front face (the primitive's +Y) points `up` or down,
/// single- or double-sided, under `matrix` (after the placement).
Scene plane_scene(float y, bool up, bool double_sided, const glm::mat4& matrix = glm::mat4(1.0f)) {
  Scene scene;
  const glm::mat4 turn =
      up ? glm::mat4(1.0f) : glm::rotate(glm::mat4(1.0f), glm::pi<float>(), glm::vec3(1, 0, 0));
  const ecs::Entity e = add(scene, PrimitiveShape::plane, matrix * trs({0, y, 0}, {2, 1, 2}) * turn);
  Material m;
  m.double_sided = double_sided;
  scene.world.emplace<Material>(e, m);
  return scene;
}

ReferenceLight culled(ReferenceLight light, CullMode cull) {
  light.cull = cull;
  return light;
}

TEST(RayTracerCasterFaces, SingleSidedPlanesBlockWithTheFacesTheCullLeaves) {
  const ReferenceLight sun = directional({0, -1, 0});  // above: shadow rays go up
  const glm::vec3 p(0, 0, 0), n(0, 1, 0);
  for (const bool up : {true, false}) {
    const RayTracer tracer = build(plane_scene(1.0f, up, false));
    // Facing up, the plane's front face faces the sun.
    EXPECT_EQ(tracer.hard_visibility(p, n, culled(sun, CullMode::back)), up ? 0.0f : 1.0f) << up;
    EXPECT_EQ(tracer.hard_visibility(p, n, culled(sun, CullMode::front)), up ? 1.0f : 0.0f) << up;
    EXPECT_EQ(tracer.hard_visibility(p, n, culled(sun, CullMode::none)), 0.0f) << up;
    // The same through the public ray query (a light along the ray) and the image path.
    EXPECT_EQ(tracer.occluded({0, 0.5f, 0}, {0, 1, 0}, 10.0f), up);
    EXPECT_EQ(tracer.occluded({0, 0.5f, 0}, {0, 1, 0}, 10.0f, CullMode::front), !up);
    const Image aov = ground_aov(5, 0.5f);  // every point under the plane
    for (const CullMode cull : {CullMode::back, CullMode::front, CullMode::none}) {
      const ShadowReference ref = reference(tracer, aov, culled(sun, cull));
      const float expected = caster_face_blocks(cull, false, up) ? 0.0f : 1.0f;
      for (int y = 0; y < aov.height; ++y)
        for (int x = 0; x < aov.width; ++x) EXPECT_EQ(ref.image.at(x, y, 0), expected);
    }
  }
}

TEST(RayTracerCasterFaces, DoubleSidedMaterialsBlockWithBothFaces) {
  const ReferenceLight sun = directional({0, -1, 0});
  for (const bool up : {true, false}) {
    const RayTracer tracer = build(plane_scene(1.0f, up, true));
    for (const CullMode cull : {CullMode::back, CullMode::front, CullMode::none})
      EXPECT_EQ(tracer.hard_visibility({0, 0, 0}, {0, 1, 0}, culled(sun, cull)), 0.0f) << up;
  }
}

// A mirroring transform (negative determinant) swaps the faces as in the shadow pass
// (glFrontFace(GL_CW)): the front face is the one its transformed normal points to.
TEST(RayTracerCasterFaces, MirroringTransformsKeepTheFrontFaceOfTheTransformedNormal) {
  const ReferenceLight sun = directional({0, -1, 0});
  const glm::vec3 p(0, 0, 0), n(0, 1, 0);
  // Mirrored in x: the plane's normal still points up, its front face still faces the sun.
  const glm::mat4 mirror_x = glm::scale(glm::mat4(1.0f), glm::vec3(-1, 1, 1));
  ASSERT_TRUE(mirrors(mirror_x));
  EXPECT_EQ(build(plane_scene(1.0f, true, false, mirror_x)).hard_visibility(p, n, sun), 0.0f);
  EXPECT_EQ(build(plane_scene(1.0f, false, false, mirror_x)).hard_visibility(p, n, sun), 1.0f);
  // Mirrored in y about the plane's own height: the same triangles, the winding reversed, so
  // now the face towards the ground is the front one and the sun's side casts nothing.
  const glm::mat4 mirror_y = glm::translate(glm::mat4(1.0f), glm::vec3(0, 2, 0)) *
                             glm::scale(glm::mat4(1.0f), glm::vec3(1, -1, 1));
  EXPECT_EQ(build(plane_scene(1.0f, true, false, mirror_y)).hard_visibility(p, n, sun), 1.0f);
  EXPECT_EQ(build(plane_scene(1.0f, false, false, mirror_y)).hard_visibility(p, n, sun), 0.0f);
}

// Spot and point lights: a face faces the light when the light's position is on its side of
// the plane, whatever way the light points.
TEST(RayTracerCasterFaces, LocalLightsDecideByTheirPosition) {
  for (const LightType type : {LightType::point, LightType::spot}) {
    // Points sideways: by its direction, no face would face it.
    ReferenceLight lamp = positional(type, {0, 4, 0}, {1, 0, 0});
    lamp.outer_cone_deg = 180.0f;
    EXPECT_EQ(build(plane_scene(2.0f, true, false)).hard_visibility({0, 0, 0}, {0, 1, 0}, lamp),
              0.0f);
    EXPECT_EQ(build(plane_scene(2.0f, false, false)).hard_visibility({0, 0, 0}, {0, 1, 0}, lamp),
              1.0f);
    // Off to the side: the ray crosses the plane at a slant, the rule is the same.
    EXPECT_EQ(build(plane_scene(2.0f, true, false)).hard_visibility({0.6f, 0, 0}, {0, 1, 0},
                                                                    positional(type, {-0.6f, 4, 0})),
              0.0f);
  }
}

// A closed mesh blocks whatever the cull, for punctual and area lights: every ray through it
// crosses a face of each orientation (the area reference tests each emitter sample's ray).
TEST(RayTracerCasterFaces, ClosedMeshesBlockUnderEveryCull) {
  Scene scene;
  add(scene, PrimitiveShape::sphere, trs({0, 3, 0}, {2, 2, 2}));
  const RayTracer tracer = build(scene);
  ReferenceLight square = positional(LightType::point, {0, 6, 0});
  square.size = 0.5f;
  ReferenceLight cone = directional({0, -1, 0});
  cone.angular_size_deg = 5.0f;
  for (const CullMode cull : {CullMode::back, CullMode::front, CullMode::none}) {
    EXPECT_EQ(tracer.hard_visibility({0, 0, 0}, {0, 1, 0}, culled(directional({0, -1, 0}), cull)),
              0.0f);
    EXPECT_EQ(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, culled(square, cull), 64, 1),
              0.0f);
    EXPECT_EQ(tracer.area_light_visibility({0, 0, 0}, {0, 1, 0}, culled(cone, cull), 64, 1), 0.0f);
  }
}

// An inverted hull (a sphere with every triangle reversed, the toon outline) around a body: the
// hull's half towards the light faces away from it, so with cull back the body's top is lit and
// the ground below still in the shadow of the body and the hull's lower half.
TEST(RayTracerCasterFaces, InvertedHullLetsTheLightOntoTheBodyInside) {
  Scene scene;
  add(scene, PrimitiveShape::sphere, trs({0, 2, 0}));  // the body, radius 0.5
  MeshData hull = make_primitive(PrimitiveShape::sphere, 32);
  for (std::size_t t = 0; t + 2 < hull.indices.size(); t += 3)
    std::swap(hull.indices[t + 1], hull.indices[t + 2]);
  for (glm::vec3& nrm : hull.normals) nrm = -nrm;
  const MeshId hull_mesh = scene.assets.add_mesh(hull);
  const ecs::Entity e = scene.world.create();
  scene.world.emplace<MeshRenderer>(e, MeshRenderer{hull_mesh, true, true});
  scene.world.emplace<WorldTransform>(e, WorldTransform{trs({0, 2, 0}, glm::vec3(1.1f))});
  const RayTracer tracer = build(scene);
  const ReferenceLight sun = directional({0, -1, 0});
  const glm::vec3 body_top(0, 2.5f, 0), ground(0, 0, 0), n(0, 1, 0);
  EXPECT_EQ(tracer.hard_visibility(body_top, n, sun), 1.0f);
  EXPECT_EQ(tracer.hard_visibility(ground, n, sun), 0.0f);
  EXPECT_EQ(tracer.hard_visibility(body_top, n, culled(sun, CullMode::front)), 0.0f);
  EXPECT_EQ(tracer.hard_visibility(body_top, n, culled(sun, CullMode::none)), 0.0f);
}

// Alpha-masked single-sided geometry: both filters apply (a face the cull leaves out never
// blocks; a kept face still lets rays through its cut-out).
TEST(RayTracerCasterFaces, CutOutsAndFacesTogether) {
  Scene scene = plane_scene(1.0f, true, false);
  TextureData tex;
  tex.width = 2;
  tex.height = 1;
  tex.rgba8 = {255, 255, 255, 0, 255, 255, 255, 255};  // u < 0.5 cut away
  scene.assets.textures.push_back(tex);
  scene.world.view<Material>().each([](ecs::Entity, Material& m) {
    m.alpha_mode = AlphaMode::mask;
    m.base_color_texture = TextureId{0};
    m.features = derive_material_features(m);
  });
  const RayTracer tracer = build(scene);
  EXPECT_EQ(tracer.alpha_masked_geometries(), 1u);
  const ReferenceLight sun = directional({0, -1, 0});
  EXPECT_EQ(tracer.hard_visibility({-0.6f, 0, 0}, {0, 1, 0}, sun), 1.0f);  // cut away
  EXPECT_EQ(tracer.hard_visibility({0.6f, 0, 0}, {0, 1, 0}, sun), 0.0f);   // opaque, front
  EXPECT_EQ(tracer.hard_visibility({0.6f, 0, 0}, {0, 1, 0}, culled(sun, CullMode::front)), 1.0f);
}

TEST(RayTracerCasterFaces, ReferenceLightTakesTheLightsCull) {
  Scene scene;
  const ecs::Entity sun = scene.world.create();
  scene.world.emplace<Light>(sun, Light{});
  scene.world.emplace<WorldTransform>(sun, WorldTransform{});
  EXPECT_EQ(reference_light(scene.world, sun).cull, ShadowSettings{}.cull);
  ShadowSettings s;
  s.cull = CullMode::front;
  scene.world.emplace<ShadowSettings>(sun, s);
  EXPECT_EQ(reference_light(scene.world, sun).cull, CullMode::front);
}

}  // namespace
}  // namespace kaskad::reference
