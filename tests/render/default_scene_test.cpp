// Renders the default scene headless and checks the shadow visibility AOV against an independent
// CPU ray cast: for every pixel, a ray from the rasterised surface point towards the light, tested
// against the scene's triangles (world space, brute force with per-object boxes). Away from shadow
// edges at least 99% of the pixels must agree.
#include <gtest/gtest.h>

#include <cmath>

#include "components/light.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "runtime/assets/scene_io.h"
#include "runtime/cli/player.h"
#include "runtime/gpu/context.h"
#include "systems/shadow_map_system.h"

namespace kaskad {
namespace {

struct Caster {
  Aabb box;
  std::vector<glm::vec3> tris;  // 3 per triangle, world space
};

std::vector<Caster> gather_casters(const Scene& scene) {
  std::vector<Caster> out;
  scene.world.view<MeshRenderer, WorldTransform>().each(
      [&](ecs::Entity, const MeshRenderer& mr, const WorldTransform& wt) {
        if (!mr.cast_shadows || mr.mesh == kNoMesh) return;
        const MeshData& m = scene.assets.meshes[mr.mesh];
        Caster c;
        for (std::uint32_t i : m.indices) {
          const glm::vec3 p = glm::vec3(wt.matrix * glm::vec4(m.positions[i], 1.0f));
          c.tris.push_back(p);
          c.box.expand(p);
        }
        out.push_back(std::move(c));
      });
  return out;
}

bool hits_box(const Aabb& b, const glm::vec3& o, const glm::vec3& inv_d) {
  float t0 = 0.0f, t1 = 1e30f;
  for (int a = 0; a < 3; ++a) {
    float tn = (b.min[a] - o[a]) * inv_d[a], tf = (b.max[a] - o[a]) * inv_d[a];
    if (tn > tf) std::swap(tn, tf);
    t0 = std::max(t0, tn);
    t1 = std::min(t1, tf);
    if (t0 > t1) return false;
  }
  return true;
}

// Möller–Trumbore, double precision, both faces.
bool hits_triangle(const glm::vec3& o, const glm::vec3& d, const glm::vec3& a, const glm::vec3& b,
                   const glm::vec3& c) {
  const glm::dvec3 e1 = glm::dvec3(b - a), e2 = glm::dvec3(c - a), dd = glm::dvec3(d);
  const glm::dvec3 p = glm::cross(dd, e2);
  const double det = glm::dot(e1, p);
  if (std::abs(det) < 1e-14) return false;
  const double inv = 1.0 / det;
  const glm::dvec3 s = glm::dvec3(o - a);
  const double u = glm::dot(s, p) * inv;
  if (u < 0.0 || u > 1.0) return false;
  const glm::dvec3 q = glm::cross(s, e1);
  const double v = glm::dot(dd, q) * inv;
  if (v < 0.0 || u + v > 1.0) return false;
  return glm::dot(e2, q) * inv > 1e-7;
}

bool occluded(const std::vector<Caster>& casters, const glm::vec3& o, const glm::vec3& d) {
  const glm::vec3 inv_d = 1.0f / d;
  for (const Caster& c : casters) {
    if (!hits_box(c.box, o, inv_d)) continue;
    for (std::size_t i = 0; i < c.tris.size(); i += 3)
      if (hits_triangle(o, d, c.tris[i], c.tris[i + 1], c.tris[i + 2])) return true;
  }
  return false;
}

struct Agreement {
  int compared = 0, agree = 0, eligible = 0, shadowed = 0, lit = 0;
  double ratio() const { return compared ? double(agree) / compared : 0.0; }
};

class DefaultSceneTest : public ::testing::Test {
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

  // Renders the default scene with overrides and compares visibility with the ray cast.
  Agreement render_and_compare(std::vector<std::string> sets, Image* aov_out = nullptr) {
    sets.push_back("render.width=400");
    sets.push_back("render.height=225");
    auto scene = load_scene(content_dir() / "scenes" / "default.json", sets);
    EXPECT_TRUE(scene.ok()) << scene.error().to_string();
    if (!scene.ok()) return {};
    RenderRun run;
    auto t = render_frames(*player_, *scene, run);
    EXPECT_TRUE(t.ok()) << t.error().to_string();
    if (!t.ok()) return {};
    const Image aov = player_->renderer->read_aovs();
    if (aov_out) *aov_out = aov;
    const ecs::Entity sun = t->last.shadow.light;
    EXPECT_TRUE(sun.valid());
    const glm::vec3 to_light =
        -light_direction(scene->world.get<WorldTransform>(sun).matrix);
    const auto casters = gather_casters(*scene);

    const int w = aov.width, h = aov.height;
    // Reference per pixel: -1 not comparable (background, facing away / grazing), 0 shadowed, 1 lit.
    std::vector<int> ref(std::size_t(w) * h, -1);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (aov.at(x, y, 8) < 0.5f) continue;
        const glm::vec3 p(aov.at(x, y, 0), aov.at(x, y, 1), aov.at(x, y, 2));
        const glm::vec3 n(aov.at(x, y, 3), aov.at(x, y, 4), aov.at(x, y, 5));
        if (glm::dot(n, to_light) < 0.1f) continue;  // facing away or grazing: self-shadowed
        const glm::vec3 origin = p + 2e-3f * n;
        ref[std::size_t(y) * w + x] = occluded(casters, origin, to_light) ? 0 : 1;
      }
    Agreement a;
    constexpr int kEdge = 2;  // pixels within this radius of a reference edge are left out
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const int r = ref[std::size_t(y) * w + x];
        if (r < 0) continue;
        ++a.eligible;
        bool edge = false;
        for (int dy = -kEdge; dy <= kEdge && !edge; ++dy)
          for (int dx = -kEdge; dx <= kEdge && !edge; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
            edge = ref[std::size_t(yy) * w + xx] != r;
          }
        if (edge) continue;
        ++a.compared;
        (r ? a.lit : a.shadowed)++;
        const int got = aov.at(x, y, 7) >= 0.5f ? 1 : 0;
        a.agree += got == r;
      }
    return a;
  }

