// Anti-aliasing (render.msaa): a wire a third of a pixel wide is seen on every row it crosses
// with 4 samples and drops out of some rows with 1; the AOVs are the same with and without MSAA,
// bit for bit (a single-sample pass draws them); an alpha-masked card's cut edge gets partial
// coverage through alpha to coverage, and its AOVs stay those of the alpha test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/assets/image_io.h"
#include "runtime/app/player.h"
#include "tests/render/player_fixture.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

constexpr int kSize = 64;  // square test frames

class MsaaTest : public PlayerTest {
 protected:
  static fs::path dir() { return test_dir("msaa"); }
  // The camera of both test scenes: 4 m in front of the origin looking at it, 40° high, so a
  // pixel of a kSize^2 frame is 2 * 4 * tan(20°) / kSize metres wide at the origin.
  static constexpr const char* kCamera =
      R"({ "name": "camera", "transform": { "translation": [0, 0, 4], "look_at": [0, 0, 0] },
           "camera": { "fov_y_deg": 40, "near": 0.1, "far": 20, "active": true } })";
  static float pixel_metres() { return 2.0f * 4.0f * std::tan(glm::radians(20.0f)) / kSize; }

  // A white emissive wire, `width_px` pixels wide, longer than the view is high, tilted 5° from
  // vertical (so it crosses the pixel columns at every sub-pixel offset), on black.
  static fs::path wire(float width_px) {
    const fs::path file = dir() / "wire.json";
    const float w = width_px * pixel_metres();
    std::ofstream(file) << R"({ "kaskad_scene": 1,
      "render": { "ambient": [0, 0, 0], "ground": "none", "clear_color": [0, 0, 0] },
      "entities": [
        { "name": "wire", "transform": { "euler_deg": [0, 0, 5], "scale": [)"
                        << w << ", 8, " << w << R"(] },
          "primitive": { "shape": "box" },
          "material": { "base_color": [0, 0, 0, 1], "emissive": [1, 1, 1] } }, )"
                        << kCamera << "] }";
    return file;
  }

  // A white emissive, alpha-masked card larger than the view, turned 8° about the view axis;
  // its texture's alpha ramps from 0 on the left to 1 on the right, so the alpha test (cutoff
  // 0.5) cuts it along a line through the middle of the frame.
  static fs::path card() {
    Image ramp;
    ramp.width = 64;
    ramp.height = 4;
    ramp.channels = 4;
    ramp.channel_names = {"R", "G", "B", "A"};
    ramp.pixels.assign(std::size_t(ramp.width) * ramp.height * 4, 1.0f);
    for (int y = 0; y < ramp.height; ++y)
      for (int x = 0; x < ramp.width; ++x) ramp.at(x, y, 3) = (float(x) + 0.5f) / ramp.width;
    const fs::path texture = dir() / "alpha_ramp.png";
    EXPECT_TRUE(save_image(texture, ramp).ok());
    std::ofstream(dir() / "ramp_card.json") << R"({
      "features": ["base_color_texture", "alpha_mask", "emissive"],
      "parameters": { "base_color": [1, 1, 1, 1], "emissive": [1, 1, 1], "alpha_cutoff": 0.5,
                      "double_sided": true },
      "textures": { "base_color": ")" << texture.string() << R"(" } })";
    const fs::path file = dir() / "card.json";
    std::ofstream(file) << R"({ "kaskad_scene": 1,
      "render": { "ambient": [0, 0, 0], "ground": "none", "clear_color": [0, 0, 0] },
      "entities": [
        { "name": "card", "transform": { "euler_deg": [90, 8, 0], "scale": [5, 1, 5] },
          "primitive": { "shape": "plane" }, "material": { "file": "ramp_card.json" } }, )"
                        << kCamera << "] }";
    return file;
  }

  static Shot render(const fs::path& file, int msaa) {
    return shoot(file, {"render.msaa=" + std::to_string(msaa)}, kSize, kSize);
  }
  // Rows of `image` with no pixel brighter than `threshold` (sRGB-encoded red).
  static int dark_rows(const Image& image, float threshold) {
    int rows = 0;
    for (int y = 0; y < image.height; ++y) {
      bool seen = false;
      for (int x = 0; x < image.width; ++x) seen = seen || image.at(x, y, 0) > threshold;
      rows += seen ? 0 : 1;
    }
    return rows;
  }
};

