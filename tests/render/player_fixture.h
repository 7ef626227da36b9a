// Test fixture for render tests that load scenes: one headless Player (GL context + renderer,
// shader binary cache in the test tmp folder) per test suite, and GL errors fail each test
// (KHR_debug errors are counted by gpu::debug_error_count()).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "components/limits.h"
#include "runtime/app/player.h"
#include "runtime/assets/image_io.h"
#include "runtime/gpu/context.h"
#include "tests/test_tmp.h"

namespace kaskad {

/// The sRGB transfer functions (IEC 61966-2-1): read_color() returns encoded values.
inline float srgb_encode(float linear) {
  const float c = std::clamp(linear, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}
inline float srgb_decode(float encoded) {
  return encoded <= 0.04045f ? encoded / 12.92f : std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}

class PlayerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    gpu::ContextOptions opt;
    opt.headless = true;
    render::RendererOptions ro;
    ro.shader_cache_dir = std::filesystem::path(KASKAD_TEST_TMP) / "shader_cache";
    auto p = Player::create(opt, ro);
    ASSERT_TRUE(p.ok()) << p.error().to_string();
    player_ = new Player(std::move(p.value()));
  }
  static void TearDownTestSuite() {
    delete player_;
    player_ = nullptr;
  }
  void SetUp() override { gpu::reset_debug_error_count(); }
  void TearDown() override { EXPECT_EQ(gpu::debug_error_count(), 0) << "GL errors were logged"; }

  static inline Player* player_ = nullptr;  ///< the suite's player (suites run one at a time)

  /// Writes a row of RGBA texels (4 values each, in [0, 1]) as the image `path`: a test texture.
  static void write_texels(const std::filesystem::path& path, std::vector<float> rgba) {
    Image image;
    image.width = int(rgba.size() / 4);
    image.height = 1;
    image.channels = 4;
    image.pixels = std::move(rgba);
    const Status saved = save_image(path, image);
    ASSERT_TRUE(saved.ok()) << saved.error().to_string();
  }

  /// Folder `name` of the running test's scratch folder (tests/test_tmp.h), created.
  static std::filesystem::path test_dir(const std::string& name) {
    return testing_util::test_tmp(name);
  }

  /// One frame of the scene file `file` (with `sets` overrides) at width x height: its colour
  /// and AOVs (empty images, with a test failure, when it does not load or render).
  struct Shot {
    Image color, aovs;
  };
  static Shot shoot(const std::filesystem::path& file, const std::vector<std::string>& sets,
                    int width, int height) {
    Shot f;
    auto scene = load_scene(file, sets);
    EXPECT_TRUE(scene.ok()) << scene.error().to_string();
    if (!scene.ok()) return f;
    RenderRun run;
    run.width = width;
    run.height = height;
    auto t = render_frames(*player_, *scene, run);
    EXPECT_TRUE(t.ok()) << t.error().to_string();
    if (!t.ok()) return f;
    f.color = player_->renderer->read_color();
    f.aovs = player_->renderer->read_aovs();
    return f;
  }

  /// The depth of `map` (Renderer::read_shadow_map(): layers stacked top to bottom, rows top to
  /// bottom) that lookups can read: texels outside each layer's `rects` entry
  /// (FrameStats::layer_rect) become -1, since a layer may keep stale depth there.
  static std::vector<float> read_part(const Image& map,
                                      const std::array<glm::ivec4, kMaxShadowLayers>& rects) {
    std::vector<float> out = map.pixels;
    const int size = map.width;
    for (std::size_t i = 0; i < out.size(); ++i) {
      const int layer = int(i / (std::size_t(size) * std::size_t(size)));
      const int x = int(i % std::size_t(size));
      const int y = size - 1 - int((i / std::size_t(size)) % std::size_t(size));
      const glm::ivec4 r = rects[std::size_t(layer)];
      if (x < r.x || x >= r.z || y < r.y || y >= r.w) out[i] = -1.0f;
    }
    return out;
  }
};

}  // namespace kaskad
