// The glTF material inputs on the GPU, through material files (the same features glTF imports
// get): a card filling the view, no lights, so its colour is ambient * base * occlusion +
// emissive, compared with that value computed here (sRGB encoded, within 8-bit rounding):
// the occlusion texture at two strengths, the emissive texture times the emissive factor, a
// texture transform (uv_offset 0.5 swaps the halves of a two-texel texture), and under a light
// the metallic-roughness texture against the CPU BRDF.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "components/brdf.h"
#include "components/ibl.h"
#include "runtime/assets/image_io.h"
#include "tests/render/player_fixture.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

class MaterialInputsTest : public PlayerTest {
 protected:
  static fs::path dir() { return test_dir("material_inputs"); }
  /// A texture of `width` x 1 texels of the given RGB values (as stored, 8-bit), written as PNG;
  /// returns the values as read back (what the renderer gets).
  static std::vector<glm::vec3> texture(const std::string& name, std::vector<glm::vec3> texels) {
    Image image;
    image.width = int(texels.size());
    image.height = 1;
    image.channels = 4;
    for (const glm::vec3& t : texels)
      for (float v : {t.r, t.g, t.b, 1.0f}) image.pixels.push_back(v);
    EXPECT_TRUE(save_image(dir() / name, image).ok());
    auto back = load_image(dir() / name);
    EXPECT_TRUE(back.ok());
    for (std::size_t i = 0; back.ok() && i < texels.size(); ++i)
      for (int c = 0; c < 3; ++c)
        texels[i][c] = back->pixels[i * std::size_t(back->channels) + std::size_t(c)];
    return texels;
  }
  /// The card scene with material file `material` (JSON text) and ambient `ambient`.
  static fs::path scene(const std::string& name, const std::string& material, float ambient) {
    std::ofstream(dir() / (name + "_material.json")) << material;
    const fs::path file = dir() / (name + ".json");
    std::ofstream(file) << R"({ "kaskad_scene": 1,
      "render": { "ambient": [)"
                        << ambient << ", " << ambient << ", " << ambient
                        << R"(], "ground": "none", "clear_color": [0, 0, 0] },
      "entities": [
        { "name": "card", "transform": { "euler_deg": [90, 0, 0] },
          "primitive": { "shape": "plane" },
          "material": { "file": ")"
                        << name << R"(_material.json" } },
        { "name": "camera", "transform": { "translation": [0, 0, 1.2], "look_at": [0, 0, 0] },
          "camera": { "fov_y_deg": 40, "near": 0.1, "far": 20, "active": true } } ] })";
    return file;
  }
  static glm::vec3 pixel(const Shot& s, int x, int y) {
    return {s.color.at(x, y, 0), s.color.at(x, y, 1), s.color.at(x, y, 2)};
  }
};

TEST_F(MaterialInputsTest, OcclusionScalesTheAmbientLightByItsStrength) {
  const float ao = texture("ao.png", {glm::vec3(0.2f)})[0].r;
  for (float strength : {1.0f, 0.5f, 0.0f}) {
    const std::string material = R"({ "features": ["occlusion_texture"],
      "parameters": { "base_color": [0.8, 0.8, 0.8, 1], "occlusion_strength": )" +
                                 std::to_string(strength) + R"( },
      "textures": { "occlusion": "ao.png" } })";
    const Shot s = shoot(scene("occlusion", material, 0.5f), {}, 32, 32);
    ASSERT_EQ(s.color.width, 32);
    const float want = 0.5f * 0.8f * (1.0f + strength * (ao - 1.0f));  // glTF 2.0, 3.9.3
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(s.color.at(16, 16, c), srgb_encode(want), 1.5f / 255.0f)
          << "strength " << strength;
  }
}

TEST_F(MaterialInputsTest, EmissiveTextureMultipliesTheEmissiveFactor) {
  const glm::vec3 t = texture("glow.png", {glm::vec3(0.6f, 0.8f, 1.0f)})[0];
  const glm::vec3 factor(1.0f, 0.5f, 0.25f);
  const Shot s = shoot(scene("emissive", R"({ "features": ["emissive", "emissive_texture"],
      "parameters": { "base_color": [0, 0, 0, 1], "emissive": [1, 0.5, 0.25] },
      "textures": { "emissive": "glow.png" } })",
                             0.0f),
                       {}, 32, 32);
  ASSERT_EQ(s.color.width, 32);
  for (int c = 0; c < 3; ++c)  // the texture is sRGB: decoded before it multiplies
    EXPECT_NEAR(s.color.at(16, 16, c), srgb_encode(factor[c] * srgb_decode(t[c])), 1.5f / 255.0f);
}

