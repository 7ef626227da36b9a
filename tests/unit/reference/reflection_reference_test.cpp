// The reflection reference on primitive scenes: a mirror ray that hits a lit diffuse wall gives
// the glTF BRDF's value (Appendix B) computed here by hand; shadowed, unshadowed and non-receiving cases;
// a miss gives the environment cube (or the clear colour); the per-pixel image and its metric.
#include "runtime/reference/reflection_reference.h"

#include <gtest/gtest.h>

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "components/ibl.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "runtime/assets/primitives.h"

namespace kaskad::reference {
namespace {

/// The mirror sits at the origin, facing +Y; the eye at (-1, 1, 0), so U = (1, -1, 0) / sqrt(2)
/// and the mirror ray R = (1, 1, 0) / sqrt(2) meets the wall x = 3 at (3, 3, 0).
const glm::vec3 kEye(-1.0f, 1.0f, 0.0f);
const glm::vec3 kMirror(0.0f);
const glm::vec3 kMirrorNormal(0.0f, 1.0f, 0.0f);
const glm::vec3 kWallHit(3.0f, 3.0f, 0.0f);

struct WallScene {
  Scene scene;
  ecs::Entity wall;
  ecs::Entity blocker;
};

/// A 10 x 10 wall in the plane x = 3 facing -X, optionally with a box between the wall point
/// (3, 3, 0) and a light shining along +X (it does not cut the mirror ray).
WallScene wall_scene(bool with_blocker, const Material& wall_material) {
  WallScene w;
  const MeshId plane = w.scene.assets.add_mesh(make_primitive(PrimitiveShape::plane, 4));
  w.wall = w.scene.world.create();
  w.scene.world.emplace<MeshRenderer>(w.wall, MeshRenderer{plane, true, true});
  // Plane faces +Y; a +90 degree turn about Z takes +Y to -X.
  const glm::mat4 m = glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(3, 0, 0)),
                                             glm::radians(90.0f), glm::vec3(0, 0, 1)),
                                 glm::vec3(10.0f));
  w.scene.world.emplace<WorldTransform>(w.wall, WorldTransform{m});
  w.scene.world.emplace<Material>(w.wall, wall_material);
  if (with_blocker) {
    const MeshId box = w.scene.assets.add_mesh(make_primitive(PrimitiveShape::box, 4));
    w.blocker = w.scene.world.create();
    w.scene.world.emplace<MeshRenderer>(w.blocker, MeshRenderer{box, true, true});
    w.scene.world.emplace<WorldTransform>(
        w.blocker, WorldTransform{glm::translate(glm::mat4(1.0f), glm::vec3(1.5f, 3.0f, 0.0f))});
  }
  return w;
}

RayTracer build(const Scene& scene) {
  auto tracer = RayTracer::build(scene);
  if (!tracer.ok()) ADD_FAILURE() << tracer.error().to_string();
  return std::move(tracer).value();
}

Material wall_material() {
  Material m;
  m.base_color = glm::vec4(0.8f, 0.4f, 0.2f, 1.0f);
  m.metallic = 0.0f;
  m.roughness = 1.0f;  // alpha = 1: D = 1 / pi, V = 0.5 / (N.L + N.V)
  return m;
}

ReflectionScene lit_by(const Scene& scene, ShadingLight light) {
  ReflectionScene rs;
  rs.world = &scene.world;
  rs.ambient = glm::vec3(0.1f, 0.2f, 0.3f);
  rs.clear_color = glm::vec3(0.25f, 0.5f, 0.75f);
  rs.lights = {light};
  return rs;
}

ShadingLight sun_along_x(bool shadowed) {
  ShadingLight l;
  l.type = LightType::directional;
  l.direction = glm::vec3(1, 0, 0);
  l.color = glm::vec3(2.0f, 1.5f, 1.0f);
  l.shadowed = shadowed;
  return l;
}

