

// The shader permutation system on the GPU: only used variants are compiled, variants match the
// uniform-driven über-shader oracle, pre-warm leaves nothing to compile, the binary cache is hit,
// and hot reload keeps the last good program.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "components/camera.h"
#include "components/transform.h"
#include "runtime/app/player.h"
#include "runtime/gpu/context.h"
#include "systems/frame.h"
#include "tests/render/headless_gl.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;
using render::Pass;
using render::VariantKey;

class PermutationTest : public HeadlessGlTest {
 protected:
  // A copy of content/shaders in the test tmp folder `name`: shaders a test edits and reloads.
  static fs::path shader_copy(const std::string& name) {
    const fs::path dir = testing_util::test_tmp() / name;
    fs::remove_all(dir);
    fs::copy(content_dir() / "shaders", dir, fs::copy_options::recursive);
    return dir;
  }
  static std::string text_of(const fs::path& file) {
    std::ifstream in(file);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  // Replaces the first `from` in `file` by `to` and moves its write time on by `seconds`
  // (reload_changed() compares times); false, changing nothing, when `from` is not in it.
  static bool replace_in(const fs::path& file, const std::string& from, const std::string& to,
                         int seconds) {
    std::string text = text_of(file);
    if (text.find(from) == std::string::npos) return false;
    text.replace(text.find(from), from.size(), to);
    std::ofstream(file, std::ios::trunc) << text;
    fs::last_write_time(file, fs::last_write_time(file) + std::chrono::seconds(seconds));
    return true;
  }

  static std::unique_ptr<render::Renderer> make_renderer(const fs::path& cache = {},
                                                         bool oracle = false,
                                                         const fs::path& shaders = content_dir() / "shaders") {
    render::RendererOptions o;
    o.shader_cache_dir = cache;
    o.uber_oracle = oracle;
    auto r = render::Renderer::create(shaders, o);
    EXPECT_TRUE(r.ok()) << r.error().to_string();
    return r.ok() ? std::move(r.value()) : nullptr;
  }
  static Scene scene(const std::string& name, std::vector<std::string> sets = {}) {
    sets.push_back("render.width=320");
    sets.push_back("render.height=180");
    auto s = load_scene(content_dir() / "scenes" / name, sets);
    EXPECT_TRUE(s.ok()) << s.error().to_string();
    return std::move(s.value());
  }
  // Renders `frames` frames with a bare renderer (no player) and returns the last colour image.
  static Image render(render::Renderer& r, Scene& s, int frames = 1, bool prewarm = false,
                      bool aovs = false, Image* aov = nullptr) {
    FrameContext ctx;
    ctx.width = s.render.width;
    ctx.height = s.render.height;
    ctx.write_aovs = aovs;
    if (prewarm) {
      EXPECT_TRUE(prewarm_frame(s, r, ctx).ok());
    }
    SystemState systems;
    FrameReport report;
    for (int i = 0; i < frames; ++i) {
      ctx.index = std::uint64_t(i);
      Status st = run_frame(s, r, ctx, systems, report);
      EXPECT_TRUE(st.ok()) << st.error().to_string();
      if (i == 0) r.shaders().first_frame_done();
    }
    r.finish();
    if (aov) *aov = r.read_aovs();
    return r.read_color();
  }

  // The largest colour and visibility differences between the variants and the über-shader
  // oracle rendering copies a and b of one scene (one frame each, with AOVs).
  struct OracleDifference {
    double colour = 0.0;
    float visibility = 0.0f;
  };
  static OracleDifference against_oracle(render::Renderer& variants, render::Renderer& oracle,
                                         Scene& a, Scene& b) {
    Image aov_v, aov_o;
    const Image v = render(variants, a, 1, false, true, &aov_v);
    const Image o = render(oracle, b, 1, false, true, &aov_o);
    OracleDifference d;
    EXPECT_EQ(v.pixels.size(), o.pixels.size());
    if (v.pixels.size() != o.pixels.size()) return {1e9, 1e9f};
    for (std::size_t i = 0; i < v.pixels.size(); ++i)
      d.colour = std::max(d.colour, double(std::abs(v.pixels[i] - o.pixels[i])));
    for (int y = 0; y < aov_v.height; ++y)
      for (int x = 0; x < aov_v.width; ++x)
        d.visibility = std::max(d.visibility, std::abs(aov_v.at(x, y, 7) - aov_o.at(x, y, 7)));
    return d;
  }
};

TEST_F(PermutationTest, CompilesExactlyTheCombinationsTheSceneUses) {
  Scene s = scene("materials.json");
  FrameContext ctx{320, 180, 0, false};
  const auto requests = render::required_programs(plan_frame(s, ctx));
  std::set<std::uint64_t> forward, depth;
  for (const auto& r : requests) (r.pass == Pass::forward ? forward : depth).insert(r.key.bits());
  // materials.json: ground (none), checker, bumpy metal, glow, foliage (alpha), textured+bumpy,
  // plain cone (no shadow receiving): 7 distinct forward keys, and the 6 that receive shadows
  // again reading the stored visibility (render.visibility_cache: still frames) and again
  // reprojecting it (render.visibility_reproject: a camera that moves); depth: opaque + alpha
  // mask.
  EXPECT_EQ(forward.size(), 7u + 6u + 6u);
  EXPECT_EQ(depth.size(), 2u);

  auto r = make_renderer();
  render(*r, s, 3);  // still frames: the second stores the visibility, the third reads it back
  EXPECT_EQ(r->shaders().built_keys(Pass::forward).size(), 7u + 6u);
  // A camera move: the frame reprojects what the still frames stored.
  s.world.view<Camera, Transform>().each([](ecs::Entity, const Camera& c, Transform& t) {
    if (c.active) t.translation += glm::vec3(0.1f, 0.0f, 0.0f);
  });
  render(*r, s, 1);
  EXPECT_TRUE(r->stats().visibility_reprojected);
  EXPECT_EQ(r->shaders().built_keys(Pass::forward).size(), forward.size());
  EXPECT_EQ(r->shaders().built_keys(Pass::depth).size(), depth.size());
  EXPECT_EQ(r->stats().shaders.programs_compiled, int(forward.size() + depth.size()));
  for (VariantKey k : r->shaders().built_keys(Pass::forward)) EXPECT_TRUE(forward.count(k.bits()));
}

TEST_F(PermutationTest, UnusedFeaturesAreNeverCompiled) {
  Scene s = scene("default.json");
  auto r = make_renderer();
  render(*r, s, 3);
  for (Pass pass : {Pass::forward, Pass::depth})
    for (VariantKey k : r->shaders().built_keys(pass)) {
      EXPECT_FALSE(k.has(VariantKey::kBaseColorTexture));
      EXPECT_FALSE(k.has(VariantKey::kNormalMap));
      EXPECT_FALSE(k.has(VariantKey::kEmissive));
      EXPECT_FALSE(k.has(VariantKey::kAlphaMask));
      EXPECT_FALSE(k.has(VariantKey::kReflectionCube));
      EXPECT_FALSE(k.has(VariantKey::kAovs));  // not asked for
    }
  // One forward program that looks the shadow maps up (and stores the visibility), one that
  // reads it back (still frames), one depth program.
  EXPECT_EQ(r->stats().shaders.programs_compiled, 3);
}

TEST_F(PermutationTest, EveryVariantMatchesTheUberShaderOracle) {
  for (const char* filter : {"pcf3x3", "none"}) {
    Scene a = scene("materials.json", {std::string("shadow.filter=") + filter});
    Scene b = scene("materials.json", {std::string("shadow.filter=") + filter});
    auto variants = make_renderer();
    auto oracle = make_renderer({}, true);
    const OracleDifference d = against_oracle(*variants, *oracle, a, b);
    EXPECT_LE(d.colour, 1.0 / 255.0 + 1e-6) << filter;
    EXPECT_LE(d.visibility, 1e-6f) << filter;
    // The oracle is one program per pass; the variants are many.
    EXPECT_EQ(oracle->shaders().built_keys(Pass::forward).size(), 1u);
    EXPECT_GT(variants->shaders().built_keys(Pass::forward).size(), 5u);
  }
}

// The glTF material inputs (occlusion, metallic-roughness and emissive textures, texture
// transforms, also on an alpha-masked caster) render the same through their variants as through
// the oracle.
TEST_F(PermutationTest, NewMaterialInputsMatchTheUberShaderOracle) {
  const fs::path dir = testing_util::test_tmp();
  fs::create_directories(dir);
  const std::string textures = (content_dir() / "materials" / "textures").string() + "/";
  std::ofstream(dir / "orm.json") << R"({ "features": ["base_color_texture", "occlusion_texture",
      "metallic_roughness_texture", "texture_transform"], "parameters": { "occlusion_strength": 0.7,
      "metallic": 1, "roughness": 1, "uv_scale": [2, 3], "uv_rotation": 0.4, "uv_offset": [0.1, 0.2] },
    "textures": { "base_color": ")" << textures << R"(checker.png", "occlusion": ")" << textures
                                  << R"(checker.png", "metallic_roughness": ")" << textures
                                  << R"(checker.png" } })";
  std::ofstream(dir / "glow.json") << R"({ "features": ["emissive", "emissive_texture"],
    "parameters": { "base_color": [0, 0, 0, 1], "emissive": [0.8, 0.5, 0.3] },
    "textures": { "emissive": ")" << textures << R"(checker.png" } })";
  std::ofstream(dir / "leaf.json") << R"({ "features": ["base_color_texture", "alpha_mask",
      "texture_transform"], "parameters": { "double_sided": true, "uv_scale": [1.5, 1.5],
      "uv_rotation": 0.8 }, "textures": { "base_color": ")" << textures << R"(cutout.png" } })";
  std::ofstream(dir / "scene.json") << R"({ "kaskad_scene": 1,
    "render": { "ambient": [0.3, 0.3, 0.35] }, "shadow": { "filter": "pcf3x3" },
    "entities": [
      { "name": "ground", "transform": { "scale": [12, 1, 12] }, "primitive": { "shape": "plane" },
        "material": { "base_color": [0.6, 0.6, 0.58, 1], "roughness": 0.9 } },
      { "name": "box", "transform": { "translation": [-1.5, 0.6, 0], "scale": [1.2, 1.2, 1.2] },
        "primitive": { "shape": "box" }, "material": { "file": "orm.json" } },
      { "name": "panel", "transform": { "translation": [0.5, 0.8, -0.8], "scale": [1.4, 1.6, 0.1] },
        "primitive": { "shape": "box" }, "material": { "file": "glow.json" } },
      { "name": "leaf", "transform": { "translation": [1.8, 1.0, 0.6], "euler_deg": [60, -35, 0],
          "scale": [1.8, 1.8, 1.8] }, "primitive": { "shape": "plane" },
        "material": { "file": "leaf.json" } },
      { "name": "sun", "transform": { "direction": [0.4, -0.7, -0.55] },
        "light": { "type": "directional", "intensity": 5, "cast_shadows": true } },
      { "name": "camera", "transform": { "translation": [0, 4, 7], "look_at": [0, 0.6, 0] },
        "camera": { "fov_y_deg": 45, "near": 0.1, "far": 100, "active": true } } ] })";
  auto load = [&] {
    auto s = load_scene(dir / "scene.json", {"render.width=320", "render.height=180"});
    EXPECT_TRUE(s.ok()) << s.error().to_string();
    return std::move(s.value());
  };
  Scene a = load(), b = load();
  auto variants = make_renderer();
  auto oracle = make_renderer({}, true);
  const OracleDifference d = against_oracle(*variants, *oracle, a, b);
  EXPECT_LE(d.colour, 1.0 / 255.0 + 1e-6);
  EXPECT_LE(d.visibility, 1e-6f);  // the transformed cut-out's shadow too
  // The cut-out's shadow program has its transform (and nothing else of the material).
  std::set<std::uint64_t> depth;
  for (VariantKey k : variants->shaders().built_keys(Pass::depth)) depth.insert(k.bits());
  EXPECT_TRUE(depth.count(
      VariantKey().set(VariantKey::kAlphaMask, 1).set(VariantKey::kTextureTransform, 1).bits()));
}

