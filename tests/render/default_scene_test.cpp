// Renders the default scene headless and checks the shadow visibility AOV against an independent
// CPU ray cast: for every pixel, a ray from the rasterised surface point towards the light, tested
// against the scene's triangles (world space, brute force with per-object boxes). Away from shadow
// edges at least 99% of the pixels must agree.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>

#include "components/light.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/scene_io.h"
#include "runtime/app/player.h"
#include "tests/render/player_fixture.h"
#include "runtime/gpu/context.h"
#include "systems/shadow_map_system.h"
#include "tests/test_tmp.h"

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
        const MeshData& m = scene.assets.meshes[index(mr.mesh)];
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

class DefaultSceneTest : public PlayerTest {
 protected:
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
    const ecs::Entity sun = t->last.shadow().light;
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

};

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

// Cascades: every count in both fits (and map-bounds selection) must agree with the ray cast.
INSTANTIATE_TEST_SUITE_P(
    Cascades, DefaultSceneVisibility,
    ::testing::Values(
        Config{"stable_1", {"shadow.cascade_count=1", "shadow.fit_mode=stable"}},
        Config{"stable_2", {"shadow.cascade_count=2", "shadow.fit_mode=stable"}},
        Config{"stable_4", {"shadow.cascade_count=4", "shadow.fit_mode=stable"}},
        Config{"stable_8", {"shadow.cascade_count=8", "shadow.fit_mode=stable"}},
        Config{"crop_1", {"shadow.cascade_count=1", "shadow.fit_mode=crop"}},
        Config{"crop_2", {"shadow.cascade_count=2", "shadow.fit_mode=crop"}},
        Config{"crop_4", {"shadow.cascade_count=4", "shadow.fit_mode=crop"}},
        Config{"crop_8", {"shadow.cascade_count=8", "shadow.fit_mode=crop"}},
        Config{"scene_1", {"shadow.cascade_count=1", "shadow.fit_mode=scene"}},
        Config{"stable_4_map_bounds", {"shadow.cascade_count=4", "shadow.selection=map_bounds"}},
        Config{"stable_4_d16", {"shadow.cascade_count=4", "shadow.depth_format=d16"}},
        Config{"stable_4_d32f", {"shadow.cascade_count=4", "shadow.depth_format=d32f"}}),
    [](const auto& info) { return std::string(info.param.name); });

// One cascade fitted to the scene is the basic map from before the cascades: its visibility AOV
// (default scene, 400x225, pcf3x3, 2048^2, d24) was rendered by the basic renderer at commit
// 25fd79d and stored as 8-bit (tests/render/data/basic_map_visibility_400x225.png).
TEST_F(DefaultSceneTest, SceneFitReproducesTheBasicMap) {
  Image aov;
  render_and_compare({"shadow.cascade_count=1", "shadow.fit_mode=scene"}, &aov);
  auto golden = load_image(std::filesystem::path(KASKAD_TEST_DATA) / "basic_map_visibility_400x225.png");
  ASSERT_TRUE(golden.ok()) << golden.error().to_string();
  ASSERT_EQ(golden->width, aov.width);
  ASSERT_EQ(golden->height, aov.height);
  int differ = 0;
  float worst = 0.0f;
  for (int y = 0; y < aov.height; ++y)
    for (int x = 0; x < aov.width; ++x) {
      const float d = std::abs(aov.at(x, y, 7) - golden->at(x, y, 0));
      worst = std::max(worst, d);
      differ += d > 0.5f / 255.0f + 1e-5f;  // beyond the golden's 8-bit rounding
    }
  std::printf("[ scene fit vs basic map ] %d pixels differ, worst %.5f\n", differ, worst);
  EXPECT_EQ(differ, 0);
  for (int y = 0; y < aov.height; ++y)
    for (int x = 0; x < aov.width; ++x)
      if (aov.at(x, y, 8) > 0.5f) {
        ASSERT_EQ(aov.at(x, y, 9), 0.0f);  // all in cascade 0
      }
}

