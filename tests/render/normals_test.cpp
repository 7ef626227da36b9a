// Normals as the shader shades them: the interpolated normal flips only on back faces
// (gl_FrontFacing), which only double-sided materials show; a mirrored transform (negative
// determinant) keeps its front faces in front. Before, the normal flipped wherever it faced away
// from the camera, which darkened terrain ridges (normals pointing down on a heightfield lit from
// above) and sphere rims.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/app/player.h"
#include "tests/render/player_fixture.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

class NormalsTest : public PlayerTest {
 protected:
  using Frame = Shot;
  static Frame render(const std::filesystem::path& file, const std::vector<std::string>& sets,
                      int width = 320, int height = 180) {
    return shoot(file, sets, width, height);
  }
  static int channel(const Image& img, const std::string& name) {
    for (std::size_t c = 0; c < img.channel_names.size(); ++c)
      if (img.channel_names[c] == name) return int(c);
    ADD_FAILURE() << "no channel " << name;
    return 0;
  }
};

// A heightfield faces up everywhere: with the crate, post and ball moved under it, every pixel of
// the terrain scene's AOV has a normal with N.y > 0 (before, ridges seen edge-on had N.y near -1).
TEST_F(NormalsTest, TerrainNormalsFaceUpOnRidges) {
  const Frame f = render(content_dir() / "scenes" / "terrain.json",
                         {"crate.transform.translation=[0, -500, 0]",
                          "post.transform.translation=[0, -500, 0]",
                          "ball.transform.translation=[0, -500, 0]"},
                         640, 360);
  const int ny = channel(f.aovs, "N.Y"), mask = channel(f.aovs, "mask");
  int geometry = 0, down = 0;
  for (int y = 0; y < f.aovs.height; ++y)
    for (int x = 0; x < f.aovs.width; ++x) {
      if (f.aovs.at(x, y, mask) < 0.5f) continue;
      ++geometry;
      down += f.aovs.at(x, y, ny) <= 0.0f;
    }
  EXPECT_GT(geometry, 10000);
  EXPECT_EQ(down, 0) << "terrain pixels whose normal points down";
}

// A box mirrored in x (scale -1), or in y and z, is the same box: the same image as unmirrored
// (AOVs within float rounding), culled and lit from the outside. Before, its faces wound the other way and back-face culling showed its inside.
TEST_F(NormalsTest, MirroredTransformRendersLikeTheUnmirroredOne) {
  const auto scene = content_dir() / "scenes" / "default.json";
  const Frame plain = render(scene, {});
  for (const char* scale : {"[-2.5, 2.5, 2.5]", "[2.5, -2.5, -2.5]"}) {
    const Frame mirrored = render(scene, {std::string("box_large.transform.scale=") + scale});
    EXPECT_EQ(mirrored.color.pixels, plain.color.pixels) << scale;
    // The mirrored triangles interpolate positions in another order: float rounding only.
    ASSERT_EQ(mirrored.aovs.pixels.size(), plain.aovs.pixels.size());
    float worst = 0.0f;
    for (std::size_t i = 0; i < plain.aovs.pixels.size(); ++i)
      worst = std::max(worst, std::abs(mirrored.aovs.pixels[i] - plain.aovs.pixels[i]));
    EXPECT_LT(worst, 1e-4f) << scale;
  }
}

// A double-sided card seen from behind is shaded with its back face's normal: lit by a light on
// the viewer's side, as bright as its front seen from the front (same angles, mirrored).
TEST_F(NormalsTest, DoubleSidedCardIsLitOnBothSides) {
  // The lamp and the camera on side `z` of the card (which faces +z).
  auto card_seen_from = [](float z) {
    const std::filesystem::path file = testing_util::test_tmp() /
                                       (z > 0 ? "card_front.json" : "card_back.json");
    std::ofstream out(file);
    out << R"({ "kaskad_scene": 1,
      "render": { "ambient": [0, 0, 0], "clear_color": [0, 0, 0], "ground": "none" },
      "entities": [
        { "name": "card", "transform": { "euler_deg": [90, 0, 0], "scale": [2, 1, 2] },
          "primitive": { "shape": "plane" },
          "material": { "base_color": [0.8, 0.8, 0.8, 1], "roughness": 1, "double_sided": true } },
        { "name": "lamp", "transform": { "translation": [0, 0, )" << 3 * z << R"(] },
          "light": { "type": "point", "intensity": 3, "cast_shadows": false } },
        { "name": "camera", "transform": { "translation": [0, 0, )" << 4 * z << R"(], "look_at": [0, 0, 0] },
          "camera": { "fov_y_deg": 40, "near": 0.1, "far": 20, "active": true } } ] })";
    return file;
  };
  const Frame front = render(card_seen_from(1.0f), {});
  const Frame back = render(card_seen_from(-1.0f), {});
  auto centre = [](const Image& img) { return img.at(img.width / 2, img.height / 2, 0); };
  EXPECT_GT(centre(front.color), 0.2f);
  EXPECT_LT(centre(front.color), 0.9f);  // not saturated: the comparison means something
  EXPECT_NEAR(centre(back.color), centre(front.color), 0.01f);
}

}  // namespace
}  // namespace kaskad