TEST_F(PermutationTest, PrewarmLeavesNothingToCompileAndTheCacheIsHit) {
  const fs::path cache = testing_util::test_tmp() / "perm_cache";
  fs::remove_all(cache);
  Scene s = scene("materials.json");
  auto cold = make_renderer(cache);
  ASSERT_TRUE(cold->shaders().binary_cache_supported());
  render(*cold, s, 20, /*prewarm=*/true);
  const auto& st = cold->stats().shaders;
  EXPECT_GT(st.programs_compiled, 0);
  EXPECT_EQ(st.runtime_compiles, 0);
  EXPECT_EQ(st.cache_hits, 0);

  Scene s2 = scene("materials.json");
  auto warm = make_renderer(cache);
  render(*warm, s2, 2, true);
  EXPECT_EQ(warm->stats().shaders.programs_compiled, 0);
  EXPECT_EQ(warm->stats().shaders.cache_hits, st.programs_compiled);
  EXPECT_EQ(warm->stats().shaders.runtime_compiles, 0);

  // A corrupt cache file is rebuilt from source, not trusted.
  for (const auto& f : fs::directory_iterator(cache)) std::ofstream(f.path(), std::ios::binary | std::ios::trunc) << "junk";
  Scene s3 = scene("materials.json");
  auto rebuilt = make_renderer(cache);
  render(*rebuilt, s3, 1, true);
  EXPECT_EQ(rebuilt->stats().shaders.cache_hits, 0);
  EXPECT_EQ(rebuilt->stats().shaders.programs_compiled, st.programs_compiled);
}