TEST_F(MaterialInputsTest, TextureTransformOffsetsTheLookup) {
  texture("halves.png", {glm::vec3(1, 0, 0), glm::vec3(0, 1, 0)});
  auto material = [](const std::string& offset) {
    return R"({ "features": ["emissive", "emissive_texture", "texture_transform"],
      "parameters": { "base_color": [0, 0, 0, 1], "emissive": [1, 1, 1], "uv_offset": )" +
           offset + R"( }, "textures": { "emissive": "halves.png" } })";
  };
  const Shot plain = shoot(scene("plain", material("[0, 0]"), 0.0f), {}, 32, 32);
  const Shot moved = shoot(scene("moved", material("[0.5, 0]"), 0.0f), {}, 32, 32);
  ASSERT_EQ(plain.color.width, 32);
  ASSERT_EQ(moved.color.width, 32);
  // Pixels 8 and 23 (centres symmetric about the view's centre) show mostly one texel each;
  // moved by half the texture, each shows what the other showed (the texture repeats).
  const glm::vec3 left = pixel(plain, 8, 16), right = pixel(plain, 23, 16);
  EXPECT_GT(std::abs(left.r - right.r), 0.5f);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(pixel(moved, 8, 16)[c], right[c], 2.0f / 255.0f);
    EXPECT_NEAR(pixel(moved, 23, 16)[c], left[c], 2.0f / 255.0f);
  }
}

// glTF's metallicRoughnessTexture (linear; B metallic, G roughness, times the factors) under a
// directional light: the card's two halves hold a smooth dielectric and a rough metal, and each
// half's pixel is the CPU evaluation of Appendix B's BRDF (components/brdf.h) with the texel's
// values, plus the ambient light through the split sum (components/ibl.h's ibl_combine()).
TEST_F(MaterialInputsTest, MetallicRoughnessTextureSetsMetallicFromBAndRoughnessFromG) {
  // Four texels of each half, so the bilinear footprint at each pixel below stays in one half.
  std::vector<glm::vec3> texels(4, glm::vec3(0.0f, 0.3f, 0.0f));  // a smooth dielectric
  texels.insert(texels.end(), 4, glm::vec3(0.0f, 0.9f, 1.0f));    // a rough metal
  texels = texture("metal_rough.png", texels);
  const float metallic_factor = 0.8f, roughness_factor = 0.9f, ambient = 0.1f, intensity = 3.0f;
  const glm::vec3 base(0.7f, 0.5f, 0.3f), to_light = glm::normalize(glm::vec3(-0.3f, 0.4f, 1.0f));
  std::ofstream(dir() / "metal_rough_material.json") << R"({
      "features": ["metallic_roughness_texture"],
      "parameters": { "base_color": [0.7, 0.5, 0.3, 1], "metallic": 0.8, "roughness": 0.9 },
      "textures": { "metallic_roughness": "metal_rough.png" } })";
  const fs::path file = dir() / "metal_rough.json";
  std::ofstream(file) << R"({ "kaskad_scene": 1,
      "render": { "ambient": [0.1, 0.1, 0.1], "ground": "none", "clear_color": [0, 0, 0] },
      "entities": [
        { "name": "card", "transform": { "euler_deg": [90, 0, 0] }, "primitive": { "shape": "plane" },
          "material": { "file": "metal_rough_material.json" } },
        { "name": "sun", "transform": { "direction": [0.3, -0.4, -1] },
          "light": { "type": "directional", "intensity": 3, "cast_shadows": false } },
        { "name": "camera", "transform": { "translation": [0, 0, 1.2], "look_at": [0, 0, 0] },
          "camera": { "fov_y_deg": 40, "near": 0.1, "far": 20, "active": true } } ] })";
  const Shot s = shoot(file, {}, 32, 32);
  ASSERT_EQ(s.color.width, 32);
  const glm::vec3 eye(0.0f, 0.0f, 1.2f), n(0.0f, 0.0f, 1.0f);
  // The pixel's colour from the texel's values: the uniform ambient through both lobes plus the
  // BRDF times the light, sRGB encoded.
  auto expected = [&](int x, int y, const glm::vec3& texel) {
    const glm::vec3 p(s.aovs.at(x, y, 0), s.aovs.at(x, y, 1), s.aovs.at(x, y, 2));
    BrdfInputs in;
    in.base = base;
    in.metallic = metallic_factor * texel.b;
    in.roughness = roughness_factor * texel.g;
    const glm::vec3 v = glm::normalize(eye - p);
    const float n_dot_v = glm::dot(n, v);
    const glm::vec3 ambient_light(ambient);
    const glm::vec3 linear =
        ibl_combine(in, n_dot_v, dfg_lookup(n_dot_v, std::max(in.roughness, kMinRoughness)),
                    ambient_light, ambient_light) +
        brdf_evaluate(in, n, v, to_light) * intensity * glm::dot(n, to_light);
    return glm::vec3(srgb_encode(linear.r), srgb_encode(linear.g), srgb_encode(linear.b));
  };
  // Pixels 8 and 23 of row 16 lie in the texture's first and second halves (u = 0.3 and 0.7).
  const glm::vec3 first = pixel(s, 8, 16), second = pixel(s, 23, 16);
  EXPECT_GT(glm::length(first - second), 0.1f) << "the halves are shaded alike";
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(first[c], expected(8, 16, texels[0])[c], 1.5f / 255.0f) << "channel " << c;
    EXPECT_NEAR(second[c], expected(23, 16, texels[7])[c], 1.5f / 255.0f) << "channel " << c;
  }
}

