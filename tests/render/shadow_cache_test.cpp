// Shadow caching: a shadow-map layer is re-rendered only when what it is drawn from
// changed (its matrix, its casters, a caster's matrix, bias, pass mode); otherwise it keeps its
// depth. Checked on the default scene: a repeated frame re-renders nothing and keeps the same
// maps; after a caster, the sun or the camera moves, the maps (kept and re-rendered layers
// together) and the visibility AOV are exactly those drawn with nothing cached for the same scene
// state. Fails when the layer's inputs leave out the caster matrices or the light matrix.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "components/camera.h"
#include "components/mesh_renderer.h"
#include "components/name.h"
#include "components/transform.h"
#include "runtime/app/player.h"
#include "tests/render/player_fixture.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

class ShadowCacheTest : public PlayerTest {
 protected:
  static ecs::Entity named(const Scene& s, const std::string& name) {
    ecs::Entity found;
    s.world.view<Name>().each([&](ecs::Entity e, const Name& n) {
      if (n.value == name) found = e;
    });
    return found;
  }

  struct Frame {
    render::FrameStats stats;
    Image raw_map;                  // every layer's depth
    std::vector<float> map;         // what lookups can read of it (read_part())
    std::vector<float> visibility;  // the AOV's visibility channel
  };

  static Frame render(Player& player, Scene& scene) {
    Frame f;
    RenderRun run;
    run.width = 320;
    run.height = 180;
    auto t = render_frames(player, scene, run);
    EXPECT_TRUE(t.ok()) << t.error().to_string();
    if (!t.ok()) return f;
    f.stats = t->last.stats;
    f.raw_map = player.renderer->read_shadow_map();
    f.map = read_part(f.raw_map, f.stats.layer_rect);
    const Image aov = player.renderer->read_aovs();
    for (int y = 0; y < aov.height; ++y)
      for (int x = 0; x < aov.width; ++x) f.visibility.push_back(aov.at(x, y, 7));
    return f;
  }

  // The same scene state drawn with nothing cached: the scene loaded again (new assets, so no
  // layer's inputs match) with `scene`'s transforms and box_floating's renderer, into new map
  // storage (a frame with another map size first), so that nothing of an earlier frame's maps
  // can survive in it.
  static Frame fresh(const Scene& scene) {
    auto other = load_scene(content_dir() / "scenes" / "default.json", {"shadow.map_size=1024"});
    EXPECT_TRUE(other.ok()) << other.error().to_string();
    if (other.ok()) render(*player_, *other);
    auto copy = load_scene(content_dir() / "scenes" / "default.json", {});
    EXPECT_TRUE(copy.ok()) << copy.error().to_string();
    if (!copy.ok()) return {};
    for (const char* name : {"box_floating", "camera", "sun"})
      copy->world.get<Transform>(named(*copy, name)) =
          scene.world.get<Transform>(named(scene, name));
    copy->world.get<MeshRenderer>(named(*copy, "box_floating")) =
        scene.world.get<MeshRenderer>(named(scene, "box_floating"));
    Frame f = render(*player_, *copy);
    EXPECT_EQ(f.stats.shadow_layers_rendered, (1u << f.stats.shadow_layers) - 1u);
    return f;
  }
};

