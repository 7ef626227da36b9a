// A texture slot on TEXCOORD_1 (glTF texCoord 1): a card whose two uv sets are swapped draws
// and casts exactly as the card with the texture on TEXCOORD_0, and differently from the same
// card when the second set is ignored. The card's emissive texture holds two colours (red |
// green) and its base colour an alpha cut-out (opaque | cut), so the set reaches the forward
// pass's colour, its cut-out and the shadow pass's cut-out (a ground behind receives the shadow).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/assets/image_io.h"
#include "tests/render/player_fixture.h"
#include "tests/unit/assets/asset_test_util.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

class UvSetsTest : public PlayerTest {
 protected:
  static fs::path dir() { return test_dir("uv_sets"); }

  static void append(std::vector<std::uint8_t>& out, const std::vector<float>& values) {
    const auto* b = reinterpret_cast<const std::uint8_t*>(values.data());
    out.insert(out.end(), b, b + values.size() * sizeof(float));
  }

  /// A unit card in the xy plane (facing +z) with TEXCOORD_0 `uv0` and TEXCOORD_1 `uv1` (4 each),
  /// its textures read through set `set`, written as `name`.gltf; returns a scene file that puts
  /// it before a ground under a light from the camera's side.
  static fs::path card(const std::string& name, const std::vector<float>& uv0,
                       const std::vector<float>& uv1, int set) {
    std::vector<std::uint8_t> buffer;
    append(buffer, {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0});
    append(buffer, {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1});
    append(buffer, uv0);
    append(buffer, uv1);
    const std::vector<std::uint16_t> indices = {0, 1, 2, 0, 2, 3};
    const auto* ib = reinterpret_cast<const std::uint8_t*>(indices.data());
    buffer.insert(buffer.end(), ib, ib + indices.size() * 2);
    json views = json::array(), accessors = json::array();
    const std::pair<int, const char*> streams[] = {{48, "VEC3"}, {48, "VEC3"}, {32, "VEC2"},
                                                   {32, "VEC2"}};
    int offset = 0;
    for (const auto& [bytes, type] : streams) {
      views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}});
      accessors.push_back({{"bufferView", int(views.size()) - 1}, {"componentType", 5126},
                           {"count", 4}, {"type", type}});
      offset += bytes;
    }
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", 12}});
    accessors.push_back({{"bufferView", 4}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}});
    json doc = {
        {"asset", {{"version", "2.0"}}},
        {"scene", 0},
        {"scenes", {{{"nodes", {0}}}}},
        {"nodes", {{{"name", "card"}, {"mesh", 0}}}},
        {"meshes",
         {{{"primitives",
            {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}, {"TEXCOORD_1", 3}}},
              {"indices", 4},
              {"material", 0}}}}}}},
        {"materials",
         {{{"alphaMode", "MASK"},
           {"doubleSided", true},
           {"emissiveFactor", {1, 1, 1}},
           {"emissiveTexture", {{"index", 1}, {"texCoord", set}}},
           {"pbrMetallicRoughness",
            {{"baseColorTexture", {{"index", 0}, {"texCoord", set}}},
             {"baseColorFactor", {0, 0, 0, 1}},  // black: the card shows its emission
             {"metallicFactor", 0}}}}}},
        {"images", {{{"uri", "cut.png"}}, {{"uri", "halves.png"}}}},
        {"samplers", {{{"magFilter", 9728}, {"minFilter", 9728}}}},
        {"textures", {{{"source", 0}, {"sampler", 0}}, {{"source", 1}, {"sampler", 0}}}},
        {"accessors", accessors},
        {"bufferViews", views},
        {"buffers",
         {{{"byteLength", buffer.size()},
           {"uri", "data:application/octet-stream;base64," + test::base64(buffer)}}}},
    };
    std::ofstream(dir() / (name + ".gltf")) << doc.dump();
    const fs::path file = dir() / (name + ".json");
    std::ofstream(file) << R"({ "kaskad_scene": 1,
      "render": { "ambient": [0.2, 0.2, 0.2], "ground": "none", "clear_color": [0, 0, 0],
                  "shadow_cache": false },
      "entities": [
        { "name": "wall", "transform": { "translation": [0, 0, -0.6], "euler_deg": [90, 0, 0],
                                         "scale": [4, 1, 4] },
          "primitive": { "shape": "plane" }, "material": { "base_color": [0.8, 0.8, 0.8, 1] } },
        { "name": "model", "model": { "path": ")" << name << R"(.gltf" } },
        { "name": "sun", "transform": { "direction": [0.5, -0.3, -1] },
          "light": { "type": "directional", "intensity": 2, "cast_shadows": true } },
        { "name": "camera", "transform": { "translation": [0, 0, 2], "look_at": [0, 0, 0] },
          "camera": { "fov_y_deg": 50, "near": 0.1, "far": 20, "active": true } } ] })";
    return file;
  }

  static void write_textures() {
    write_texels(dir() / "cut.png", {1, 1, 1, 1, 1, 1, 1, 0});     // opaque | cut away
    write_texels(dir() / "halves.png", {1, 0, 0, 1, 0, 1, 0, 1});  // red | green
  }

  /// The largest difference of any channel of any pixel.
  static float max_difference(const Image& a, const Image& b) {
    float d = 0.0f;
    for (std::size_t i = 0; i < a.pixels.size() && i < b.pixels.size(); ++i)
      d = std::max(d, std::abs(a.pixels[i] - b.pixels[i]));
    return d;
  }
};

TEST_F(UvSetsTest, ASlotOnTexcoord1DrawsAndCastsAsOnTexcoord0) {
  write_textures();
  const std::vector<float> uv = {0, 1, 1, 1, 1, 0, 0, 0};      // the card's uvs
  const std::vector<float> flat = {0.25f, 0.5f, 0.25f, 0.5f, 0.25f, 0.5f, 0.25f, 0.5f};  // one texel
  const Shot on0 = shoot(card("on_set0", uv, flat, 0), {}, 96, 64);
  const Shot on1 = shoot(card("on_set1", flat, uv, 1), {}, 96, 64);
  const Shot ignored = shoot(card("set1_ignored", flat, uv, 0), {}, 96, 64);
  ASSERT_EQ(on0.color.width, 96);
  ASSERT_EQ(on1.color.width, 96);
  ASSERT_EQ(ignored.color.width, 96);
  // The card shows its colour and its cut: red on the left, the wall through the cut-out right.
  const auto at = [](const Shot& s, int x, int y, int c) { return s.color.at(x, y, c); };
  EXPECT_GT(at(on0, 40, 32, 0), 0.6f);
  EXPECT_LT(at(on0, 40, 32, 1), 0.3f);
  EXPECT_NEAR(at(on0, 56, 32, 0), at(on0, 56, 32, 1), 0.05f) << "the grey wall, not green";
  EXPECT_LE(max_difference(on0.color, on1.color), 1.0f / 255.0f) << "TEXCOORD_1 reads as TEXCOORD_0";
  EXPECT_GT(max_difference(on0.color, ignored.color), 0.3f) << "the set the slot names matters";
}

}  // namespace
}  // namespace kaskad
