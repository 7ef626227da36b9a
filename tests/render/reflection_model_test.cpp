// The reflection reference shades mirror-ray hits with "the same material model as the forward
// pass". Checked here against the rasteriser itself: the default scene is rendered headless and
// every pixel's colour is recomputed on the CPU with reference::shade_point() from the pixel's
// AOV position and normal, the entity's Material and the engine's own shadow visibility; the
// sRGB results must agree to within 8-bit rounding.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "components/material.h"
#include "components/name.h"
#include "runtime/assets/image_io.h"
#include "runtime/app/player.h"
#include "runtime/gpu/context.h"
#include "runtime/reference/reflection_reference.h"

namespace kaskad {
namespace {

float srgb_encode(float linear) {
  const float c = std::clamp(linear, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

class ForwardModelTest : public ::testing::Test {
 protected:
  void SetUp() override { gpu::reset_debug_error_count(); }
  void TearDown() override { EXPECT_EQ(gpu::debug_error_count(), 0) << "GL errors were logged"; }
};

TEST_F(ForwardModelTest, ShadePointReproducesTheForwardPass) {
  gpu::ContextOptions opt;
  opt.headless = true;
  render::RendererOptions ro;
  ro.shader_cache_dir = std::filesystem::path(KASKAD_TEST_TMP) / "shader_cache";
  auto player = Player::create(opt, ro);
  ASSERT_TRUE(player.ok()) << player.error().to_string();
  auto scene = load_scene(content_dir() / "scenes" / "default.json",
                          {"render.width=320", "render.height=180"});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  RenderRun run;
  auto frame = render_frames(*player, *scene, run);
  ASSERT_TRUE(frame.ok()) << frame.error().to_string();
  const Image aov = player->renderer->read_aovs();
  const Image color = player->renderer->read_color();
  ASSERT_EQ(aov.width, color.width);
  const glm::vec3 eye = frame->last.camera.position;

  auto tracer = reference::RayTracer::build(*scene);
  ASSERT_TRUE(tracer.ok()) << tracer.error().to_string();
  // forward.frag: colour = ambient term + visibility * (the shadowed light's term) for the one
  // (shadowed) light of the default scene. Evaluate shade_point without shadow rays, with the
  // light and without, and blend with the engine's visibility AOV.
  reference::ReflectionScene lit = reference::reflection_scene(*scene);
  ASSERT_EQ(lit.lights.size(), 1u);
  lit.lights[0].shadowed = false;
  reference::ReflectionScene unlit = lit;
  unlit.lights.clear();
  const float exposure = scene->render.exposure;

  // Fraction of the pixels whose recomputed sRGB colour is within 1.5/255 of the engine's, with
  // each Material passed through `tweak` first.
  struct Agreement {
    int compared = 0, agree = 0;
    float worst = 0.0f;
  };
  auto agreement = [&](auto tweak) {
    Agreement a;
    for (int y = 0; y < aov.height; ++y) {
      for (int x = 0; x < aov.width; ++x) {
        if (aov.at(x, y, 8) < 0.5f) continue;
        const glm::vec3 p(aov.at(x, y, 0), aov.at(x, y, 1), aov.at(x, y, 2));
        const glm::vec3 n =
            glm::normalize(glm::vec3(aov.at(x, y, 3), aov.at(x, y, 4), aov.at(x, y, 5)));
        // Which entity the pixel shows: the first surface along the eye ray, if it is this point.
        const auto hit = tracer->intersect(eye, p - eye);
        if (!hit || glm::length(hit->position - p) > 1e-3f * glm::length(p - eye)) continue;
        const Material* m = scene->world.try_get<Material>(hit->entity);
        Material material = tweak(m ? *m : Material{});
        material.base_color = reference::hit_base_color(lit, material, *hit);
        const glm::vec3 v = glm::normalize(eye - p);
        const glm::vec3 with_light = reference::shade_point(*tracer, lit, material, p, n, v, false);
        const glm::vec3 ambient = reference::shade_point(*tracer, unlit, material, p, n, v, false);
        const float visibility = aov.at(x, y, 7);
        const glm::vec3 expected = (ambient + visibility * (with_light - ambient)) * exposure;
        float diff = 0.0f;
        for (int c = 0; c < 3; ++c)
          diff = std::max(diff, std::abs(srgb_encode(expected[c]) - color.at(x, y, c)));
        a.worst = std::max(a.worst, diff);
        ++a.compared;
        a.agree += diff <= 1.5f / 255.0f;
      }
    }
    return a;
  };
  const Agreement same = agreement([](Material m) { return m; });
  std::printf("compared %d pixels: %.3f%% within 1.5/255, worst %.4f\n", same.compared,
              100.0 * same.agree / std::max(same.compared, 1), double(same.worst));
  EXPECT_GT(same.compared, aov.width * aov.height / 2);
  EXPECT_GE(same.agree, same.compared * 995 / 1000);

  // The check can fail: a base colour 3% off, or a much shinier surface, is caught.
  const Agreement darker = agreement([](Material m) {
    m.base_color *= glm::vec4(0.97f, 0.97f, 0.97f, 1.0f);
    return m;
  });
  const Agreement shinier = agreement([](Material m) {
    m.roughness *= 0.5f;
    return m;
  });
  std::printf("base colour x 0.97: %.3f%%, roughness x 0.5: %.3f%% within 1.5/255\n",
              100.0 * darker.agree / std::max(darker.compared, 1),
              100.0 * shinier.agree / std::max(shinier.compared, 1));
  EXPECT_LT(darker.agree, darker.compared / 2);
  EXPECT_LT(shinier.agree, shinier.compared / 2);
}

TEST_F(ForwardModelTest, BaseColourTexturesMatchTheForwardPass) {
  // The checker box of the materials scene (base colour texture, no normal map), moved close to
  // the camera: the CPU texture lookup (top mip level, bilinear) against GL's trilinear
  // sampling, seen large enough that the top mip level is what GL reads too.
  gpu::ContextOptions opt;
  opt.headless = true;
  render::RendererOptions ro;
  ro.shader_cache_dir = std::filesystem::path(KASKAD_TEST_TMP) / "shader_cache";
  auto player = Player::create(opt, ro);
  ASSERT_TRUE(player.ok()) << player.error().to_string();
  auto scene = load_scene(
      content_dir() / "scenes" / "materials.json",
      {"render.width=640", "render.height=360", "checker_box.transform.translation=[0, 2.8, 5.6]"});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  RenderRun run;
  auto frame = render_frames(*player, *scene, run);
  ASSERT_TRUE(frame.ok()) << frame.error().to_string();
  const Image aov = player->renderer->read_aovs();
  const Image color = player->renderer->read_color();
  const glm::vec3 eye = frame->last.camera.position;
  auto tracer = reference::RayTracer::build(*scene);
  ASSERT_TRUE(tracer.ok()) << tracer.error().to_string();
  reference::ReflectionScene lit = reference::reflection_scene(*scene);
  ASSERT_EQ(lit.lights.size(), 1u);
  lit.lights[0].shadowed = false;
  reference::ReflectionScene unlit = lit;
  unlit.lights.clear();
  ecs::Entity box = ecs::kNullEntity;
  scene->world.view<Name>().each([&](ecs::Entity e, const Name& name) {
    if (name.value == "checker_box") box = e;
  });
  ASSERT_TRUE(box.valid());
  const Material& material = scene->world.get<Material>(box);
  ASSERT_NE(material.base_color_texture, kNoTexture);
  ASSERT_EQ(material.normal_texture, kNoTexture);

  auto agreement = [&](bool textured, int& compared) {
    int agree = 0;
    compared = 0;
    for (int y = 0; y < aov.height; ++y)
      for (int x = 0; x < aov.width; ++x) {
        if (aov.at(x, y, 8) < 0.5f) continue;
        const glm::vec3 p(aov.at(x, y, 0), aov.at(x, y, 1), aov.at(x, y, 2));
        const glm::vec3 n =
            glm::normalize(glm::vec3(aov.at(x, y, 3), aov.at(x, y, 4), aov.at(x, y, 5)));
        const auto hit = tracer->intersect(eye, p - eye);
        if (!hit || hit->entity != box ||
            glm::length(hit->position - p) > 1e-3f * glm::length(p - eye))
          continue;
        // Checker edges: a sub-texel difference in uv changes the colour a lot there; compare
        // where the engine's colour is locally smooth.
        bool edge = x == 0 || y == 0 || x + 1 == aov.width || y + 1 == aov.height;
        for (int c = 0; c < 3 && !edge; ++c) {
          const float v0 = color.at(x, y, c);
          edge = std::abs(color.at(x + 1, y, c) - v0) > 0.04f ||
                 std::abs(color.at(x - 1, y, c) - v0) > 0.04f ||
                 std::abs(color.at(x, y + 1, c) - v0) > 0.04f ||
                 std::abs(color.at(x, y - 1, c) - v0) > 0.04f;
        }
        if (edge) continue;
        Material m = material;
        if (textured) m.base_color = reference::hit_base_color(lit, material, *hit);
        const glm::vec3 v = glm::normalize(eye - p);
        const glm::vec3 with_light = reference::shade_point(*tracer, lit, m, p, n, v, false);
        const glm::vec3 ambient = reference::shade_point(*tracer, unlit, m, p, n, v, false);
        const glm::vec3 expected =
            (ambient + aov.at(x, y, 7) * (with_light - ambient)) * scene->render.exposure;
        float diff = 0.0f;
        for (int c = 0; c < 3; ++c)
          diff = std::max(diff, std::abs(srgb_encode(expected[c]) - color.at(x, y, c)));
        ++compared;
        agree += diff <= 3.0f / 255.0f;
      }
    return agree;
  };
  int compared = 0;
  const int agree = agreement(true, compared);
  int compared_plain = 0;
  const int agree_plain = agreement(false, compared_plain);
  std::printf("checker box: %d pixels, %.3f%% within 3/255 (%.3f%% without the texture)\n",
              compared, 100.0 * agree / std::max(compared, 1),
              100.0 * agree_plain / std::max(compared_plain, 1));
  EXPECT_GT(compared, 5000);
  EXPECT_GE(agree, compared * 95 / 100);
  EXPECT_LT(agree_plain, compared_plain / 2);
}

}  // namespace
}  // namespace kaskad