TEST_F(ShadowCacheTest, LayersAreRedrawnOnlyWhenTheirInputsChange) {
  auto loaded = load_scene(content_dir() / "scenes" / "default.json", {});
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  Scene& scene = *loaded;

  const Frame first = render(*player_, scene);
  ASSERT_EQ(first.stats.shadow_layers, 4);
  EXPECT_EQ(first.stats.shadow_layers_rendered, 0xfu);
  // A real map: lit and shadowed receivers.
  EXPECT_NE(std::count(first.visibility.begin(), first.visibility.end(), 1.0f), 0);
  EXPECT_NE(std::count(first.visibility.begin(), first.visibility.end(), 0.0f), 0);
  // Nothing moved: every layer kept, the same maps and visibility, the same caster counts.
  const Frame still = render(*player_, scene);
  EXPECT_EQ(still.stats.shadow_layers_rendered, 0u);
  EXPECT_EQ(still.map, first.map);
  EXPECT_EQ(still.visibility, first.visibility);
  EXPECT_GT(first.stats.shadow_draw_calls, 0);
  EXPECT_EQ(still.stats.shadow_draw_calls, 0);  // nothing recorded
  EXPECT_EQ(still.stats.shadow_instances, first.stats.shadow_instances);
  EXPECT_EQ(still.stats.layer_casters, first.stats.layer_casters);

  // A caster moves: the layers that hold it are redrawn, and the maps are those drawn with
  // nothing cached.
  Transform& box = scene.world.get<Transform>(named(scene, "box_floating"));
  box.translation += glm::vec3(0.3f, 0.2f, 0.1f);
  const Frame moved = render(*player_, scene);
  EXPECT_NE(moved.stats.shadow_layers_rendered, 0u);
  EXPECT_NE(moved.map, first.map);
  const Frame moved_fresh = fresh(scene);
  EXPECT_EQ(moved.map, moved_fresh.map);
  EXPECT_EQ(moved.visibility, moved_fresh.visibility);

  // Back to the cached scene, unchanged since its last frame: its assets differ from the fresh
  // copy's, so every layer is redrawn once, then kept again.
  EXPECT_EQ(render(*player_, scene).map, moved.map);
  EXPECT_EQ(render(*player_, scene).stats.shadow_layers_rendered, 0u);

  // The sun turns a little: same splits and casters, new light matrices.
  Transform& sun = scene.world.get<Transform>(named(scene, "sun"));
  sun.rotation = glm::angleAxis(0.03f, glm::vec3(0.0f, 1.0f, 0.0f)) * sun.rotation;
  const Frame turned = render(*player_, scene);
  EXPECT_EQ(turned.stats.shadow_layers_rendered, 0xfu);
  const Frame turned_fresh = fresh(scene);
  EXPECT_EQ(turned.map, turned_fresh.map);
  EXPECT_EQ(turned.visibility, turned_fresh.visibility);
  render(*player_, scene);

  // The camera moves: the cascades move with it and are redrawn; again as drawn from scratch.
  // Without scrolling (ScrollTest), to the bit.
  scene.render.shadow_scroll = false;
  scene.world.get<Transform>(named(scene, "camera")).translation += glm::vec3(0.7f, 0.0f, -0.4f);
  const Frame walked = render(*player_, scene);
  EXPECT_NE(walked.stats.shadow_layers_rendered, 0u);
  EXPECT_EQ(walked.stats.shadow_layers_scrolled, 0u);
  const Frame walked_fresh = fresh(scene);
  EXPECT_EQ(walked.map, walked_fresh.map);
  EXPECT_EQ(walked.visibility, walked_fresh.visibility);
}

// A caster that moves under a still camera redraws only the texels of its old and new boxes
// (ShadowMapPass, moved_caster_rects()): each frame's maps and visibility are those drawn with
// nothing cached, bit for bit, while the layers draw a small part of their texels. Also when it
// stops casting (its old box alone). Fails when the old box is left out (its stale shadow stays
// in the map), or the new one.
TEST_F(ShadowCacheTest, AMovedCasterRedrawsOnlyItsTexels) {
  auto loaded = load_scene(content_dir() / "scenes" / "default.json", {});
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  Scene& scene = *loaded;
  const Frame first = render(*player_, scene);
  ASSERT_EQ(first.stats.shadow_layers, 4);
  std::int64_t needed = 0;  // the texels lookups read, over every layer
  for (const glm::ivec4& r : first.stats.layer_rect) needed += std::int64_t(r.z - r.x) * (r.w - r.y);
  ASSERT_GT(needed, 0);
  const ecs::Entity box = named(scene, "box_floating");
  for (int step = 0; step < 4; ++step) {
    const bool last = step == 3;
    if (last)
      scene.world.get<MeshRenderer>(box).cast_shadows = false;
    else
      scene.world.get<Transform>(box).translation += glm::vec3(0.12f, 0.05f, -0.08f);
    const Frame moved = render(*player_, scene);
    EXPECT_NE(moved.stats.shadow_layers_patched, 0u) << "step " << step;
    EXPECT_EQ(moved.stats.shadow_layers_scrolled, 0u) << "step " << step;
    EXPECT_LT(moved.stats.shadow_texels_drawn * 5, needed) << "step " << step;
    std::printf("[ step %d ] %d layers patched, %lld of %lld needed texels drawn (%.1f%%)\n", step,
                std::popcount(moved.stats.shadow_layers_patched),
                static_cast<long long>(moved.stats.shadow_texels_drawn),
                static_cast<long long>(needed), 100.0 * double(moved.stats.shadow_texels_drawn) / double(needed));
    const Frame moved_fresh = fresh(scene);
    EXPECT_EQ(moved.map, moved_fresh.map) << "step " << step;
    EXPECT_EQ(moved.visibility, moved_fresh.visibility) << "step " << step;
    // The cached scene again: its assets differ from the fresh copy's, so it redraws once.
    render(*player_, scene);
  }
}