/// forward.frag's value at the wall point by hand: n = (-1, 0, 0), l = (-1, 0, 0) (N.L = 1),
/// v = (-1, -1, 0) / sqrt(2) towards the mirror (N.V = sqrt(1/2)); roughness 1 (alpha 1):
/// D = 1 / pi, V = 0.5 / (N.L + N.V); f0 0.04, F = f0 + (1 - f0)(1 - V.H)^5; the diffuse part
/// (1 - F) c / pi. `radiance` is the light's colour (an illuminance). The ambient reaches the
/// BRDF through the split sum.
glm::vec3 expected_wall(const glm::vec3& ambient, const glm::vec3& radiance, float light_factor) {
  const glm::vec3 diffuse(0.8f, 0.4f, 0.2f);
  const float pi = 3.14159265f;
  const float s = std::sqrt(0.5f);
  const glm::vec3 h = glm::normalize(glm::vec3(-1.0f - s, -s, 0.0f));
  const float v_dot_h = glm::dot(glm::vec3(-s, -s, 0.0f), h);
  const float fresnel = 0.04f + 0.96f * std::pow(1.0f - v_dot_h, 5.0f);
  const float spec = fresnel * (1.0f / pi) * (0.5f / (1.0f + s));
  const glm::vec3 brdf = (1.0f - fresnel) * diffuse / pi + glm::vec3(spec);
  // The uniform ambient through the split sum (components/ibl.h), written out: roughness 1
  // makes the roughness-dependent Fresnel f0 itself.
  const glm::vec2 ab = dfg_lookup(s, 1.0f);
  const float fss_ess = 0.04f * ab.x + ab.y;
  const float ems = 1.0f - ab.x - ab.y;
  const float f_avg = 0.04f + 0.96f / 21.0f;
  const float fms_ems = ems * fss_ess * f_avg / (1.0f - f_avg * ems);
  const glm::vec3 ambient_reflected =
      ambient * (glm::vec3(fss_ess + fms_ems) + diffuse * (1.0f - fss_ess - fms_ems));
  return ambient_reflected + brdf * radiance * light_factor;
}

