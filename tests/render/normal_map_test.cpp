// Normal mapping with tangent frames (runtime/assets/mesh_tangents.h, forward.vert/frag): a flat
// card whose normal map tilts every normal towards +u is shaded as the CPU BRDF shades the
// tilted normal, the per-vertex tangent frame agrees with the screen-derivative frame it replaced
// (kept for vertices without a tangent), and a mirrored card under a mirrored light looks the
// same (the bitangent's sign follows the transform's determinant).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "components/brdf.h"
#include "components/mesh_renderer.h"
#include "components/name.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/mesh_tangents.h"
#include "runtime/assets/primitives.h"
#include "runtime/app/player.h"
#include "tests/render/player_fixture.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

class NormalMapTest : public PlayerTest {
 protected:
  // The tangent-space normal every texel holds (8-bit encoded as a normal map stores it).
  static glm::vec3 texel_normal() {
    const glm::vec3 tilt = glm::normalize(glm::vec3(0.45f, 0.3f, 0.84f));
    const glm::vec3 enc = glm::round((tilt * 0.5f + 0.5f) * 255.0f) / 255.0f;
    return glm::normalize(enc * 2.0f - 1.0f);
  }
  // A 2 x 2 m card facing up (the plane primitive: +u along +x, +v along +z), seen from above,
  // lit by a sun travelling along `sun_dir`; the card's x scale is `sx` (-1 mirrors it). Each
  // test writes its own files (ctest runs tests in parallel).
  static fs::path scene(glm::vec3 sun_dir, float sx) {
    const fs::path dir =
        test_dir(std::string("normal_map/") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    Image tex;
    tex.width = tex.height = 4;
    tex.channels = 3;
    const glm::vec3 enc = texel_normal() * 0.5f + 0.5f;
    tex.pixels.assign(4 * 4 * 3, 0.0f);
    for (int i = 0; i < 16; ++i)
      for (int c = 0; c < 3; ++c) tex.pixels[std::size_t(i) * 3 + std::size_t(c)] = enc[c];
    EXPECT_TRUE(save_image(dir / "tilt.png", tex).ok());
    std::ofstream(dir / "tilt.material.json") << R"({ "features": ["normal_map"],
      "parameters": { "base_color": [0.8, 0.8, 0.8, 1], "roughness": 0.8 },
      "textures": { "normal": "tilt.png" } })";
    const fs::path file = dir / "card.json";
    std::ofstream(file) << R"({ "kaskad_scene": 1,
      "render": { "ground": "none", "ambient": [0, 0, 0], "clear_color": [0, 0, 0] },
      "entities": [
        { "name": "card", "transform": { "scale": [)" << 2.0f * sx << R"(, 1, 2] },
          "primitive": { "shape": "plane" }, "material": { "file": "tilt.material.json" } },
        { "name": "sun", "transform": { "direction": [)" << sun_dir.x << ", " << sun_dir.y << ", "
                          << sun_dir.z << R"(] },
          "light": { "type": "directional", "intensity": 2.0, "cast_shadows": false } },
        { "name": "camera", "transform": { "translation": [0, 3, 0.001], "look_at": [0, 0, 0] },
          "camera": { "fov_y_deg": 30, "near": 0.1, "far": 20, "active": true } } ] })";
    return file;
  }
  // The linear red of the centre pixel, rendered with the scene's meshes as given (tangents
  // generated at upload) or with every tangent zeroed (the screen-derivative frame).
  static float centre(const fs::path& file, bool zero_tangents) {
    auto s = load_scene(file, {});
    EXPECT_TRUE(s.ok()) << s.error().to_string();
    if (!s.ok()) return -1.0f;
    if (zero_tangents)
      for (MeshData& m : s->assets.meshes) m.tangents.assign(m.positions.size(), glm::vec4(0.0f));
    RenderRun run;
    run.width = run.height = 33;
    auto r = render_frames(*player_, *s, run);
    EXPECT_TRUE(r.ok()) << r.error().to_string();
    const Image c = player_->renderer->read_color();
    return srgb_decode(c.at(16, 16, 0));
  }
};

