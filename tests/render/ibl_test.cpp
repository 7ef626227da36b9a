// Image-based lighting on the GPU (components/ibl.h, content/shaders/ibl.glsl): the white
// furnace (a white sphere in a uniform environment shows that radiance, metal or not, from the
// ambient and from an environment map), a metal sphere in a two-coloured room reflects the room
// (it was black before image-based lighting), the GPU's prefiltered levels and SH rows match the
// CPU twins (runtime/assets/env_lighting.h), and a reflector of the pbr reflection model is lit
// by its probe: a mirror sees what S3's model sees, a rough one a blur of it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "components/ibl.h"
#include "components/probe_state.h"
#include "runtime/assets/env_lighting.h"
#include "runtime/assets/image_io.h"
#include "runtime/app/player.h"
#include "systems/frame.h"
#include "tests/render/player_fixture.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

class IblTest : public PlayerTest {
 protected:
  static fs::path dir() { return test_dir("ibl"); }
  // An equirectangular environment image: `top` above the horizon, `bottom` below.
  static fs::path room(const std::string& name, glm::vec3 top, glm::vec3 bottom) {
    Image img;
    img.width = 64;
    img.height = 32;
    img.channels = 3;
    img.pixels.resize(64 * 32 * 3);
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 64; ++x)
        for (int c = 0; c < 3; ++c) img.at(x, y, c) = (y < 16 ? top : bottom)[c];
    const fs::path file = dir() / (name + ".exr");
    EXPECT_TRUE(save_image(file, img).ok());
    return file;
  }
  // A sphere of the given material in front of the camera, nothing else, no lights.
  static fs::path sphere_scene(const std::string& name, const std::string& material,
                               const std::string& render) {
    const fs::path file = dir() / (name + ".json");
    std::ofstream(file) << R"({ "kaskad_scene": 1,
      "render": { "ground": "none", "clear_color": [0, 0, 0])" << render << R"( },
      "entities": [
        { "name": "ball", "transform": { "translation": [0, 0, 0] },
          "primitive": { "shape": "sphere", "segments": 64 }, "material": )" << material << R"( },
        { "name": "camera", "transform": { "translation": [0, 0, 3.2], "look_at": [0, 0, 0] },
          "camera": { "fov_y_deg": 40, "near": 0.1, "far": 20, "active": true } } ] })";
    return file;
  }
  // Linear colour of every pixel the sphere covers (AOV mask), and their positions.
  struct Covered {
    std::vector<glm::vec3> colour;
    std::vector<glm::vec3> normal;
  };
  static Covered covered(const Shot& s) {
    Covered out;
    const int mask = s.aovs.channel("mask"), nx = s.aovs.channel("N.X");
    if (mask < 0 || nx < 0) return out;
    for (int y = 0; y < s.color.height; ++y)
      for (int x = 0; x < s.color.width; ++x) {
        if (s.aovs.at(x, y, mask) != 1.0f) continue;
        out.colour.emplace_back(srgb_decode(s.color.at(x, y, 0)), srgb_decode(s.color.at(x, y, 1)),
                                srgb_decode(s.color.at(x, y, 2)));
        out.normal.emplace_back(s.aovs.at(x, y, nx), s.aovs.at(x, y, nx + 1), s.aovs.at(x, y, nx + 2));
      }
    return out;
  }
};

TEST_F(IblTest, WhiteFurnaceShowsTheEnvironmentsRadiance) {
  const float l = 0.5f;
  const fs::path grey = room("grey", glm::vec3(l), glm::vec3(l));
  for (const char* material : {R"({ "base_color": [1, 1, 1, 1], "metallic": 0, "roughness": 0.9 })",
                               R"({ "base_color": [1, 1, 1, 1], "metallic": 0, "roughness": 0.2 })",
                               R"({ "base_color": [1, 1, 1, 1], "metallic": 1, "roughness": 0.5 })"})
    for (bool map : {false, true}) {
      const std::string render = map ? R"(, "ambient": [0, 0, 0], "environment": ")" +
                                           grey.filename().string() + "\""
                                     : R"(, "ambient": [0.5, 0.5, 0.5])";
      const Shot s = shoot(sphere_scene("furnace", material, render), {}, 96, 96);
      const Covered c = covered(s);
      ASSERT_GT(c.colour.size(), 1000u) << material;
      float worst = 0.0f;
      for (const glm::vec3& v : c.colour)
        for (int ch = 0; ch < 3; ++ch) worst = std::max(worst, std::abs(v[ch] - l) / l);
      // Within 3% (8-bit sRGB rounding is about 0.5% here).
      EXPECT_LT(worst, 0.03f) << material << (map ? " in a grey environment map" : " in grey ambient");
    }
}