void expect_near(const glm::vec3& a, const glm::vec3& b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

TEST(ReflectionReference, MirrorRayOntoLitWallGivesTheGltfBrdf) {
  WallScene w = wall_scene(false, wall_material());
  const RayTracer tracer = build(w.scene);
  const ReflectionScene rs = lit_by(w.scene, sun_along_x(true));
  bool hit = false;
  const glm::vec3 c = reflected_radiance(tracer, rs, kMirror, kMirrorNormal, kEye, &hit);
  EXPECT_TRUE(hit);
  expect_near(c, expected_wall(rs.ambient, glm::vec3(2.0f, 1.5f, 1.0f), 1.0f));
  // The mirror's normal may face either way: the eye's side is used.
  expect_near(reflected_radiance(tracer, rs, kMirror, -kMirrorNormal, kEye), c);
  // Emission adds to it, as forward.frag's u_emissive.
  Material glowing = wall_material();
  glowing.emissive = glm::vec3(0.5f, 0.0f, 0.25f);
  w.scene.world.get<Material>(w.wall) = glowing;
  expect_near(reflected_radiance(tracer, rs, kMirror, kMirrorNormal, kEye), c + glowing.emissive);
}

TEST(ReflectionReference, HitsAreShadowedByShadowRays) {
  WallScene w = wall_scene(true, wall_material());
  const RayTracer tracer = build(w.scene);
  const glm::vec3 lit =
      expected_wall(glm::vec3(0.1f, 0.2f, 0.3f), glm::vec3(2.0f, 1.5f, 1.0f), 1.0f);
  const glm::vec3 dark =
      expected_wall(glm::vec3(0.1f, 0.2f, 0.3f), glm::vec3(2.0f, 1.5f, 1.0f), 0.0f);
  std::uint64_t rays = 0;
  bool hit = false;
  const ReflectionScene shadowed = lit_by(w.scene, sun_along_x(true));
  expect_near(reflected_radiance(tracer, shadowed, kMirror, kMirrorNormal, kEye, &hit, &rays),
              dark);
  EXPECT_TRUE(hit);
  EXPECT_EQ(rays, 2u);  // the mirror ray and one shadow ray
  // A light without cast_shadows is never blocked; neither is a surface that receives none.
  expect_near(
      reflected_radiance(tracer, lit_by(w.scene, sun_along_x(false)), kMirror, kMirrorNormal, kEye),
      lit);
  w.scene.world.get<MeshRenderer>(w.wall).receive_shadows = false;
  expect_near(reflected_radiance(tracer, shadowed, kMirror, kMirrorNormal, kEye), lit);
}

TEST(ReflectionReference, PointAndSpotLightsAttenuateAsTheForwardPass) {
  WallScene w = wall_scene(false, wall_material());
  const RayTracer tracer = build(w.scene);
  ShadingLight point;
  point.type = LightType::point;
  point.position = glm::vec3(1.0f, 3.0f, 0.0f);  // 2 m in front of the wall point: 1 / d^2 = 1/4
  point.color = glm::vec3(4.0f);
  ReflectionScene rs = lit_by(w.scene, point);
  expect_near(reflected_radiance(tracer, rs, kMirror, kMirrorNormal, kEye),
              expected_wall(rs.ambient, glm::vec3(4.0f), 0.25f));
  // KHR range window: (1 - (d^2 / range^2)^2) with d = 2, range = 4: 1 - 1/16.
  rs.lights[0].range = 4.0f;
  expect_near(reflected_radiance(tracer, rs, kMirror, kMirrorNormal, kEye),
              expected_wall(rs.ambient, glm::vec3(4.0f), 0.25f * (1.0f - 1.0f / 16.0f)));
  // A spot pointing away from the wall point lights nothing; pointing at it, fully.
  rs.lights[0].range = 0.0f;
  rs.lights[0].type = LightType::spot;
  rs.lights[0].cos_inner = std::cos(glm::radians(10.0f));
  rs.lights[0].cos_outer = std::cos(glm::radians(20.0f));
  rs.lights[0].direction = glm::vec3(-1, 0, 0);
  expect_near(reflected_radiance(tracer, rs, kMirror, kMirrorNormal, kEye),
              expected_wall(rs.ambient, glm::vec3(4.0f), 0.0f));
  rs.lights[0].direction = glm::vec3(1, 0, 0);
  expect_near(reflected_radiance(tracer, rs, kMirror, kMirrorNormal, kEye),
              expected_wall(rs.ambient, glm::vec3(4.0f), 0.25f));
}

TEST(ReflectionReference, MissReturnsTheEnvironmentOrTheClearColour) {
  WallScene w = wall_scene(false, wall_material());
  const RayTracer tracer = build(w.scene);
  ReflectionScene rs = lit_by(w.scene, sun_along_x(true));
  // Looking straight down at a mirror facing up: R = +Y, nothing above.
  const glm::vec3 eye_above(0.0f, 2.0f, 0.0f);
  bool hit = true;
  expect_near(reflected_radiance(tracer, rs, kMirror, kMirrorNormal, eye_above, &hit),
              rs.clear_color);
  EXPECT_FALSE(hit);
  // With a coloured-cube environment: the +Y face's colour.
  const CubeMap cube = make_cube_map(4, [](const glm::vec3& d) {
    return std::abs(d.y) > std::max(std::abs(d.x), std::abs(d.z))
               ? (d.y > 0 ? glm::vec4(0, 1, 0, 1) : glm::vec4(1, 0, 1, 1))
               : glm::vec4(0.5f, 0.5f, 0.5f, 1);
  });
  rs.environment = &cube;
  expect_near(reflected_radiance(tracer, rs, kMirror, kMirrorNormal, eye_above),
              glm::vec3(0, 1, 0));
  // An oblique miss samples the cube along R: eye at (1, 1, 0) reflects towards (-1, 1, 0),
  // away from the wall; the cube's value along that direction.
  expect_near(reflected_radiance(tracer, rs, kMirror, kMirrorNormal, glm::vec3(1, 1, 0)),
              glm::vec3(sample_cube(cube, glm::vec3(-1, 1, 0))));
}

/// A 3 x 1 AOV: pixel 0 is the mirror seen from kEye (hits the wall), pixel 1 a mirror looked
/// at from straight above (a miss), pixel 2 background.
Image three_pixel_aov() {
  Image aov;
  aov.width = 3;
  aov.height = 1;
  aov.channel_names = {"P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z", "Z", "visibility", "mask"};
  aov.channels = 9;
  aov.pixels.assign(27, 0.0f);
  for (int x = 0; x < 2; ++x) {
    aov.at(x, 0, 4) = 1.0f;  // N = +Y
    aov.at(x, 0, 8) = 1.0f;  // mask
  }
  aov.at(1, 0, 0) = -1.0f;  // pixel 1 at (-1, 0, 0): kEye is straight above it
  return aov;
}

TEST(ReflectionReference, ImageAndMetric) {
  WallScene w = wall_scene(false, wall_material());
  const RayTracer tracer = build(w.scene);
  const ReflectionScene rs = lit_by(w.scene, sun_along_x(false));
  const glm::vec3 eye =
      kEye;  // sees pixel 0 at (0,0,0) obliquely (R hits the wall), pixel 1 from above
  auto ref = reflection_reference(tracer, three_pixel_aov(), rs, eye, 2);
  ASSERT_TRUE(ref.ok()) << ref.error().to_string();
  const Image& img = ref->image;
  ASSERT_EQ(img.channels, 5);
  EXPECT_EQ(img.channel_names[0], "reflection.R");
  EXPECT_EQ(img.at(0, 0, 3), 1.0f);  // hit
  EXPECT_EQ(img.at(1, 0, 3), 0.0f);  // miss
  EXPECT_EQ(img.at(2, 0, 4), 0.0f);  // background: not evaluated
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(img.at(0, 0, c),
              reflected_radiance(tracer, rs, glm::vec3(0.0f), kMirrorNormal, eye)[c]);
    EXPECT_EQ(img.at(1, 0, c), rs.clear_color[c]);
  }
  EXPECT_EQ(ref->rays, 2u);

  // The metric: an engine image equal to the reference scores 0; 0.3 off in one channel of one
  // of the two compared pixels gives mean |e| = 0.3 / 6 and RMSE = sqrt(0.09 / 6).
  Image method = img;
  auto same = compare_reflections(method, img);
  ASSERT_TRUE(same.ok()) << same.error().to_string();
  EXPECT_EQ(same->pixels, 2u);
  EXPECT_EQ(same->rmse, 0.0);
  method.at(1, 0, 1) += 0.3f;
  auto off = compare_reflections(method, img);
  ASSERT_TRUE(off.ok());
  EXPECT_NEAR(off->mean_abs_error, 0.3 / 6, 1e-6);
  EXPECT_NEAR(off->rmse, std::sqrt(0.09 / 6), 1e-6);
  EXPECT_NEAR(off->max_abs_error, 0.3, 1e-6);
  // A "reflector" channel limits the pixels to reflective ones.
  // (The pixels are re-laid out with the old channel count before the new channel is declared.)
  std::vector<float> px;
  for (int x = 0; x < 3; ++x) {
    for (int c = 0; c < method.channels; ++c) px.push_back(method.at(x, 0, c));
    px.push_back(x == 0 ? 1.0f : 0.0f);
  }
  method.channel_names.push_back("reflector");
  method.channels += 1;
  method.pixels = px;
  auto reflective = compare_reflections(method, img);
  ASSERT_TRUE(reflective.ok());
  EXPECT_EQ(reflective->pixels, 1u);
  EXPECT_EQ(reflective->rmse, 0.0);
  // Errors name the problem.
  Image bare = img;
  bare.channel_names[1] = "G";
  auto missing = compare_reflections(bare, img);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("reflection.G"), std::string::npos);
  Image aov_without_normal = three_pixel_aov();
  aov_without_normal.channel_names[3] = "X";
  auto bad = reflection_reference(tracer, aov_without_normal, rs, eye);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("N.X"), std::string::npos);
}