// Cut-outs casting shadows with the new inputs: the depth pass draws them with only the
// features its program has (alpha_mask, and texture_transform when the material has it), so no
// uniform of the others may be set there (a GL error, which fails the test through the fixture).
TEST_F(MaterialInputsTest, CutOutsWithTheNewInputsCastShadowsWithoutGlErrors) {
  write_texels(dir() / "mask.png", {1, 1, 1, 1, 1, 1, 1, 0});  // opaque | transparent
  texture("ao2.png", {glm::vec3(0.5f)});
  for (const char* transform : {"", R"(, "texture_transform")"}) {
    const std::string material = std::string(R"({ "features": ["base_color_texture", "alpha_mask",
        "occlusion_texture", "emissive", "emissive_texture")") + transform + R"(],
      "parameters": { "base_color": [1, 1, 1, 1], "emissive": [0.1, 0.1, 0.1],
                      "double_sided": true)" + (*transform ? R"(, "uv_offset": [0.5, 0])" : "") +
                                 R"( },
      "textures": { "base_color": "mask.png", "occlusion": "ao2.png", "emissive": "mask.png" } })";
    std::ofstream(dir() / "cutout_material.json") << material;
    const fs::path file = dir() / "cutout.json";
    std::ofstream(file) << R"({ "kaskad_scene": 1,
      "render": { "ambient": [0.2, 0.2, 0.2], "ground": "none", "clear_color": [0, 0, 0],
                  "shadow_cache": false },
      "entities": [
        { "name": "floor", "transform": { "scale": [6, 1, 6] }, "primitive": { "shape": "plane" },
          "material": { "base_color": [0.8, 0.8, 0.8, 1] } },
        { "name": "card", "transform": { "translation": [0, 1, 0], "scale": [2, 1, 2] },
          "primitive": { "shape": "plane" }, "material": { "file": "cutout_material.json" } },
        { "name": "sun", "transform": { "direction": [0.3, -1, 0.2] },
          "light": { "type": "directional", "intensity": 2, "cast_shadows": true } },
        { "name": "camera", "transform": { "translation": [0, 6, 0.01], "look_at": [0, 0, 0] },
          "camera": { "fov_y_deg": 60, "near": 0.1, "far": 20, "active": true } } ] })";
    const Shot s = shoot(file, {}, 64, 64);
    ASSERT_EQ(s.color.width, 64) << transform;
    EXPECT_EQ(gpu::debug_error_count(), 0) << "with" << transform;
  }
}

}  // namespace
}  // namespace kaskad