// vsm/evsm (MomentsPass): a layer's moments are recomputed exactly when the shadow pass redraws
// it; a repeated frame recomputes none and shades the same. Fails when the moments pass
// recomputes every layer every frame, or keeps a layer the shadow pass redrew.
TEST_F(ShadowCacheTest, MomentsAreRecomputedForTheRedrawnLayersOnly) {
  for (const char* technique : {"vsm", "evsm"}) {
    // Far cascades on a 4-frame cadence, so that a moving caster redraws only some layers.
    auto loaded = load_scene(content_dir() / "scenes" / "default.json",
                             {std::string("shadow.technique=") + technique,
                              "shadow.far_cascade_interval=4"});
    ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
    Scene& scene = *loaded;
    const Frame first = render(*player_, scene);
    EXPECT_EQ(first.stats.shadow_layers_rendered, 0xfu) << technique;
    EXPECT_EQ(first.stats.vsm_layers_computed, 0xfu) << technique;
    const Frame still = render(*player_, scene);
    EXPECT_EQ(still.stats.vsm_layers_computed, 0u) << technique;
    EXPECT_EQ(still.visibility, first.visibility) << technique;
    scene.world.get<Transform>(named(scene, "box_floating")).translation +=
        glm::vec3(0.3f, 0.2f, 0.1f);
    const Frame moved = render(*player_, scene);
    EXPECT_NE(moved.stats.shadow_layers_rendered, 0u) << technique;
    EXPECT_NE(moved.stats.shadow_layers_rendered, 0xfu) << technique << ": only some layers";
    EXPECT_EQ(moved.stats.vsm_layers_computed, moved.stats.shadow_layers_rendered) << technique;
    std::printf("[ %s ] moments recomputed: first 0x%x, still 0x%x, after a caster moved 0x%x "
                "(shadow layers redrawn 0x%x)\n",
                technique, first.stats.vsm_layers_computed, still.stats.vsm_layers_computed,
                moved.stats.vsm_layers_computed, moved.stats.shadow_layers_rendered);
  }
}

// The layered pass draws all of a light's layers in one pass: it redraws all of them or none.
TEST_F(ShadowCacheTest, TheLayeredPassRedrawsAllLayersOrNone) {
  auto loaded = load_scene(content_dir() / "scenes" / "default.json", {"shadow.layered=true"});
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  Scene& scene = *loaded;
  const Frame first = render(*player_, scene);
  EXPECT_EQ(first.stats.shadow_layers_rendered, 0xfu);
  const Frame still = render(*player_, scene);
  EXPECT_EQ(still.stats.shadow_layers_rendered, 0u);
  EXPECT_EQ(still.map, first.map);
  Transform& box = scene.world.get<Transform>(named(scene, "box_floating"));
  box.translation += glm::vec3(0.3f, 0.2f, 0.1f);
  const Frame moved = render(*player_, scene);
  EXPECT_EQ(moved.stats.shadow_layers_rendered, 0xfu);
  // Against one pass per layer drawn from scratch: the same maps (LocalLightTest's
  // LayeredPassWritesTheSameMapsAsOnePassPerLayer), through the other code path.
  const Frame moved_fresh = fresh(scene);
  // Layered layers are drawn whole; one pass per layer draws what lookups read.
  EXPECT_EQ(read_part(moved.raw_map, moved_fresh.stats.layer_rect), moved_fresh.map);
  EXPECT_EQ(moved.visibility, moved_fresh.visibility);
}