TEST(ReflectionReference, SampleTextureIsGlLinearRepeat) {
  TextureData t;
  t.width = 2;
  t.height = 2;
  t.srgb = false;
  // Row 0: red, green; row 1: blue, white.
  t.rgba8 = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255};
  auto near4 = [](glm::vec4 a, glm::vec4 b) { return glm::length(a - b) < 1e-5f; };
  EXPECT_TRUE(near4(sample_texture(t, {0.25f, 0.25f}), {1, 0, 0, 1}));  // texel centres
  EXPECT_TRUE(near4(sample_texture(t, {0.75f, 0.25f}), {0, 1, 0, 1}));
  EXPECT_TRUE(near4(sample_texture(t, {0.25f, 0.75f}), {0, 0, 1, 1}));
  EXPECT_TRUE(near4(sample_texture(t, {1.75f, -0.25f}), {1, 1, 1, 1}));  // repeat
  // The corner (0, 0) lies between all four texels (wrapping): their mean.
  EXPECT_TRUE(near4(sample_texture(t, {0.0f, 0.0f}), {0.5f, 0.5f, 0.5f, 1.0f}));
  EXPECT_TRUE(near4(sample_texture(t, {0.5f, 0.25f}), {0.5f, 0.5f, 0, 1}));
  // sRGB texels are decoded before filtering: 128 -> ((128/255 + 0.055) / 1.055)^2.4.
  TextureData s;
  s.width = s.height = 1;
  s.rgba8 = {128, 0, 255, 128};
  const glm::vec4 d = sample_texture(s, {0.3f, 0.6f});
  EXPECT_NEAR(d.r, std::pow((128.0f / 255.0f + 0.055f) / 1.055f, 2.4f), 1e-6f);
  EXPECT_EQ(d.g, 0.0f);
  EXPECT_EQ(d.b, 1.0f);
  EXPECT_NEAR(d.a, 128.0f / 255.0f, 1e-6f);  // alpha is linear
  EXPECT_EQ(sample_texture(TextureData{}, {0.5f, 0.5f}), glm::vec4(1.0f));
}