  static Player* player_;
};
Player* DefaultSceneTest::player_ = nullptr;

struct Config {
  const char* name;
  std::vector<std::string> sets;
};
void PrintTo(const Config& c, std::ostream* os) { *os << c.name; }

class DefaultSceneVisibility : public DefaultSceneTest,
                               public ::testing::WithParamInterface<Config> {};

TEST_P(DefaultSceneVisibility, AgreesWithRayCastAwayFromEdges) {
  const Agreement a = render_and_compare(GetParam().sets);
  std::printf("[ %s ] compared %d of %d eligible pixels (%d lit, %d shadowed): %.3f%% agree\n",
              GetParam().name, a.compared, a.eligible, a.lit, a.shadowed, 100.0 * a.ratio());
  // The comparison must be meaningful: most pixels compared, both classes well represented.
  EXPECT_GT(a.compared, a.eligible / 2);
  EXPECT_GT(a.shadowed, 300);
  EXPECT_GT(a.lit, 5000);
  EXPECT_GE(a.ratio(), 0.99);
}

INSTANTIATE_TEST_SUITE_P(
    Filters, DefaultSceneVisibility,
    ::testing::Values(Config{"pcf3x3", {}}, Config{"none", {"shadow.filter=none"}},
                      Config{"bilinear", {"shadow.filter=bilinear"}},
                      Config{"cull_front", {"shadow.cull=front"}},
                      Config{"map_1024", {"shadow.map_size=1024"}}),
    [](const auto& info) { return std::string(info.param.name); });

TEST_F(DefaultSceneTest, BadConfigurationIsCaughtByTheSameCheck) {
  // No bias and a tiny map: acne and blocky edges. The check above must be able to fail.
  const Agreement a = render_and_compare(
      {"shadow.map_size=64", "shadow.constant_bias=0", "shadow.slope_bias=0",
       "shadow.normal_offset_bias=0", "shadow.filter=none"});
  std::printf("[ bad config ] %.3f%% agree\n", 100.0 * a.ratio());
  EXPECT_LT(a.ratio(), 0.99);
}

TEST_F(DefaultSceneTest, AovChannelsFollowTheContract) {
  Image aov;
  render_and_compare({}, &aov);
  ASSERT_EQ(aov.channels, 10);
  ASSERT_EQ(aov.channel_names[9], "cascade");
  ASSERT_EQ(aov.channel_names[7], "visibility");
  int drawn = 0, background = 0;
  for (int y = 0; y < aov.height; ++y)
    for (int x = 0; x < aov.width; ++x) {
      if (aov.at(x, y, 8) < 0.5f) {
        ++background;
        continue;
      }
      ++drawn;
      const glm::vec3 n(aov.at(x, y, 3), aov.at(x, y, 4), aov.at(x, y, 5));
      ASSERT_NEAR(glm::length(n), 1.0f, 1e-3f);
      ASSERT_GT(aov.at(x, y, 6), 0.0f);  // view depth is positive in front of the camera
      const float v = aov.at(x, y, 7);
      ASSERT_TRUE(v >= 0.0f && v <= 1.0f);
    }
  EXPECT_GT(drawn, aov.width * aov.height / 2);
  EXPECT_GT(background, 0);  // the sky is visible above the horizon
}

TEST_F(DefaultSceneTest, BackgroundIsTheSrgbEncodedClearColour) {
  auto scene = load_scene(content_dir() / "scenes" / "default.json",
                          {"render.width=64", "render.height=36", "render.clear_color=[0.5,0.25,0.0]"});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  ASSERT_TRUE(render_frames(*player_, *scene, {}).ok());
  const Image c = player_->renderer->read_color();
  // Top-left pixel is sky. sRGB(0.5) = 0.7354, sRGB(0.25) = 0.5371.
  EXPECT_NEAR(c.at(0, 0, 0), 0.7354f, 1.5f / 255.0f);
  EXPECT_NEAR(c.at(0, 0, 1), 0.5371f, 1.5f / 255.0f);
  EXPECT_NEAR(c.at(0, 0, 2), 0.0f, 1.0f / 255.0f);
}

}  // namespace
}  // namespace kaskad