// S2's stabilisation: with the stable fit the cascades' texel grid is fixed in the world, so
// moving the camera by less than a texel leaves the visibility at every world point unchanged.
// A top-down orthographic camera moved by whole screen pixels (1/16 m; the cascade texels are
// about 0.1 m) sees the same world points at shifted pixels; their visibility must be identical.
TEST_F(DefaultSceneTest, StableCascadesDoNotShimmerUnderSubTexelCameraMoves) {
  auto render_at = [&](float x, const char* fit, ShadowData* shadow) {
    const std::string tx = "camera.transform.translation=[" + std::to_string(x) + ",20,0]";
    auto scene = load_scene(content_dir() / "scenes" / "default.json",
                            {"render.width=256", "render.height=256",
                             "camera.camera.projection=orthographic", "camera.camera.ortho_height=16",
                             tx, "camera.transform.rotation=[-0.70710678,0,0,0.70710678]",
                             "shadow.map_size=256", "shadow.cascade_count=4",
                             std::string("shadow.fit_mode=") + fit});
    EXPECT_TRUE(scene.ok()) << scene.error().to_string();
    auto t = render_frames(*player_, *scene, {});
    EXPECT_TRUE(t.ok()) << t.error().to_string();
    if (shadow && t.ok()) *shadow = t->last.shadow();
    return player_->renderer->read_aovs();
  };
  auto count_changes = [&](const char* fit, int& compared, float& texel) {
    ShadowData shadow;
    const Image a = render_at(0.0f, fit, &shadow);
    texel = shadow.texel_size[3];
    int changed = 0;
    compared = 0;
    for (int k = 1; k <= 3; ++k) {
      const Image b = render_at(float(k) / 16.0f, fit, nullptr);
      for (int y = 0; y < b.height; ++y)
        for (int x = 0; x + k < b.width; ++x) {
          if (a.at(x + k, y, 8) < 0.5f || b.at(x, y, 8) < 0.5f) continue;
          bool same_point = true;
          for (int c = 0; c < 3; ++c)
            same_point = same_point && std::abs(a.at(x + k, y, c) - b.at(x, y, c)) < 1e-4f;
          if (!same_point) continue;
          ++compared;
          changed += a.at(x + k, y, 7) != b.at(x, y, 7);
        }
    }
    return changed;
  };
  int compared = 0;
  float texel = 0.0f;
  const int stable = count_changes("stable", compared, texel);
  std::printf("[ stable ] %d of %d world points changed visibility (last cascade texel %.4f m)\n",
              stable, compared, texel);
  EXPECT_GT(compared, 100000);
  EXPECT_GT(texel, 1.0f / 16.0f);  // the one-pixel move is a sub-texel move
  // Snapping moves the map by whole texels, so a world point keeps its texel up to float
  // rounding of the light-space coordinate (about 1e-5 texel): a PCF tap (or gather) whose
  // coordinate lies that close to a texel edge may take the neighbour. Measured: 0 to 10 of
  // 195,072 points, depending on the split scheme and the PCF form (0 with filter none). That is
  // noise at texel edges, not shimmer: allow 1 in 10,000, 50x below the crop fit's rate.
  EXPECT_LE(stable, compared / 10000);
  // The contrast that shows the comparison can see shimmer: the crop fit (S0, not snapped)
  // changes the visibility of a few percent of the same points (6109 of 195072 when written);
  // a crop fit that stopped moving with the camera would change none.
  const int crop = count_changes("crop", compared, texel);
  std::printf("[ crop, for contrast ] %d of %d world points changed visibility\n", crop, compared);
  EXPECT_GT(compared, 100000);
  EXPECT_GT(crop, compared / 100) << "the crop fit should shimmer under sub-texel camera moves";
}