TEST_F(IblTest, MetalSphereReflectsTheColouredRoom) {
  const fs::path red_blue = room("red_blue", glm::vec3(1.0f, 0.05f, 0.05f), glm::vec3(0.05f, 0.05f, 1.0f));
  const std::string metal = R"({ "base_color": [0.95, 0.95, 0.95, 1], "metallic": 1, "roughness": 0.15 })";
  const std::string env = R"(, "ambient": [0, 0, 0], "environment": ")" + red_blue.filename().string() + "\"";
  const Covered lit = covered(shoot(sphere_scene("metal", metal, env), {}, 96, 96));
  ASSERT_GT(lit.colour.size(), 1000u);
  int up = 0, down = 0;
  for (std::size_t i = 0; i < lit.colour.size(); ++i) {
    const glm::vec3 c = lit.colour[i], n = lit.normal[i];
    // The normal's top reflects the view ray upwards: the red sky; its bottom the blue floor.
    if (n.y > 0.5f) {
      EXPECT_GT(c.r, 0.5f);
      EXPECT_GT(c.r, 4.0f * c.b);
      ++up;
    } else if (n.y < -0.5f) {
      EXPECT_GT(c.b, 0.5f);
      EXPECT_GT(c.b, 4.0f * c.r);
      ++down;
    }
  }
  EXPECT_GT(up, 200);
  EXPECT_GT(down, 200);
  // Without the environment (and no ambient) the same metal is black: the room is what lit it.
  const Covered dark = covered(shoot(sphere_scene("metal_dark", metal, R"(, "ambient": [0, 0, 0])"), {}, 96, 96));
  ASSERT_FALSE(dark.colour.empty());
  for (const glm::vec3& c : dark.colour) EXPECT_LT(std::max({c.r, c.g, c.b}), 0.01f);
}

TEST_F(IblTest, GpuPrefilteringAndShMatchTheCpuTwins) {
  // A smooth sky (brighter above, tinted by direction) as an equirect file.
  Image img;
  img.width = 128;
  img.height = 64;
  img.channels = 3;
  img.pixels.resize(std::size_t(128) * 64 * 3);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 128; ++x) {
      const float lat = 3.14159265f * (0.5f - (y + 0.5f) / 64.0f);
      const float lon = 2.0f * 3.14159265f * ((x + 0.5f) / 128.0f - 0.5f);
      const glm::vec3 d(std::cos(lat) * std::sin(lon), std::sin(lat), -std::cos(lat) * std::cos(lon));
      img.at(x, y, 0) = 0.6f + 0.4f * d.y;
      img.at(x, y, 1) = 0.4f + 0.3f * d.x;
      img.at(x, y, 2) = 0.35f + 0.2f * d.z + 0.1f * d.x * d.z;
    }
  const fs::path sky = dir() / "sky.exr";
  ASSERT_TRUE(save_image(sky, img).ok());
  const fs::path scene_file = sphere_scene(
      "sky", R"({ "base_color": [1, 1, 1, 1] })", R"(, "environment": "sky.exr")");
  auto scene = load_scene(scene_file, {});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  RenderRun run;
  run.width = run.height = 32;
  run.frames = 1;
  ASSERT_TRUE(render_frames(*player_, *scene, run).ok());
  const CubeMap& cpu = scene->assets.env_maps.at(scene->environment_map);

  // SH row 0 against project_sh9() of the same (256 x 256 a face) cube: the GPU projects a
  // 16 x 16 box-filtered mip, so agreement is to the filtering of a smooth function.
  const std::vector<glm::vec3> gpu_sh = player_->renderer->read_sh_row(0);
  ASSERT_EQ(gpu_sh.size(), 9u);
  const Sh9 cpu_sh = project_sh9(cpu);
  for (std::size_t i = 0; i < 9; ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(gpu_sh[i][c], cpu_sh[i][c], 0.01f) << "coefficient " << i;

  // Each prefiltered level against prefiltered_radiance() at texel centres of every face.
  const int levels = ibl_specular_levels(cpu.size);
  for (int level = 0; level < levels; ++level) {
    const CubeMap gpu = player_->renderer->read_environment_level(level);
    ASSERT_EQ(gpu.size, cpu.size >> level);
    const float roughness = float(level) / float(levels - 1);
    for (int f = 0; f < 6; ++f)
      for (glm::vec2 st : {glm::vec2(0.5f), glm::vec2(0.15f, 0.8f), glm::vec2(0.9f, 0.3f)}) {
        const int x = std::min(int(st.x * gpu.size), gpu.size - 1), y = std::min(int(st.y * gpu.size), gpu.size - 1);
        const glm::vec3 d = cube_direction(CubeFace(f), (x + 0.5f) / gpu.size, (y + 0.5f) / gpu.size);
        const glm::vec3 want = prefiltered_radiance(cpu, d, roughness, 2048);
        const glm::vec3 got(gpu.at(CubeFace(f), x, y));
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(got[c], want[c], 0.02f) << "level " << level << " face " << f << " channel " << c;
      }
  }
}

