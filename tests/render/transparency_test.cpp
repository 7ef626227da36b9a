// Transparency (glTF alphaMode BLEND, docs/guide/materials.md "Transparency"), on glTF files the
// tests write: a blended quad over an opaque box shows the over operator's colour; two
// overlapping blended quads blend back to front whatever order the file lists them in; a
// blended quad receives shadows (with the visibility cache as without it); blended casters cast
// by the rule (alpha >= alpha_cutoff), which the ray-traced reference follows too, and the AOVs
// show the opaque surface behind a blended one.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "components/light.h"
#include "tests/unit/assets/asset_test_util.h"
#include "components/transform.h"
#include "runtime/app/player.h"
#include "runtime/reference/ray_tracer.h"
#include "runtime/reference/shadow_metrics.h"
#include "tests/render/player_fixture.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::base64;

constexpr int kSize = 64;  // square test frames

// ---- A small glTF writer: boxes and quads with normals and uvs, one material each ----------

/// Meshes of axis-aligned quads, each mesh under one node with a translation.
class Gltf {
 public:
  /// A material: linear base colour (alpha included), emission, alphaMode.
  int material(glm::vec4 base, glm::vec3 emissive, const std::string& mode,
               bool double_sided = false) {
    materials_.push_back({{"pbrMetallicRoughness",
                           {{"baseColorFactor", {base.r, base.g, base.b, base.a}},
                            {"metallicFactor", 0.0},
                            {"roughnessFactor", 1.0}}},
                          {"emissiveFactor", {emissive.r, emissive.g, emissive.b}},
                          {"alphaMode", mode},
                          {"doubleSided", double_sided}});
    return int(materials_.size()) - 1;
  }
  /// A w x h quad in the xy plane facing +z at `at`.
  void quad(const std::string& name, glm::vec3 at, glm::vec2 size, int material) {
    Mesh m;
    face(m, {0, 0, 0}, {size.x, 0, 0}, {0, size.y, 0});
    add(name, at, m, material);
  }
  /// An axis-aligned box of `size` centred at `at`, faces outward.
  void box(const std::string& name, glm::vec3 at, glm::vec3 size, int material) {
    Mesh m;
    const glm::vec3 h = 0.5f * size;
    face(m, {0, 0, h.z}, {size.x, 0, 0}, {0, size.y, 0});    // +z
    face(m, {0, 0, -h.z}, {-size.x, 0, 0}, {0, size.y, 0});  // -z
    face(m, {h.x, 0, 0}, {0, 0, -size.z}, {0, size.y, 0});   // +x
    face(m, {-h.x, 0, 0}, {0, 0, size.z}, {0, size.y, 0});   // -x
    face(m, {0, h.y, 0}, {size.x, 0, 0}, {0, 0, -size.z});   // +y
    face(m, {0, -h.y, 0}, {size.x, 0, 0}, {0, 0, size.z});   // -y
    add(name, at, m, material);
  }
  void write(const fs::path& file) const {
    json doc = {{"asset", {{"version", "2.0"}}},
                {"scene", 0},
                {"scenes", {{{"nodes", roots_}}}},
                {"nodes", nodes_},
                {"meshes", meshes_},
                {"materials", materials_},
                {"accessors", accessors_},
                {"bufferViews", views_},
                {"buffers",
                 {{{"byteLength", buffer_.size()},
                   {"uri", "data:application/octet-stream;base64," + base64(buffer_)}}}}};
    std::ofstream(file) << doc.dump(1);
  }