TEST_F(PermutationTest, HotReloadKeepsTheLastGoodProgramAndMapsErrors) {
  const fs::path dir = shader_copy("hot_shaders");
  Scene s = scene("default.json");
  auto r = make_renderer({}, false, dir);
  const Image before = render(*r, s);

  // Break common.glsl (included by every program): each program reports the included file.
  const fs::path common = dir / "common.glsl";
  const std::string text = text_of(common);
  const int lines = int(std::count(text.begin(), text.end(), '\n'));
  std::ofstream(common, std::ios::app) << "this is not glsl;\n";
  fs::last_write_time(common, fs::last_write_time(common) + std::chrono::seconds(2));
  const auto errors = r->shaders().reload_changed();
  ASSERT_EQ(errors.size(), r->shaders().program_count());
  for (const auto& e : errors)
    EXPECT_NE(e.to_string().find("common.glsl:" + std::to_string(lines + 1)), std::string::npos) << e.to_string();
  // Still renders, with the last good programs.
  const Image during = render(*r, s);
  EXPECT_EQ(during.pixels, before.pixels);

  // Fix it, with a visible change: everything gets brighter.
  std::ofstream(common, std::ios::trunc) << text;
  fs::last_write_time(common, fs::last_write_time(common) + std::chrono::seconds(4));
  ASSERT_TRUE(replace_in(dir / "forward.frag",
                         "o_color = vec4(tone_map(color * u_frame.x), coverage);",
                         "o_color = vec4(tone_map(color * u_frame.x) + 0.2, coverage);", 4));
  EXPECT_TRUE(r->shaders().reload_changed().empty());
  EXPECT_EQ(r->stats().shaders.runtime_compiles, 0);  // reloads are not runtime compiles
  const Image after = render(*r, s);
  EXPECT_GT(r->shaders().stats().reloads, 0);
  // The ground at the bottom centre is drawn by the reloaded program (the sky is a clear colour).
  const int x = after.width / 2, y = after.height - 1;
  EXPECT_GT(after.at(x, y, 0), before.at(x, y, 0) + 0.05f);
}