TEST(ReflectionReference, HitsCarryTheirMeshTriangleAndBarycentrics) {
  WallScene w = wall_scene(false, wall_material());
  // A mesh whose first triangle has a non-finite vertex: Embree never sees it, and the hit
  // triangle must still index the mesh (not Embree's primitive list).
  MeshData mesh = make_primitive(PrimitiveShape::plane, 4);
  mesh.positions.push_back(glm::vec3(NAN));
  const std::uint32_t bad = std::uint32_t(mesh.positions.size() - 1);
  mesh.indices.insert(mesh.indices.begin(), {bad, bad, bad});
  mesh.normals.push_back(glm::vec3(0, 1, 0));
  mesh.uvs.push_back(glm::vec2(0));
  w.scene.world.get<MeshRenderer>(w.wall).mesh = w.scene.assets.add_mesh(mesh);
  const RayTracer tracer = build(w.scene);
  const auto hit = tracer.intersect(kMirror, glm::vec3(1, 1, 0));
  ASSERT_TRUE(hit.has_value());
  ASSERT_GE(hit->triangle, 1u);  // triangle 0 was dropped
  ASSERT_LT(3 * hit->triangle + 2, mesh.indices.size());
  const glm::mat4& m = w.scene.world.get<WorldTransform>(w.wall).matrix;
  std::array<glm::vec3, 3> p;
  for (std::size_t k = 0; k < 3; ++k)
    p[k] = glm::vec3(m * glm::vec4(mesh.positions[mesh.indices[3 * hit->triangle + k]], 1.0f));
  const glm::vec2 b = hit->barycentric;
  expect_near((1 - b.x - b.y) * p[0] + b.x * p[1] + b.y * p[2], hit->position, 1e-4f);
  expect_near(hit->position, kWallHit, 1e-4f);
}