// Per-cascade stats: each layer draws exactly the casters the system kept for it; layers without
// receivers draw nothing; the farthest receiver pulls the last split in from the camera's far.
// Crop fits: the stable fit's spheres are wide enough here for every cascade to see every caster
// once the range starts at the nearest receiver.
TEST_F(DefaultSceneTest, EachCascadeDrawsOnlyItsCulledCasters) {
  // One pass per layer: the casters of each cascade, one instanced draw per mesh among them, all
  // in one call (the depth program does not read materials; the layered pass is below).
  auto scene = load_scene(
      content_dir() / "scenes" / "default.json",
      {"render.width=160", "render.height=90", "shadow.cascade_count=8", "shadow.layered=false",
       "shadow.fit_mode=crop"});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  auto t = render_frames(*player_, *scene, {});
  ASSERT_TRUE(t.ok()) << t.error().to_string();
  const render::FrameStats& st = t->last.stats;
  const ShadowData& sh = t->last.shadow();
  ASSERT_EQ(st.shadow_layers, 8);
  int casters = 0, culled = 0, meshes_per_layer = 0, layers_drawn = 0;
  std::size_t triangles = 0;
  std::set<MeshId> all_meshes;
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_EQ(st.layer_casters[i], int(sh.casters[i].size())) << "cascade " << i;
    std::set<MeshId> meshes;
    for (ecs::Entity e : sh.casters[i]) meshes.insert(scene->world.get<MeshRenderer>(e).mesh);
    if (!sh.skipped[i]) meshes_per_layer += int(meshes.size());
    if (!sh.skipped[i] && !meshes.empty()) ++layers_drawn;
    all_meshes.insert(meshes.begin(), meshes.end());
    if (sh.skipped[i]) {
      EXPECT_EQ(st.layer_casters[i], 0) << "cascade " << i;
    }
    casters += st.layer_casters[i];
    triangles += st.layer_triangles[i];
    culled += 8 - st.layer_casters[i];  // the default scene has 8 casters
  }
  EXPECT_EQ(casters, st.shadow_instances);
  EXPECT_EQ(st.shadow_mesh_draws, meshes_per_layer);
  EXPECT_LT(st.shadow_mesh_draws, st.shadow_instances);  // the boxes share a draw
  EXPECT_EQ(st.shadow_draw_calls, layers_drawn);         // every mesh of a layer in one call
  EXPECT_EQ(triangles, st.shadow_triangles);
  EXPECT_GT(culled, 0);  // the nearest and farthest cascades do not see every caster
  EXPECT_FLOAT_EQ(sh.far_requested, 100.0f);
  EXPECT_LT(sh.far_used, 60.0f);  // the ground ends about 40 m from the camera
  EXPECT_FLOAT_EQ(sh.splits[8], sh.far_used);
  std::printf("[ 8 cascades ] last split pulled in from %.1f to %.1f m; %d of 64 caster draws culled\n",
              double(sh.far_requested), double(sh.far_used), culled);

  // Layered: the same casters per cascade and the same triangles, but one instanced draw per
  // mesh for all cascades at once, in one call.
  auto layered_scene = load_scene(
      content_dir() / "scenes" / "default.json",
      {"render.width=160", "render.height=90", "shadow.cascade_count=8", "shadow.layered=true",
       "shadow.fit_mode=crop"});
  ASSERT_TRUE(layered_scene.ok()) << layered_scene.error().to_string();
  auto lt = render_frames(*player_, *layered_scene, {});
  ASSERT_TRUE(lt.ok()) << lt.error().to_string();
  const render::FrameStats& ls = lt->last.stats;
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_EQ(ls.layer_casters[i], st.layer_casters[i]) << "cascade " << i;
    EXPECT_EQ(ls.layer_triangles[i], st.layer_triangles[i]) << "cascade " << i;
  }
  EXPECT_EQ(ls.shadow_instances, st.shadow_instances);
  EXPECT_EQ(ls.shadow_mesh_draws, int(all_meshes.size()));
  EXPECT_LT(ls.shadow_mesh_draws, st.shadow_mesh_draws);
  EXPECT_EQ(ls.shadow_draw_calls, 1);
  EXPECT_EQ(ls.shadow_triangles, st.shadow_triangles);
}

// Set-ups that used to be degenerate for one part or another: each renders without GL errors
// (TearDown) and with finite visibility in [0, 1].
class DegenerateSetups : public DefaultSceneTest,
                         public ::testing::WithParamInterface<Config> {};

void expect_sane_visibility(const Image& aov) {
  for (int y = 0; y < aov.height; ++y)
    for (int x = 0; x < aov.width; ++x) {
      const float v = aov.at(x, y, 7);
      ASSERT_TRUE(v >= 0.0f && v <= 1.0f) << x << "," << y << ": " << v;
      const float c = aov.at(x, y, 9);
      ASSERT_TRUE(c >= -1.0f && c < 8.0f) << c;
    }
}

TEST_P(DegenerateSetups, RenderWithoutErrors) {
  std::vector<std::string> sets = GetParam().sets;
  sets.push_back("render.width=160");
  sets.push_back("render.height=90");
  auto scene = load_scene(content_dir() / "scenes" / "default.json", sets);
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  auto t = render_frames(*player_, *scene, {});
  ASSERT_TRUE(t.ok()) << t.error().to_string();
  expect_sane_visibility(player_->renderer->read_aovs());
}