// An edited shadow lookup shows at once under a still camera: a hot reload invalidates the shadow
// layers and the stored visibility (render.visibility_cache), which would otherwise be kept
// because nothing in the scene moved. Fails when the reload count is left out of either's inputs.
TEST_F(PermutationTest, HotReloadOfTheShadowCodeShowsUnderAStillCamera) {
  const fs::path dir = shader_copy("hot_shadow_shaders");
  Scene s = scene("default.json");
  auto r = make_renderer({}, false, dir);
  render(*r, s);
  render(*r, s);  // the same frame again: stores its visibility
  const Image before = render(*r, s);
  EXPECT_TRUE(r->stats().visibility_reused);  // still: read back, every layer kept
  EXPECT_EQ(r->stats().shadow_layers_rendered, 0u);
  // Edit the lookup: no shadows at all.
  ASSERT_TRUE(replace_in(dir / "shadow_filter.glsl", "  return sum / 9.0;", "  return 1.0;", 4));
  EXPECT_TRUE(r->shaders().reload_changed().empty());
  const Image after = render(*r, s);
  EXPECT_FALSE(r->stats().visibility_reused);
  EXPECT_NE(r->stats().shadow_layers_rendered, 0u);
  // Shadowed ground got brighter; nothing got darker.
  int brighter = 0;
  for (std::size_t i = 0; i < after.pixels.size(); ++i) {
    brighter += after.pixels[i] > before.pixels[i] + 0.05f;
    EXPECT_GE(after.pixels[i], before.pixels[i] - 1e-6f) << "value " << i;
    if (after.pixels[i] < before.pixels[i] - 1e-6f) break;
  }
  EXPECT_GT(brighter, 1000);
}

}  // namespace
}  // namespace kaskad

namespace kaskad {
namespace {

// One renderer drawing two scenes in turn (as `kaskad bench` and the editor do) must not reuse
// the first scene's GPU meshes for the second scene's mesh ids.
TEST_F(PermutationTest, ARendererDrawsEachSceneWithItsOwnMeshes) {
  Scene first = PermutationTest::scene("terrain.json");  // mesh 0: a heightfield, not a plane
  Scene def_a = PermutationTest::scene("default.json");
  auto fresh = make_renderer();
  const Image expected = render(*fresh, def_a);
  auto shared = make_renderer();
  render(*shared, first);
  Scene def_b = PermutationTest::scene("default.json");
  const Image got = render(*shared, def_b);
  EXPECT_EQ(got.pixels, expected.pixels);
}

}  // namespace
}  // namespace kaskad