 private:
  struct Mesh {
    std::vector<float> positions, normals, uvs;
    std::vector<std::uint16_t> indices;
  };
  // A quad centred at `c` spanned by `u` and `v` (full lengths); its normal is u x v.
  static void face(Mesh& m, glm::vec3 c, glm::vec3 u, glm::vec3 v) {
    const glm::vec3 n = glm::normalize(glm::cross(u, v));
    const auto base = std::uint16_t(m.positions.size() / 3);
    const glm::vec2 corners[4] = {{-0.5f, -0.5f}, {0.5f, -0.5f}, {0.5f, 0.5f}, {-0.5f, 0.5f}};
    for (const glm::vec2 k : corners) {
      const glm::vec3 p = c + k.x * u + k.y * v;
      m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
      m.normals.insert(m.normals.end(), {n.x, n.y, n.z});
      m.uvs.insert(m.uvs.end(), {k.x + 0.5f, 0.5f - k.y});
    }
    for (int i : {0, 1, 2, 0, 2, 3}) m.indices.push_back(std::uint16_t(base + i));
  }
  template <class T>
  int view(const std::vector<T>& data) {
    while (buffer_.size() % 4) buffer_.push_back(0);
    const std::size_t offset = buffer_.size(), length = data.size() * sizeof(T);
    buffer_.resize(offset + length);
    std::memcpy(buffer_.data() + offset, data.data(), length);
    views_.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}});
    return int(views_.size()) - 1;
  }
  int accessor(const std::vector<float>& data, int width, const char* type) {
    json a = {{"bufferView", view(data)}, {"componentType", 5126},
              {"count", data.size() / std::size_t(width)}, {"type", type}};
    if (width == 3) {
      glm::vec3 lo(1e30f), hi(-1e30f);
      for (std::size_t i = 0; i < data.size(); i += 3) {
        lo = glm::min(lo, glm::vec3(data[i], data[i + 1], data[i + 2]));
        hi = glm::max(hi, glm::vec3(data[i], data[i + 1], data[i + 2]));
      }
      a["min"] = {lo.x, lo.y, lo.z};
      a["max"] = {hi.x, hi.y, hi.z};
    }
    accessors_.push_back(a);
    return int(accessors_.size()) - 1;
  }
  void add(const std::string& name, glm::vec3 at, const Mesh& m, int material) {
    const int p = accessor(m.positions, 3, "VEC3"), n = accessor(m.normals, 3, "VEC3"),
              t = accessor(m.uvs, 2, "VEC2");
    accessors_.push_back({{"bufferView", view(m.indices)}, {"componentType", 5123},
                          {"count", m.indices.size()}, {"type", "SCALAR"}});
    const int i = int(accessors_.size()) - 1;
    meshes_.push_back({{"name", name},
                       {"primitives",
                        {{{"attributes", {{"POSITION", p}, {"NORMAL", n}, {"TEXCOORD_0", t}}},
                          {"indices", i},
                          {"material", material}}}}});
    nodes_.push_back({{"name", name}, {"mesh", meshes_.size() - 1}, {"translation", {at.x, at.y, at.z}}});
    roots_.push_back(nodes_.size() - 1);
  }

  std::vector<std::uint8_t> buffer_;
  json nodes_ = json::array(), meshes_ = json::array(), materials_ = json::array(),
       accessors_ = json::array(), views_ = json::array(), roots_ = json::array();
};

class TransparencyTest : public PlayerTest {
 protected:
  static fs::path dir() { return test_dir("transparency"); }
  // A scene holding `model` (written next to it), a camera 4 m in front of the origin looking
  // down -z (40° high), no ambient light, a black background, and `extra` entities.
  static fs::path scene(const std::string& name, const Gltf& model, const std::string& extra = "") {
    model.write(dir() / (name + ".gltf"));
    const fs::path file = dir() / (name + ".json");
    std::ofstream(file) << R"({ "kaskad_scene": 1,
      "render": { "ambient": [0, 0, 0], "clear_color": [0, 0, 0] },
      "entities": [
        { "name": "model", "model": { "path": ")" << name << R"(.gltf" } },
        { "name": "camera", "transform": { "translation": [0, 0, 4], "look_at": [0, 0, 0] },
          "camera": { "fov_y_deg": 40, "near": 0.1, "far": 20, "active": true } })"
                        << extra << "] }";
    return file;
  }
  // The pixel (x, y) of a frame (rows top to bottom) as linear RGB.
  static glm::vec3 linear(const Image& color, int x, int y) {
    return {srgb_decode(color.at(x, y, 0)), srgb_decode(color.at(x, y, 1)),
            srgb_decode(color.at(x, y, 2))};
  }
  // The pixel the camera sees world point (x, y, z) at (z: the depth of the plane it lies on).
  static glm::ivec2 pixel_of(float x, float y, float z) {
    const float half = (4.0f - z) * std::tan(glm::radians(20.0f));
    return {int((x / half * 0.5f + 0.5f) * kSize), int((0.5f - y / half * 0.5f) * kSize)};
  }
};

// Emissive colours on black with no light: each surface's colour is its emission, so the
// expected pixel is the over operator's, alpha x source + (1 - alpha) x destination, in linear
// light (the sRGB target).
constexpr float kTolerance = 3.0f / 255.0f;

void expect_near(glm::vec3 got, glm::vec3 want, const std::string& what) {
  EXPECT_NEAR(got.r, want.r, kTolerance) << what;
  EXPECT_NEAR(got.g, want.g, kTolerance) << what;
  EXPECT_NEAR(got.b, want.b, kTolerance) << what;
}