constexpr const char* kDown = "[-0.70710678,0,0,0.70710678]";  // local -Z to world -Y
INSTANTIATE_TEST_SUITE_P(
    Cascades, DegenerateSetups,
    ::testing::Values(
        Config{"light_straight_down", {std::string("sun.transform.rotation=") + kDown}},
        Config{"light_along_view", {std::string("sun.transform.rotation=") + kDown,
                                    std::string("camera.transform.rotation=") + kDown,
                                    "camera.transform.translation=[0,20,0]"}},
        Config{"light_along_view_crop", {std::string("sun.transform.rotation=") + kDown,
                                         std::string("camera.transform.rotation=") + kDown,
                                         "camera.transform.translation=[0,20,0]",
                                         "shadow.fit_mode=crop"}},
        Config{"near_1e-4_far_1e4", {"camera.camera.near=0.0001", "camera.camera.far=10000",
                                     "shadow.max_distance=0", "shadow.cascade_count=8"}},
        Config{"near_1e-4_far_1e4_crop", {"camera.camera.near=0.0001", "camera.camera.far=10000",
                                          "shadow.max_distance=0", "shadow.fit_mode=crop"}},
        Config{"camera_below_ground", {"camera.transform.translation=[0,-5,0]"}}),
    [](const auto& info) {
      std::string n = info.param.name;
      std::replace(n.begin(), n.end(), '-', '_');
      std::replace(n.begin(), n.end(), '.', '_');
      return n;
    });

// Scenes written on the fly: no geometry at all, and geometry that casts nothing.
TEST_F(DefaultSceneTest, EmptySceneAndSceneWithoutCastersRender) {
  const std::filesystem::path dir = testing_util::test_tmp();
  std::filesystem::create_directories(dir);
  const std::string light_and_camera = R"(
    { "name": "sun", "transform": { "direction": [0.5, -0.6, -0.45] },
      "light": { "type": "directional", "cast_shadows": true } },
    { "name": "camera", "transform": { "translation": [6, 4, 8], "look_at": [0, 0, 0] },
      "camera": { "near": 0.1, "far": 100 } })";
  const std::pair<const char*, std::string> scenes[] = {
      {"empty.json", R"({ "kaskad_scene": 1, "entities": [)" + light_and_camera + "] }"},
      {"no_casters.json", R"({ "kaskad_scene": 1, "entities": [
        { "name": "ground", "transform": { "scale": [20, 1, 20] }, "primitive": { "shape": "plane" },
          "renderer": { "cast_shadows": false } },
        { "name": "box", "transform": { "translation": [0, 0.5, 0] }, "primitive": { "shape": "box" },
          "renderer": { "cast_shadows": false } },)" + light_and_camera + "] }"}};
  for (const auto& [name, text] : scenes) {
    std::ofstream(dir / name) << text;
    auto scene = load_scene(dir / name, {"render.width=160", "render.height=90"});
    ASSERT_TRUE(scene.ok()) << scene.error().to_string();
    auto t = render_frames(*player_, *scene, {});
    ASSERT_TRUE(t.ok()) << name << ": " << t.error().to_string();
    const Image aov = player_->renderer->read_aovs();
    expect_sane_visibility(aov);
    for (int y = 0; y < aov.height; ++y)
      for (int x = 0; x < aov.width; ++x)
        if (aov.at(x, y, 8) > 0.5f) {
          ASSERT_EQ(aov.at(x, y, 7), 1.0f) << name;  // nothing casts
        }
    EXPECT_EQ(t->last.stats.shadow_draw_calls, 0) << name;
  }
}

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
  ASSERT_EQ(aov.channels, 14);
  ASSERT_EQ(aov.channel_names[9], "cascade");
  ASSERT_EQ(aov.channel_names[7], "visibility");
  ASSERT_EQ(aov.channel_names[10], "reflection.R");
  ASSERT_EQ(aov.channel_names[12], "reflection.B");
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
      ASSERT_EQ(aov.at(x, y, 10), 0.0f);  // no reflector in the default scene: C_t = 0
      ASSERT_EQ(aov.at(x, y, 13), 0.0f);
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