TEST_F(MsaaTest, AThirdOfAPixelWireIsSeenOnEveryRow) {
  const fs::path file = wire(1.0f / 3.0f);
  const Shot one = render(file, 1);
  const Shot four = render(file, 4);
  ASSERT_EQ(four.color.width, kSize);
  ASSERT_EQ(player_->renderer->stats().msaa_samples, 4);
  // One sample per pixel: the wire covers the pixel centre on about a third of the rows.
  EXPECT_GT(dark_rows(one.color, 0.1f), kSize / 4);
  // Four: on every row at least one sample of some pixel is covered. One sample of four, white
  // on black, resolves to 0.25 linear (0.54 sRGB-encoded): 0.1 is far below it.
  EXPECT_EQ(dark_rows(four.color, 0.1f), 0);
  // The resolve averages in linear light (the target is sRGB, GL_FRAMEBUFFER_SRGB on): a pixel
  // is black or one of 1/4, 2/4, 3/4, 1 encoded, never the encoded values' average.
  const float levels[] = {0.0f, 0.537f, 0.735f, 0.881f, 1.0f};
  int off_level = 0;
  for (float v : four.color.pixels)
    if (std::none_of(std::begin(levels), std::end(levels),
                     [&](float l) { return std::abs(v - l) < 2.0f / 255.0f; }))
      ++off_level;
  EXPECT_EQ(off_level, 0);
}

TEST_F(MsaaTest, AovsAreTheSameWithAndWithoutMsaa) {
  for (const char* scene : {"default.json", "materials.json"}) {
    const fs::path file = content_dir() / "scenes" / scene;
    const Shot one = shoot(file, {"render.msaa=1"}, 160, 90);
    const Shot four = shoot(file, {"render.msaa=4"}, 160, 90);
    ASSERT_EQ(four.aovs.width, 160) << scene;
    EXPECT_EQ(one.aovs.channel_names, four.aovs.channel_names);
    EXPECT_TRUE(one.aovs.pixels == four.aovs.pixels) << scene << ": AOVs differ";
    EXPECT_NE(one.color.pixels, four.color.pixels) << scene << ": MSAA changed nothing";
  }
  // The wire too: thinner than a pixel, yet the AOV shows it exactly where one sample would.
  const fs::path file = wire(1.0f / 3.0f);
  EXPECT_TRUE(render(file, 1).aovs.pixels == render(file, 4).aovs.pixels);
}

TEST_F(MsaaTest, AlphaToCoverageSoftensACutOutEdge) {
  const fs::path file = card();
  const Shot one = render(file, 1);
  const Shot four = render(file, 4);
  ASSERT_EQ(four.color.width, kSize);
  // Per row: the card is white on the right, cut away (black) on the left, and pixels in
  // between (0.1 .. 0.9 encoded) appear only where coverage is partial.
  int rows_partial_one = 0, rows_partial_four = 0;
  for (int y = 0; y < kSize; ++y) {
    bool partial_one = false, partial_four = false;
    for (int x = 0; x < kSize; ++x) {
      const float a = one.color.at(x, y, 0), b = four.color.at(x, y, 0);
      partial_one = partial_one || (a > 0.1f && a < 0.9f);
      partial_four = partial_four || (b > 0.1f && b < 0.9f);
    }
    rows_partial_one += partial_one ? 1 : 0;
    rows_partial_four += partial_four ? 1 : 0;
    // Both keep the cut: black at the left edge, white at the right.
    EXPECT_LT(four.color.at(0, y, 0), 0.1f) << "row " << y;
    EXPECT_GT(four.color.at(kSize - 1, y, 0), 0.9f) << "row " << y;
    EXPECT_LT(one.color.at(0, y, 0), 0.1f) << "row " << y;
    EXPECT_GT(one.color.at(kSize - 1, y, 0), 0.9f) << "row " << y;
  }
  EXPECT_EQ(rows_partial_one, 0);  // the alpha test: all or nothing
  EXPECT_GT(rows_partial_four, kSize / 2);
  // The AOVs are the alpha test's, as without MSAA.
  EXPECT_TRUE(one.aovs.pixels == four.aovs.pixels);
}

}  // namespace
}  // namespace kaskad