// render.shadow_cache=false draws every layer every frame, with the same maps as the cache keeps.
TEST_F(ShadowCacheTest, CacheOffDrawsEveryLayerEveryFrame) {
  auto cached = load_scene(content_dir() / "scenes" / "default.json", {});
  auto uncached = load_scene(content_dir() / "scenes" / "default.json", {"render.shadow_cache=false"});
  ASSERT_TRUE(cached.ok() && uncached.ok());
  render(*player_, *cached);
  const Frame kept = render(*player_, *cached);
  EXPECT_EQ(kept.stats.shadow_layers_rendered, 0u);
  render(*player_, *uncached);
  const Frame drawn = render(*player_, *uncached);
  EXPECT_EQ(drawn.stats.shadow_layers_rendered, 0xfu);
  EXPECT_GT(drawn.stats.shadow_draw_calls, 0);
  EXPECT_EQ(drawn.map, kept.map);
  EXPECT_EQ(drawn.visibility, kept.visibility);
}

// Casters culled by receivers (shadow.cull_by_receivers) and layers drawn only where receivers
// read them (shadow.scissor_to_receivers, which also leaves out casters outside those texels)
// change no pixel of the default scene: colour and every
// AOV equal those drawn with both off, with the camera still, walking (stable cascades reuse
// layers drawn over larger rectangles) and turning, and they do less: the ground is left out of
// some cascade and some layer is drawn in part. The same on the probes' scene, whose faces read
// the maps anywhere (whole layers are drawn on capture frames), and on the terrain.
TEST_F(ShadowCacheTest, ReceiverCullingAndScissorChangeNoPixel) {
  struct Case {
    const char* scene;
    const char* camera;
  };
  for (const Case& c : {Case{"default.json", "camera"}, Case{"reflections.json", "camera"},
                        Case{"terrain.json", "camera"}}) {
    std::array<std::vector<Image>, 2> frames;
    std::array<std::vector<render::FrameStats>, 2> stats;
    for (int on = 1; on >= 0; --on) {
      // New map storage first, so no depth of an earlier run survives outside what is drawn.
      auto other = load_scene(content_dir() / "scenes" / "default.json", {"shadow.map_size=256"});
      ASSERT_TRUE(other.ok()) << other.error().to_string();
      render(*player_, *other);
      const std::string flag = on ? "true" : "false";
      // Without scrolling, which draws layers in part either way (ScrollTest).
      auto loaded = load_scene(content_dir() / "scenes" / c.scene,
                               {"shadow.cull_by_receivers=" + flag,
                                "shadow.scissor_to_receivers=" + flag, "render.shadow_scroll=false"});
      ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
      Scene& scene = *loaded;
      Transform& cam = scene.world.get<Transform>(named(scene, c.camera));
      for (int step = 0; step < 6; ++step) {
        if (step >= 2 && step < 4) cam.translation += glm::vec3(0.05f, 0.0f, -0.03f);
        if (step >= 4) cam.rotation = glm::angleAxis(0.04f, glm::vec3(0, 1, 0)) * cam.rotation;
        RenderRun run;
        run.width = 320;
        run.height = 180;
        run.frames = 1;
        auto t = render_frames(*player_, scene, run);
        ASSERT_TRUE(t.ok()) << t.error().to_string();
        stats[std::size_t(on)].push_back(t->last.stats);
        frames[std::size_t(on)].push_back(player_->renderer->read_color());
        frames[std::size_t(on)].push_back(player_->renderer->read_aovs());
      }
    }
    for (std::size_t i = 0; i < frames[0].size(); ++i)
      EXPECT_EQ(frames[0][i].pixels, frames[1][i].pixels) << c.scene << ", image " << i;
    int fewer_casters = 0, part_drawn = 0, rect_culled = 0;
    for (std::size_t f = 0; f < stats[0].size(); ++f) {
      EXPECT_EQ(stats[0][f].shadow_rect_culled, 0) << c.scene << ", frame " << f;
      rect_culled += stats[1][f].shadow_rect_culled;
    }
    for (std::size_t f = 0; f < stats[0].size(); ++f)
      for (int l = 0; l < stats[0][f].shadow_layers; ++l) {
        const auto li = std::size_t(l);
        fewer_casters += stats[1][f].layer_casters[li] < stats[0][f].layer_casters[li];
        const glm::ivec4 r = stats[1][f].layer_rect[li], whole = stats[0][f].layer_rect[li];
        part_drawn += (r.z - r.x) * (r.w - r.y) < (whole.z - whole.x) * (whole.w - whole.y);
      }
    EXPECT_GT(fewer_casters, 0) << c.scene;
    EXPECT_GT(part_drawn, 0) << c.scene;
    // Casters whose boxes miss a part-drawn layer's texels are left out of it: on the terrain,
    // where cascades are drawn over a quarter to a half of their texels (every caster of the
    // small default scene meets every rectangle).
    if (std::string(c.scene) == "terrain.json") {
      EXPECT_GT(rect_culled, 0) << c.scene;
    }
  }
}