TEST_F(NormalMapTest, TiltedNormalsShadeAsTheCpuBrdf) {
  // The mapped normal leans towards +x (the tangent) and +z (the bitangent): lit from +x it is
  // brighter than the flat card would be, lit from -x darker, each as brdf_evaluate() of that
  // normal.
  const glm::vec3 mapped = glm::normalize(texel_normal().x * glm::vec3(1, 0, 0) +
                                          texel_normal().y * glm::vec3(0, 0, 1) +
                                          texel_normal().z * glm::vec3(0, 1, 0));
  for (float side : {1.0f, -1.0f}) {
    const glm::vec3 sun = glm::normalize(glm::vec3(-side, -1.0f, -0.4f));  // light from +side x, +z
    const float got = centre(scene(sun, 1.0f), false);
    const glm::vec3 v(0, 1, 0), l = -sun;
    const BrdfInputs in{glm::vec3(0.8f), 0.0f, 0.8f};
    const float want = (brdf_evaluate(in, mapped, v, l) * 2.0f * std::max(glm::dot(mapped, l), 0.0f)).x;
    EXPECT_NEAR(got, want, 0.01f * std::max(want, 0.05f) + 0.004f) << "sun from side " << side;
  }
}

TEST_F(NormalMapTest, TangentFrameAgreesWithTheDerivativeFrame) {
  for (glm::vec3 sun : {glm::vec3(-1, -1, 0), glm::vec3(1, -1, 0), glm::vec3(0, -1, 1)}) {
    const fs::path file = scene(glm::normalize(sun), 1.0f);
    EXPECT_NEAR(centre(file, false), centre(file, true), 0.004f) << sun.x << " " << sun.z;
  }
}

TEST_F(NormalMapTest, MirroredCardUnderAMirroredLightLooksTheSame) {
  for (float side : {1.0f, -1.0f}) {
    const glm::vec3 sun = glm::normalize(glm::vec3(-side, -1.0f, 0.3f));
    const glm::vec3 mirrored(-sun.x, sun.y, sun.z);
    EXPECT_NEAR(centre(scene(sun, 1.0f), false), centre(scene(mirrored, -1.0f), false), 0.004f);
    EXPECT_NEAR(centre(scene(sun, 1.0f), true), centre(scene(mirrored, -1.0f), true), 0.004f) << "derivative frame";
  }
}

TEST(MeshTangents, FollowTheUvGradientsWithTheirHandedness) {
  // The plane: +u along +x, +v along +z, normal +y: cross(n, t) = -z, so w = -1.
  MeshData plane = make_primitive(PrimitiveShape::plane, 3);
  std::vector<glm::vec4> t = generate_tangents(plane);
  ASSERT_EQ(t.size(), plane.positions.size());
  for (const glm::vec4& v : t) {
    EXPECT_NEAR(v.x, 1.0f, 1e-6f);
    EXPECT_NEAR(v.w, -1.0f, 0.0f);
  }
  // Mirrored in u: the tangent turns round and the handedness flips.
  for (glm::vec2& uv : plane.uvs) uv.x = 1.0f - uv.x;
  t = generate_tangents(plane);
  for (const glm::vec4& v : t) {
    EXPECT_NEAR(v.x, -1.0f, 1e-6f);
    EXPECT_NEAR(v.w, 1.0f, 0.0f);
  }
  // A sphere: unit tangents in each vertex's tangent plane.
  const MeshData sphere = make_primitive(PrimitiveShape::sphere, 24);
  t = generate_tangents(sphere);
  ASSERT_EQ(t.size(), sphere.positions.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_NEAR(glm::length(glm::vec3(t[i])), 1.0f, 1e-4f);
    EXPECT_NEAR(glm::dot(glm::vec3(t[i]), sphere.normals[i]), 0.0f, 1e-4f);
  }
  // Degenerate uvs: some unit tangent perpendicular to the normal, w = 1; no uvs: none.
  MeshData flat_uv = make_primitive(PrimitiveShape::plane, 3);
  for (glm::vec2& uv : flat_uv.uvs) uv = glm::vec2(0.5f);
  for (const glm::vec4& v : generate_tangents(flat_uv)) {
    EXPECT_NEAR(glm::length(glm::vec3(v)), 1.0f, 1e-5f);
    EXPECT_NEAR(v.y, 0.0f, 1e-6f);
    EXPECT_EQ(v.w, 1.0f);
  }
  flat_uv.uvs.clear();
  EXPECT_TRUE(generate_tangents(flat_uv).empty());
}

}  // namespace
}  // namespace kaskad