TEST_F(TransparencyTest, BlendedQuadOverAnOpaqueBoxIsTheOverOperator) {
  Gltf g;
  const int blue = g.material({0, 0, 0, 1}, {0, 0, 1}, "OPAQUE");
  const int red = g.material({0, 0, 0, 0.4f}, {1, 0, 0}, "BLEND");
  g.quad("red", {0, 0, 1}, {1.6f, 1.6f}, red);  // first in the file, drawn after the box
  g.box("box", {0, 0, -1}, {0.8f, 0.8f, 0.8f}, blue);
  const fs::path file = scene("over_box", g);
  for (int msaa : {1, 4}) {
    const std::string what = "msaa " + std::to_string(msaa);
    const Shot s = shoot(file, {"render.msaa=" + std::to_string(msaa)}, kSize, kSize);
    ASSERT_EQ(s.color.width, kSize);
    // Over the box: 0.4 red + 0.6 blue; over the background: 0.4 red; outside: black.
    expect_near(linear(s.color, kSize / 2, kSize / 2), {0.4f, 0.0f, 0.6f}, what + ", over the box");
    const glm::ivec2 beside = pixel_of(0.65f, 0.0f, 1.0f);
    expect_near(linear(s.color, beside.x, beside.y), {0.4f, 0.0f, 0.0f}, what + ", over black");
    expect_near(linear(s.color, 1, 1), {0, 0, 0}, what + ", outside");
    // The AOVs show the opaque surface behind the blended one: the box's front at z = -0.6.
    EXPECT_NEAR(s.aovs.at(kSize / 2, kSize / 2, 2), -0.6f, 1e-3f) << what;
    EXPECT_EQ(s.aovs.at(beside.x, beside.y, 8), 0.0f) << what << ": the background's mask";
  }
}

TEST_F(TransparencyTest, OverlappingBlendedQuadsBlendBackToFront) {
  // Blue, then the green quad over it (0, 0.5, 0.5), then the red one over that: (0.5, 0.25,
  // 0.25). Front to back would give (0.25, 0.5, 0.25). The file lists the quads both ways: the
  // order is the view's, not the file's.
  for (bool near_first : {true, false}) {
    Gltf g;
    const int blue = g.material({0, 0, 0, 1}, {0, 0, 1}, "OPAQUE");
    const int red = g.material({0, 0, 0, 0.5f}, {1, 0, 0}, "BLEND");
    const int green = g.material({0, 0, 0, 0.5f}, {0, 1, 0}, "BLEND", true);
    if (near_first) g.quad("near_red", {0, 0, 1}, {1, 1}, red);
    g.quad("far_green", {0, 0, 0.5f}, {1, 1}, green);
    if (!near_first) g.quad("near_red", {0, 0, 1}, {1, 1}, red);
    g.box("box", {0, 0, -1}, {0.8f, 0.8f, 0.8f}, blue);
    const std::string name = near_first ? "near_first" : "far_first";
    const Shot s = shoot(scene(name, g), {}, kSize, kSize);
    ASSERT_EQ(s.color.width, kSize);
    expect_near(linear(s.color, kSize / 2, kSize / 2), {0.5f, 0.25f, 0.25f}, name);
  }
}

TEST_F(TransparencyTest, BlendedQuadReceivesShadows) {
  // A white blended quad at z = 0 lit by a sun shining along (0.5, 0, -1): an opaque box out of
  // view at z = 2, x in [-2, -1], shadows the quad's left half (x in [-1, 0]).
  Gltf g;
  const int white = g.material({1, 1, 1, 0.5f}, {0, 0, 0}, "BLEND");
  const int grey = g.material({0.5f, 0.5f, 0.5f, 1}, {0, 0, 0}, "OPAQUE");
  g.quad("glass", {0, 0, 0}, {2, 2}, white);
  g.box("caster", {-1.5f, 0, 2}, {1, 3, 0.2f}, grey);
  const fs::path file = scene("receiver", g, R"(,
        { "name": "sun", "transform": { "direction": [0.5, 0, -1] },
          "light": { "type": "directional", "intensity": 3, "cast_shadows": true } })");
  const Shot s = shoot(file, {}, kSize, kSize);
  ASSERT_EQ(s.color.width, kSize);
  const glm::ivec2 shadowed = pixel_of(-0.5f, 0.0f, 0.0f), lit = pixel_of(0.5f, 0.0f, 0.0f);
  const glm::vec3 in_shadow = linear(s.color, shadowed.x, shadowed.y);
  const glm::vec3 in_light = linear(s.color, lit.x, lit.y);
  EXPECT_GT(in_light.g, 0.1f);
  EXPECT_LT(in_shadow.g, 0.01f) << "the blended quad is not shadowed";
  // The visibility cache (a still camera: frames 3 on read back) leaves blended draws to look
  // up: the image is the one without the cache.
  auto loaded = load_scene(file, {"render.visibility_cache=true"});
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  RenderRun run;
  run.width = run.height = kSize;
  run.frames = 4;
  run.write_aovs = false;
  auto t = render_frames(*player_, *loaded, run);
  ASSERT_TRUE(t.ok()) << t.error().to_string();
  EXPECT_TRUE(t->last.stats.visibility_reused);
  EXPECT_TRUE(player_->renderer->read_color().pixels == s.color.pixels);
}