// shadow.far_cascade_interval = 3 with a caster moving under a still camera: cascade 0 is
// redrawn every frame, the far cascades at most every third frame (their shadows lag, so some
// frame differs from the interval-1 run), and a few frames after the caster stops the images
// are exactly those of interval 1 again.
TEST_F(ShadowCacheTest, FarCascadesAreRedrawnEveryKthFrame) {
  std::array<std::vector<std::vector<float>>, 2> visibility;
  std::array<std::array<int, kMaxShadowLayers>, 2> redraws{};
  const int intervals[2] = {1, 3};
  for (int run = 0; run < 2; ++run) {
    auto loaded = load_scene(content_dir() / "scenes" / "default.json",
                             {"shadow.far_cascade_interval=" + std::to_string(intervals[run])});
    ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
    Scene& scene = *loaded;
    render(*player_, scene);
    Transform& box = scene.world.get<Transform>(named(scene, "box_floating"));
    for (int f = 0; f < 12; ++f) {
      if (f < 9) box.translation += glm::vec3(0.05f, 0.0f, 0.03f);
      const Frame frame = render(*player_, scene);
      for (int l = 0; l < frame.stats.shadow_layers; ++l)
        redraws[std::size_t(run)][std::size_t(l)] += (frame.stats.shadow_layers_rendered >> l) & 1u;
      visibility[std::size_t(run)].push_back(frame.visibility);
    }
  }
  EXPECT_EQ(redraws[0][0], 9);
  EXPECT_EQ(redraws[1][0], 9);  // cascade 0: every frame the caster moved
  for (int l = 1; l < 4; ++l) {
    EXPECT_LE(redraws[1][std::size_t(l)], 4) << "layer " << l;
    if (redraws[0][std::size_t(l)] > 0) {
      EXPECT_LT(redraws[1][std::size_t(l)], redraws[0][std::size_t(l)]) << "layer " << l;
    }
  }
  int lagging = 0;
  for (std::size_t f = 0; f < 9; ++f) lagging += visibility[0][f] != visibility[1][f];
  EXPECT_GT(lagging, 0) << "the far cascades should lag while the caster moves";
  EXPECT_EQ(visibility[0].back(), visibility[1].back());
}