TEST(ReflectionReference, HitsShowTheBaseColourTexture) {
  // The wall's uv at (3, 3, 0): plane-local (0.3, 0, 0) -> uv (0.8, 0.5). A 4 x 4 texture whose
  // right half is one colour: columns 2 and 3 are read there.
  Material textured = wall_material();
  WallScene w = wall_scene(false, textured);
  TextureData t;
  t.width = t.height = 4;
  t.srgb = false;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      const std::array<std::uint8_t, 4> c = x < 2 ? std::array<std::uint8_t, 4>{0, 0, 0, 255}
                                                  : std::array<std::uint8_t, 4>{255, 128, 51, 255};
      t.rgba8.insert(t.rgba8.end(), c.begin(), c.end());
    }
  textured.base_color_texture = w.scene.assets.add_texture(t);
  w.scene.world.get<Material>(w.wall) = textured;
  const RayTracer tracer = build(w.scene);
  ReflectionScene rs = lit_by(w.scene, sun_along_x(false));
  rs.assets = &w.scene.assets;
  const auto hit = tracer.intersect(kMirror, glm::vec3(1, 1, 0));
  ASSERT_TRUE(hit.has_value());
  const glm::vec4 texel(1.0f, 128.0f / 255.0f, 51.0f / 255.0f, 1.0f);
  const glm::vec4 base = hit_base_color(rs, textured, *hit);
  EXPECT_LT(glm::length(base - textured.base_color * texel), 1e-5f);
  // Shaded with that colour.
  Material expected_material = textured;
  expected_material.base_color = textured.base_color * texel;
  const glm::vec3 v = glm::normalize(kMirror - hit->position);
  expect_near(reflected_radiance(tracer, rs, kMirror, kMirrorNormal, kEye),
              shade_point(tracer, rs, expected_material, hit->position, hit->normal, v, true));
  // Without assets, the factor alone.
  rs.assets = nullptr;
  EXPECT_EQ(hit_base_color(rs, textured, *hit), textured.base_color);
}

TEST(ReflectionReference, SceneLightsAsTheFrameBuildsThem) {
  Scene scene;
  const ecs::Entity e = scene.world.create();
  Light light;
  light.type = LightType::spot;
  light.color = glm::vec3(1.0f, 0.5f, 0.25f);
  light.intensity = 4.0f;
  light.inner_cone_deg = 10.0f;
  light.outer_cone_deg = 30.0f;
  light.cast_shadows = true;
  scene.world.emplace<Light>(e, light);
  // Rotated -90 degrees about X: local -Z points down.
  scene.world.emplace<WorldTransform>(
      e, WorldTransform{glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(1, 5, 2)),
                                    glm::radians(-90.0f), glm::vec3(1, 0, 0))});
  scene.render.ambient = glm::vec3(0.3f);
  const ReflectionScene rs = reflection_scene(scene);
  ASSERT_EQ(rs.lights.size(), 1u);
  expect_near(rs.lights[0].color, glm::vec3(4.0f, 2.0f, 1.0f));
  expect_near(rs.lights[0].direction, glm::vec3(0, -1, 0));
  expect_near(rs.lights[0].position, glm::vec3(1, 5, 2));
  EXPECT_NEAR(rs.lights[0].cos_outer, std::cos(glm::radians(30.0f)), 1e-6f);
  EXPECT_TRUE(rs.lights[0].shadowed);
  EXPECT_EQ(rs.ambient, glm::vec3(0.3f));
  EXPECT_EQ(rs.world, &scene.world);
}

}  // namespace
}  // namespace kaskad::reference