TEST_F(TransparencyTest, BlendedCastersCastWhereAlphaReachesTheCutoff) {
  // An opaque white wall facing +z at z = 0 and two blended quads at z = 1 in front of it, lit straight
  // along -z: alpha 0.6 (>= 0.5) casts, alpha 0.4 does not (the rule of AlphaMode::blend).
  Gltf g;
  const int wall = g.material({1, 1, 1, 1}, {0, 0, 0}, "OPAQUE");
  const int thick = g.material({1, 0, 0, 0.6f}, {0, 0, 0}, "BLEND");
  const int thin = g.material({0, 1, 0, 0.4f}, {0, 0, 0}, "BLEND");
  g.quad("thick", {-0.6f, 0, 1}, {0.6f, 0.6f}, thick);
  g.quad("thin", {0.6f, 0, 1}, {0.6f, 0.6f}, thin);
  // A slab, not a quad: the cascades end at the deepest visible receiver bound, which a flat
  // wall facing the camera would put exactly on its pixels' depth (outside by rounding).
  g.box("wall", {0, 0, -0.1f}, {4, 4, 0.2f}, wall);
  const fs::path file = scene("casters", g, R"(,
        { "name": "sun", "transform": { "direction": [0, 0, -1] },
          "light": { "type": "directional", "intensity": 3, "cast_shadows": true } })");
  auto loaded = load_scene(file, {});
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  RenderRun run;
  run.width = run.height = 128;
  auto t = render_frames(*player_, *loaded, run);
  ASSERT_TRUE(t.ok()) << t.error().to_string();
  const Image aov = player_->renderer->read_aovs();
  // The wall behind each quad's middle (AOV positions: the opaque surface behind the quads).
  int behind_thick = 0, behind_thin = 0;
  for (int y = 0; y < aov.height; ++y)
    for (int x = 0; x < aov.width; ++x) {
      if (aov.at(x, y, 8) != 1.0f || std::abs(aov.at(x, y, 2)) > 1e-3f) continue;
      const glm::vec2 p(aov.at(x, y, 0), aov.at(x, y, 1));
      const float vis = aov.at(x, y, 7);
      if (glm::length(p - glm::vec2(-0.6f, 0)) < 0.2f) {
        ++behind_thick;
        EXPECT_LT(vis, 0.01f) << "alpha 0.6 casts at (" << p.x << ", " << p.y << ")";
      }
      if (glm::length(p - glm::vec2(0.6f, 0)) < 0.2f) {
        ++behind_thin;
        EXPECT_GT(vis, 0.99f) << "alpha 0.4 casts no shadow at (" << p.x << ", " << p.y << ")";
      }
    }
  EXPECT_GT(behind_thick, 100);
  EXPECT_GT(behind_thin, 100);
  // The ray-traced reference follows the same rule: away from the shadow's edges the two agree.
  auto tracer = reference::RayTracer::build(*loaded);
  ASSERT_TRUE(tracer.ok()) << tracer.error().to_string();
  EXPECT_EQ(tracer->alpha_masked_geometries(), 2u);
  const ShadowData shadow = t->last.shadow();
  ASSERT_TRUE(shadow.light.valid());
  const auto light = reference::reference_light(loaded->world.get<Light>(shadow.light),
                                                loaded->world.get<WorldTransform>(shadow.light).matrix);
  auto ref = tracer->shadow_reference(aov, light, {});
  ASSERT_TRUE(ref.ok()) << ref.error().to_string();
  auto m = reference::compare_shadows(aov, ref->image);
  ASSERT_TRUE(m.ok()) << m.error().to_string();
  std::printf("blended casters: %zu of %zu misclassified away from edges, RMSE %.4f over %zu "
              "receivers\n",
              m->outside_edges.misclassified, m->outside_edges.pixels, m->all.rmse, m->all.pixels);
  EXPECT_GT(m->outside_edges.pixels, 5000u);
  EXPECT_LT(m->outside_edges.misclassified_pct, 1.0);
}

}  // namespace
}  // namespace kaskad