// render.shadow_scroll: under a camera that walks across the sun, stable cascades that moved by
// whole texels keep their depth (the texture scrolls, nothing is copied) and draw only the texels
// that came into view, and every frame shades as the same frames drawn without scrolling: the same
// visibility at every pixel but a few where the redrawn depth differs by rasterisation rounding,
// and the colour within one 8-bit step elsewhere. On a field of casters that the camera walks
// over (the texels coming into view hold shadows that are seen at once), the default scene with
// a caster moving on the way (its layers are redrawn whole), the probes' scene (faces read the
// maps anywhere: whole layers on capture frames) and the terrain.
TEST_F(ShadowCacheTest, ScrolledLayersShadeAsRedrawnOnes) {
  // The field around `centre` (x and z), the sun's entity off the origin (its position is the
  // light view's origin): 4 km away, the light matrices' translations are in the thousands and
  // carry the rounding of float products; the layers must scroll there too.
  auto write_field = [](const fs::path& file, double centre) {
    std::ofstream out(file);
    out << R"({ "kaskad_scene": 1, "render": { "ground": "none" },
      "shadow": { "map_size": 1024, "cascade_count": 4, "fit_mode": "stable" },
      "entities": [
        { "name": "ground", "transform": { "translation": [)" << centre << ", 0, " << centre
        << R"(], "scale": [80, 1, 80] }, "primitive": { "shape": "plane" } },
        { "name": "sun", "transform": { "translation": [17.3, 40.1, -9.7],
                                        "direction": [0.5, -0.6, -0.45] },
          "light": { "type": "directional", "cast_shadows": true } },
        { "name": "camera", "transform": { "translation": [)" << centre - 20 << ", 3, " << centre
        << R"(], "look_at": [)" << centre - 12 << ", 0, " << centre - 2 << R"(] },
          "camera": { "fov_y_deg": 60, "near": 0.1, "far": 60, "active": true } })";
    for (int i = 0; i < 26 * 26; ++i)
      out << R"(, { "transform": { "translation": [)" << centre - 37.5 + 3.0 * (i % 26) << ", 0.5, "
          << centre - 37.5 + 3.0 * (i / 26) << R"(], "euler_deg": [0, )" << (i * 37) % 90
          << R"(, 0] }, "primitive": { "shape": "box" } })";
    out << "] }";
  };
  const fs::path field = testing_util::test_tmp() / "field.json";
  const fs::path far_field = testing_util::test_tmp() / "far_field.json";
  write_field(field, 0.0);
  write_field(far_field, 4000.0);
  for (const std::string& name : {field.string(), far_field.string(), std::string("default.json"),
                                 std::string("terrain.json"), std::string("reflections.json")}) {
    SCOPED_TRACE(name);
    struct Run {
      std::vector<std::vector<float>> visibility;
      std::vector<Image> color;
      std::vector<render::FrameStats> stats;
    };
    std::array<Run, 2> runs;  // scrolling off, on
    for (int on = 0; on < 2; ++on) {
      auto other = load_scene(content_dir() / "scenes" / "default.json", {"shadow.map_size=256"});
      ASSERT_TRUE(other.ok()) << other.error().to_string();
      render(*player_, *other);  // new map storage: nothing of the other run survives
      const fs::path file = fs::path(name).is_absolute() ? fs::path(name) : content_dir() / "scenes" / name;
      auto loaded = load_scene(file,
                               {std::string("render.shadow_scroll=") + (on ? "true" : "false")});
      ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
      Scene& scene = *loaded;
      Transform& cam = scene.world.get<Transform>(named(scene, "camera"));
      ecs::Entity caster = ecs::kNullEntity;
      if (name == "default.json") caster = named(scene, "box_floating");
      for (int f = 0; f < 12; ++f) {
        // Across the sun (direction (0.5, -0.6, -0.45)): the cascades' depth ranges stay, so
        // the layers scroll frame after frame and the texels they drew come into the view.
        cam.translation += 0.4f * glm::normalize(glm::vec3(0.45f, 0.0f, 0.5f));
        if (f == 7 && caster.valid())
          scene.world.get<Transform>(caster).translation += glm::vec3(0.1f, 0.0f, 0.0f);
        const Frame fr = render(*player_, scene);
        runs[std::size_t(on)].visibility.push_back(fr.visibility);
        runs[std::size_t(on)].color.push_back(player_->renderer->read_color());
        runs[std::size_t(on)].stats.push_back(fr.stats);
      }
    }
    std::int64_t texels[2] = {0, 0};
    int scrolled = 0, most_differ = 0, most_far_off = 0;
    for (std::size_t f = 0; f < runs[0].stats.size(); ++f) {
      EXPECT_EQ(runs[0].stats[f].shadow_layers_scrolled, 0u);
      scrolled += runs[1].stats[f].shadow_layers_scrolled != 0;
      for (int on = 0; on < 2; ++on) texels[on] += runs[std::size_t(on)].stats[f].shadow_texels_drawn;
      const std::vector<float>& a = runs[0].visibility[f];
      const std::vector<float>& b = runs[1].visibility[f];
      ASSERT_EQ(a.size(), b.size());
      int differ = 0;
      for (std::size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i];
      EXPECT_LE(differ, int(a.size() / 2000)) << "frame " << f;  // 0.05% of the pixels
      most_differ = std::max(most_differ, differ);
      const Image& ca = runs[0].color[f];
      const Image& cb = runs[1].color[f];
      ASSERT_EQ(ca.pixels.size(), cb.pixels.size());
      int far_off = 0;
      for (std::size_t i = 0; i < ca.pixels.size(); ++i)
        far_off += std::abs(ca.pixels[i] - cb.pixels[i]) > 1.5f / 255.0f;
      EXPECT_LE(far_off, 3 * int(a.size() / 2000)) << "frame " << f;
      most_far_off = std::max(most_far_off, far_off);
    }
    // Every frame moves the cascades: most scroll, and draw a small part of what redrawing does
    // (the probes' scene less so: its capture frames draw whole layers either way).
    EXPECT_GE(scrolled, 6);
    if (name == "reflections.json") {
      EXPECT_LT(texels[1], texels[0]);
    } else {
      EXPECT_LT(texels[1] * 3, texels[0]);
    }
    std::printf("%s: %d of %zu frames scrolled; texels drawn %lld scrolling, %lld redrawing; at "
                "most %d pixels' visibility and %d colour values (of %zu) differ in a frame\n",
                fs::path(name).filename().c_str(), scrolled, runs[1].stats.size(), (long long)texels[1], (long long)texels[0],
                most_differ, most_far_off, runs[0].visibility[0].size());
  }
}

// A caster can join a layer without moving and without the layer's matrix moving: with
// shadow.cull_by_receivers it is assigned by the receivers the slice serves. Here a box (which
// receives nothing) hangs under a platform (a receiver that casts nothing), below every
// receiver: it shadows none and is left out. Then the floor under it, inside the platform's rectangle in the map, starts to
// receive shadows: the box joins the layer, and its shadow falls on texels the layer kept. The
// layer must be redrawn there, not scrolled: the floor is as shadowed as with nothing cached.
TEST_F(ShadowCacheTest, ACasterThatJoinsALayerIsDrawnOverTheTexelsItKept) {
  const fs::path file = testing_util::test_tmp() / "joins.json";
  std::ofstream(file) << R"({ "kaskad_scene": 1, "render": { "ground": "none" },
    "shadow": { "map_size": 1024, "cascade_count": 2, "fit_mode": "stable" },
    "entities": [
      { "name": "platform", "transform": { "translation": [0, 4, 0], "scale": [4, 1, 4] },
        "primitive": { "shape": "plane" }, "renderer": { "cast_shadows": false } },
      { "name": "floor", "transform": { "scale": [4, 1, 4] }, "primitive": { "shape": "plane" },
        "renderer": { "cast_shadows": false, "receive_shadows": false } },
      { "name": "box", "transform": { "translation": [0, 1.5, 0] }, "primitive": { "shape": "box" },
        "renderer": { "receive_shadows": false } },
      { "name": "sun", "transform": { "direction": [0.1, -1, 0.15] },
        "light": { "type": "directional", "cast_shadows": true } },
      { "name": "camera", "transform": { "translation": [0, 2, 9], "look_at": [0, 1, 0] },
        "camera": { "fov_y_deg": 60, "near": 0.5, "far": 40, "active": true } } ] })";
  auto run = [&](bool scroll) {
    auto loaded = load_scene(file, {std::string("render.shadow_scroll=") + (scroll ? "true" : "false")});
    EXPECT_TRUE(loaded.ok()) << loaded.error().to_string();
    if (!loaded.ok()) return Frame{};
    render(*player_, *loaded);
    EXPECT_EQ(render(*player_, *loaded).stats.layer_casters[0], 0);  // the box is left out
    loaded->world.get<MeshRenderer>(named(*loaded, "floor")).receive_shadows = true;
    const Frame joined = render(*player_, *loaded);
    EXPECT_EQ(joined.stats.layer_casters[0], 1);  // the box joins
    return joined;
  };
  const Frame scrolled = run(true);
  const Frame redrawn = run(false);
  ASSERT_EQ(scrolled.visibility.size(), redrawn.visibility.size());
  // The floor is shadowed somewhere, and exactly as drawn without scrolling.
  EXPECT_NE(std::count(redrawn.visibility.begin(), redrawn.visibility.end(), 0.0f), 0);
  EXPECT_EQ(scrolled.visibility, redrawn.visibility);
  EXPECT_EQ(scrolled.stats.shadow_layers_scrolled, 0u);
}

}  // namespace
}  // namespace kaskad
