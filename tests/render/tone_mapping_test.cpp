// Tone mapping on the GPU (render.tone_mapping): an emissive card of known radiance filling the
// view comes out as components/tone_mapping.h's curve of that radiance times the exposure (sRGB
// encoded, within 8-bit rounding) for every mode, the clear colour likewise, render.exposure_ev
// gives the scale 2^EV, and the AOVs are the same whatever the mode.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "components/tone_mapping.h"
#include "runtime/app/player.h"
#include "tests/render/player_fixture.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

class ToneMappingTest : public PlayerTest {
 protected:
  // An emissive card of radiance `e` filling the middle of the view, black clear colour
  // `clear` around it, no lights, no ambient.
  static std::filesystem::path card(glm::vec3 e, glm::vec3 clear) {
    const std::filesystem::path file = testing_util::test_tmp() / "tone_card.json";
    std::ofstream out(file);
    out << R"({ "kaskad_scene": 1,
      "render": { "ambient": [0, 0, 0], "ground": "none", "clear_color": [)"
        << clear.r << ", " << clear.g << ", " << clear.b << R"(] },
      "entities": [
        { "name": "card", "transform": { "euler_deg": [90, 0, 0], "scale": [1, 1, 1] },
          "primitive": { "shape": "plane" },
          "material": { "base_color": [0, 0, 0, 1], "emissive": [)"
        << e.r << ", " << e.g << ", " << e.b << R"(] } },
        { "name": "camera", "transform": { "translation": [0, 0, 4], "look_at": [0, 0, 0] },
          "camera": { "fov_y_deg": 40, "near": 0.1, "far": 20, "active": true } } ] })";
    return file;
  }
  using Frame = Shot;
  static Frame render(const std::filesystem::path& file, const std::vector<std::string>& sets) {
    return shoot(file, sets, 32, 32);
  }
};

TEST_F(ToneMappingTest, ColourFollowsTheCurveOfRadianceTimesExposure) {
  const char* modes[] = {"none", "khr_pbr_neutral", "aces"};
  const glm::vec3 clear(0.9f, 0.6f, 2.0f);
  for (int m = 0; m < 3; ++m)
    for (glm::vec3 e : {glm::vec3(0.05f), glm::vec3(0.3f), glm::vec3(1.0f), glm::vec3(3.0f),
                        glm::vec3(4.0f, 1.0f, 0.2f)}) {
      const float exposure = 1.5f;
      const Frame f = render(card(e, clear), {std::string("render.tone_mapping=") + modes[m],
                                              "render.exposure=1.5"});
      ASSERT_EQ(f.color.width, 32);
      const glm::vec3 want = tone_map(ToneMapping(m), e * exposure);
      const glm::vec3 want_clear = tone_map(ToneMapping(m), clear * exposure);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(f.color.at(16, 16, c), srgb_encode(want[c]), 1.5f / 255.0f)
            << modes[m] << " e " << e[c] << " channel " << c;
        EXPECT_NEAR(f.color.at(0, 0, c), srgb_encode(want_clear[c]), 1.5f / 255.0f)
            << modes[m] << " clear channel " << c;
      }
    }
}

TEST_F(ToneMappingTest, ExposureInEvIsTwoToTheEv) {
  const auto file = card(glm::vec3(0.8f), glm::vec3(0.5f));
  const Frame ev = render(file, {"render.exposure_ev=-1", "render.tone_mapping=aces"});
  const Frame scale = render(file, {"render.exposure=0.5", "render.tone_mapping=aces"});
  ASSERT_EQ(ev.color.width, 32);
  EXPECT_EQ(ev.color.pixels, scale.color.pixels);
  EXPECT_NEAR(ev.color.at(16, 16, 0), srgb_encode(tone_map_aces(glm::vec3(0.4f)).r), 1.5f / 255.0f);
}

TEST_F(ToneMappingTest, AovsStayLinear) {
  const auto file = card(glm::vec3(2.0f), glm::vec3(0.5f));
  const Frame none = render(file, {"render.tone_mapping=none"});
  const Frame aces = render(file, {"render.tone_mapping=aces"});
  EXPECT_EQ(none.aovs.pixels, aces.aovs.pixels);
  EXPECT_NE(none.color.pixels, aces.color.pixels);
}

}  // namespace
}  // namespace kaskad