// A reflector sphere facing a red wall (its probe's +Z face), a green one behind the camera
// side... the probe sees red ahead of the camera's mirror direction.
fs::path reflector_scene(const std::string& name, const std::string& model, float roughness,
                         const std::string& update = R"("update": "first_frame")") {
  const fs::path file = testing_util::test_tmp("ibl") / (name + ".json");
  std::ofstream(file) << R"({ "kaskad_scene": 1,
    "render": { "ground": "none", "clear_color": [0.1, 0.1, 0.1], "ambient": [0.02, 0.02, 0.02] },
    "entities": [
      { "name": "ball", "transform": { "translation": [0, 0, 0] },
        "primitive": { "shape": "sphere", "segments": 64 },
        "material": { "base_color": [1, 1, 1, 1], "metallic": 1, "roughness": )" << roughness
                            << R"(, "reflection_model": ")" << model << R"(" },
        "reflector": { "map": "cube", )" << update << R"(, "resolution": 64 } },
      { "name": "wall", "transform": { "translation": [0, 0, 4], "euler_deg": [90, 0, 0], "scale": [6, 1, 6] },
        "primitive": { "shape": "plane" },
        "material": { "base_color": [0, 0, 0, 1], "emissive": [0.8, 0.1, 0.1], "double_sided": true } },
      { "name": "camera", "transform": { "translation": [0, 0, 3], "look_at": [0, 0, 0] },
        "camera": { "fov_y_deg": 40, "near": 0.1, "far": 20, "active": true } } ] })";
  return file;
}

TEST_F(IblTest, PbrReflectorIsLitByItsProbe) {
  // The camera sits between the ball and the red wall: the ball's middle mirrors the wall.
  auto reflection = [](const Shot& s, int x, int y) {
    const int r = s.aovs.channel("reflection.R");
    return glm::vec4(s.aovs.at(x, y, r), s.aovs.at(x, y, r + 1), s.aovs.at(x, y, r + 2),
                     s.aovs.at(x, y, r + 3));
  };
  const Shot s3 = shoot(reflector_scene("s3", "s3", 0.0f), {}, 64, 64);
  const Shot pbr = shoot(reflector_scene("pbr", "pbr", 0.0f), {}, 64, 64);
  ASSERT_EQ(s3.aovs.width, 64);
  ASSERT_EQ(pbr.aovs.width, 64);
  // A mirror: the pbr probe's level 0 is S3's map, so the reflection AOV agrees.
  const glm::vec4 a = reflection(s3, 32, 32), b = reflection(pbr, 32, 32);
  EXPECT_EQ(b.w, 1.0f);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 0.02f) << c;
  EXPECT_GT(b.r, 0.5f);
  // And the colour is the BRDF's: a white metal mirror reflects the wall's red (F ~ 1).
  EXPECT_GT(srgb_decode(pbr.color.at(32, 32, 0)), 0.6f);
  EXPECT_LT(srgb_decode(pbr.color.at(32, 32, 1)), 0.2f);
  // A rough pbr reflector blurs the probe: its reflection reaches the dark surroundings, so the
  // red at the centre falls and spreads.
  const Shot rough = shoot(reflector_scene("rough", "pbr", 0.8f), {}, 64, 64);
  const glm::vec4 r = reflection(rough, 32, 32);
  EXPECT_EQ(r.w, 1.0f);
  EXPECT_LT(r.r, b.r - 0.05f);
  EXPECT_GT(r.r, 0.05f);
}

TEST_F(IblTest, PbrPrefilteringIsTimeSlicedLikeTheCaptures) {
  // Captures every 8 frames, 2 faces a frame: the first map is prefiltered whole at once, every
  // later one 2 faces a frame over the 3 frames after its capture completes, and the pbr
  // reflector shows the new prefiltered cube only once all six are done.
  auto scene = load_scene(reflector_scene("sliced", "pbr", 0.5f,
                                          R"("update": "every_n", "every_n": 8, "faces_per_frame": 2)"),
                          {});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  FrameContext ctx;
  ctx.width = ctx.height = 32;
  ASSERT_TRUE(prewarm_frame(*scene, *player_->renderer, ctx).ok());
  SystemState systems;
  FrameReport report;
  std::vector<int> faces, done, captured;
  for (int k = 0; k < 24; ++k) {
    ctx.index = std::uint64_t(k);
    ASSERT_TRUE(run_frame(*scene, *player_->renderer, ctx, systems, report).ok());
    faces.push_back(report.stats.probe_prefilter_faces);
    done.push_back(report.stats.probe_prefilters);
    captured.push_back(report.stats.probe_faces);
  }
  EXPECT_EQ(faces[0], 6);
  EXPECT_EQ(done[0], 1);
  int completions = 0;
  for (int k = 1; k < 24; ++k) {
    EXPECT_TRUE(faces[std::size_t(k)] == 0 || faces[std::size_t(k)] == 2) << "frame " << k;
    if (done[std::size_t(k)] == 0) continue;
    ++completions;
    // Done in the third frame of 2 faces, which follow the frame the capture completed in.
    ASSERT_GE(k, 3);
    EXPECT_EQ(faces[std::size_t(k - 1)], 2);
    EXPECT_EQ(faces[std::size_t(k - 2)], 2);
    EXPECT_EQ(faces[std::size_t(k - 3)], 0);
    EXPECT_GT(captured[std::size_t(k - 3)], 0);
  }
  EXPECT_GE(completions, 2);
}

}  // namespace
}  // namespace kaskad
