// The visibility cache (render.visibility_cache): a frame whose camera, draws, lights
// and shadow maps are those of the frame that stored its visibility reads each pixel's shadow
// visibility back instead of looking the maps up; a frame stores only when a later frame may read
// it. Checked by replaying one sequence of scene changes with the cache on and off: every frame's
// colour is the same bit for bit, still frames store and then read back, and a frame after a
// change looks up again. Fails when the visibility inputs leave out the draws' matrices (a moved
// object that casts nothing then shows stale visibility), or when a storing frame stores nothing.
// With one shadow view, a frame whose camera alone moved reprojects the stored visibility
// (render.visibility_reproject): its colour is within a few pixels of the looked-up frame's
// (ReprojectedFramesMatchTheLookUpAlongCameraPaths measures how close).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "components/camera.h"
#include "components/light.h"
#include "components/name.h"
#include "components/transform.h"
#include "runtime/app/player.h"
#include "tests/render/player_fixture.h"

namespace kaskad {
namespace {

class VisibilityCacheTest : public PlayerTest {
 protected:
  // One step of the replay: what changes before the frame, and what the frame does with the
  // stored visibility: kLookUp (it changed since the frame before), kStore (the same as the
  // frame before: it looks up and stores), kReadBack (the same as the frame stored), kReproject
  // (only the camera moved since the frame stored), kEither (not asserted).
  enum class Change { none, caster, receiver, light, camera, turn, size, base_colour };
  static constexpr int kLookUp = 0, kReadBack = 1, kStore = 2, kReproject = 3, kEither = -1;
  struct Step {
    Change change;
    int use;
  };

  struct Frame {
    Image colour;
    bool reused = false;
    bool stored = false;
    bool reprojected = false;
  };

  static ecs::Entity find(const Scene& s, const char* name) {
    ecs::Entity found;
    s.world.view<Name>().each([&](ecs::Entity e, const Name& n) {
      if (n.value == name) found = e;
    });
    return found;
  }

  // Pixels where a channel of `a` and `b` differs by more than 0.02, the playback goldens'
  // threshold (docs/guide/playback.md).
  static int differing_pixels(const Image& a, const Image& b) {
    int n = 0;
    for (std::size_t p = 0; p + 3 < a.pixels.size() && p + 3 < b.pixels.size(); p += 4) {
      float d = 0.0f;
      for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(a.pixels[p + c] - b.pixels[p + c]));
      n += d > 0.02f;
    }
    return n;
  }
  // At most 0.15% of the replay's 320x180 pixels a frame (measured along the paths of
  // ReprojectedFramesMatchTheLookUpAlongCameraPaths: at most 0.099% in a frame, 0.05% over a
  // path).
  static constexpr int kMaxReprojectedPixels = 86;

  // Replays `steps` on the scene file with `sets`, one frame each, without AOVs.
  static std::vector<Frame> replay(const std::string& file, std::vector<std::string> sets,
                                   const std::vector<Step>& steps) {
    std::vector<Frame> out;
    auto loaded = load_scene(content_dir() / "scenes" / file, sets);
    EXPECT_TRUE(loaded.ok()) << loaded.error().to_string();
    if (!loaded.ok()) return out;
    Scene& scene = *loaded;
    ecs::Entity camera, light, caster = find(scene, "box_floating");
    scene.world.view<Camera>().each([&](ecs::Entity e, const Camera& c) {
      if (c.active) camera = e;
    });
    scene.world.view<Light>().each([&](ecs::Entity e, const Light& l) {
      if (l.cast_shadows && !light.valid()) light = e;
    });
    EXPECT_TRUE(camera.valid() && light.valid()) << file;
    int width = 320, height = 180;
    for (const Step& step : steps) {
      switch (step.change) {
        case Change::none: break;
        case Change::caster:
          if (caster.valid()) scene.world.get<Transform>(caster).translation += glm::vec3(0.3f, 0.2f, 0.1f);
          break;
        case Change::receiver: {
          // Sideways in the view, a few centimetres: its view depths stay, so do the splits and
          // (it casts nothing) the shadow maps; only the visibility inputs see it move.
          const Transform& cam = scene.world.get<Transform>(camera);
          const glm::vec3 right = cam.rotation * glm::vec3(1, 0, 0);
          if (caster.valid()) scene.world.get<Transform>(caster).translation += 0.04f * right;
          break;
        }
        case Change::light: {
          Transform& t = scene.world.get<Transform>(light);
          t.rotation = glm::angleAxis(0.05f, glm::vec3(0, 1, 0)) * t.rotation;
          t.translation += glm::vec3(0.1f, 0.0f, 0.05f);
          break;
        }
        case Change::camera:
          scene.world.get<Transform>(camera).translation += glm::vec3(0.2f, 0.0f, -0.1f);
          break;
        case Change::turn: {
          Transform& t = scene.world.get<Transform>(camera);
          t.rotation = glm::angleAxis(glm::radians(0.7f), glm::vec3(0, 1, 0)) * t.rotation;
          break;
        }
        case Change::size:
          width = 240;
          height = 136;
          break;
        case Change::base_colour:
          scene.world.view<Material>().each([](ecs::Entity, Material& m) {
            m.base_color.r = 1.0f - m.base_color.r;
          });
          break;
      }
      RenderRun run;
      run.width = width;
      run.height = height;
      run.write_aovs = false;
      auto t = render_frames(*player_, scene, run);
      EXPECT_TRUE(t.ok()) << file << ": " << t.error().to_string();
      if (!t.ok()) return out;
      out.push_back({player_->renderer->read_color(), t->last.stats.visibility_reused,
                     t->last.stats.visibility_stored, t->last.stats.visibility_reprojected});
    }
    return out;
  }
};

TEST_F(VisibilityCacheTest, ReadBackFramesAreThoseLookedUp) {
  using C = Change;
  // The default scene: a caster, the sun, the camera and the size change in turn. A change of
  // base colours leaves the visibility as it was, but may reorder the draws (they sort by
  // material), which looks up again: either way the colour must be right.
  // A camera move reprojects what the frame before stored; once it stops, a frame looks up and
  // stores (a still camera reads back only looked-up visibility), and the next reads it back.
  const int L = kLookUp, S = kStore, R = kReadBack, P = kReproject;
  const std::vector<Step> with_caster = {
      {C::none, L},  {C::none, S},   {C::none, R},   {C::none, R},
      {C::caster, L}, {C::none, S},  {C::none, R},   {C::light, L},
      {C::none, S},  {C::none, R},   {C::camera, P}, {C::camera, P},
      {C::none, S},  {C::none, R},   {C::base_colour, kEither}, {C::size, L},
      {C::none, S},  {C::none, R}};
  // The floating box casts nothing and moves sideways: no shadow layer is redrawn, but the
  // pixels it covers changed.
  const std::vector<Step> receiver = {{C::none, L},     {C::none, S}, {C::none, R},
                                      {C::receiver, L}, {C::none, S}, {C::none, R},
                                      {C::receiver, L}, {C::none, S}, {C::none, R}};
  // Other shadow views (a spot light; a point light's cube faces; two suns: two channels and no
  // reprojection) and techniques: the same replay without a named caster.
  const std::vector<Step> without_caster = {{C::none, L},   {C::none, S}, {C::none, R},
                                            {C::light, L},  {C::none, S}, {C::none, R},
                                            {C::camera, P}, {C::none, S}, {C::none, R}};
  const std::vector<Step> two_views = {{C::none, L},   {C::none, S}, {C::none, R},
                                       {C::light, L},  {C::none, S}, {C::none, R},
                                       {C::camera, L}, {C::none, S}, {C::none, R}};
  struct Case {
    const char* file;
    std::vector<std::string> sets;
    const std::vector<Step>* steps;
  };
  const Case cases[] = {
      {"default.json", {}, &with_caster},
      {"default.json", {"box_floating.renderer.cast_shadows=false"}, &receiver},
      {"default.json", {"shadow.technique=pcss"}, &with_caster},
      {"default.json", {"shadow.technique=vsm"}, &with_caster},
      {"two_suns.json", {}, &two_views},
      {"default.json", {"render.visibility_reproject=false"}, &two_views},
      {"spot.json", {}, &without_caster},
      {"point.json", {}, &without_caster},
  };
  for (const Case& c : cases) {
    std::string what = c.file;
    for (const std::string& s : c.sets) what += " " + s;
    std::vector<std::string> off = c.sets;
    off.push_back("render.visibility_cache=false");
    const std::vector<Frame> cached = replay(c.file, c.sets, *c.steps);
    const std::vector<Frame> looked_up = replay(c.file, off, *c.steps);
    ASSERT_EQ(cached.size(), c.steps->size()) << what;
    ASSERT_EQ(looked_up.size(), c.steps->size()) << what;
    int reused = 0, reprojected = 0;
    for (std::size_t i = 0; i < cached.size(); ++i) {
      const int use = (*c.steps)[i].use;
      if (use != kEither) {
        EXPECT_EQ(cached[i].reused, use == kReadBack) << what << ", frame " << i;
        EXPECT_EQ(cached[i].reprojected, use == kReproject) << what << ", frame " << i;
        EXPECT_EQ(cached[i].stored, use == kStore || use == kReproject) << what << ", frame " << i;
      }
      EXPECT_FALSE(looked_up[i].reused || looked_up[i].reprojected) << what << ", frame " << i;
      EXPECT_FALSE(looked_up[i].stored) << what << ", frame " << i;
      EXPECT_EQ(cached[i].colour.width, looked_up[i].colour.width);
      // A reprojected frame is held to the reprojection's bound (a few pixels at shadow edges:
      // the test below); every other one is the looked-up frame bit for bit: a camera that
      // stops shows the lookup again.
      if (cached[i].reprojected) {
        EXPECT_LE(differing_pixels(cached[i].colour, looked_up[i].colour), kMaxReprojectedPixels)
            << what << ", frame " << i;
      } else {
        EXPECT_TRUE(cached[i].colour.pixels == looked_up[i].colour.pixels)
            << what << ", frame " << i << " differs from the frame that looked the maps up";
      }
      reused += cached[i].reused;
      reprojected += cached[i].reprojected;
    }
    std::printf("[ %s ] %d of %zu frames read the visibility back, %d reprojected it; every "
                "other colour equal to the looked-up frame's\n",
                what.c_str(), reused, cached.size(), reprojected);
  }
}

// Reprojection against the lookup along camera paths: a camera that walks and turns for 24
// frames reprojects on every frame after the first two, and each frame's colour differs from the
// frame looked up with the cache off in at most kMaxReprojectedPixels pixels (0.15%, by more than
// 0.02). The differences are pixels at the edge of a shadow narrower than a pixel's
// step, where the four stored pixels around the point agree and the point itself is partly lit.
// Fails when the reprojection ignores the surface check (pixels across silhouettes) or reuses
// partly lit pixels.
TEST_F(VisibilityCacheTest, ReprojectedFramesMatchTheLookUpAlongCameraPaths) {
  using C = Change;
  std::vector<Step> path = {{C::none, kLookUp}, {C::none, kStore}};
  for (int i = 0; i < 24; ++i) path.push_back({i % 3 == 2 ? C::turn : C::camera, kReproject});
  struct Case {
    const char* file;
    std::vector<std::string> sets;
  };
  const Case cases[] = {
      {"default.json", {}},
      {"default.json", {"shadow.technique=pcss"}},
      {"default.json", {"shadow.fit_mode=crop"}},
      {"terrain.json", {}},
      {"spot.json", {}},
      {"reflections.json", {}},
  };
  for (const Case& c : cases) {
    std::string what = c.file;
    for (const std::string& s : c.sets) what += " " + s;
    std::vector<std::string> off = c.sets;
    off.push_back("render.visibility_cache=false");
    const std::vector<Frame> reprojected = replay(c.file, c.sets, path);
    const std::vector<Frame> looked_up = replay(c.file, off, path);
    ASSERT_EQ(reprojected.size(), path.size()) << what;
    ASSERT_EQ(looked_up.size(), path.size()) << what;
    int worst = 0, total = 0, frames = 0;
    for (std::size_t i = 0; i < path.size(); ++i) {
      EXPECT_EQ(reprojected[i].reprojected, path[i].use == kReproject) << what << ", frame " << i;
      const int n = differing_pixels(reprojected[i].colour, looked_up[i].colour);
      EXPECT_LE(n, kMaxReprojectedPixels) << what << ", frame " << i;
      worst = std::max(worst, n);
      total += n;
      frames += reprojected[i].reprojected;
    }
    std::printf("[ %s ] %d of %zu frames reprojected; pixels differing from the lookup: at most "
                "%d of %d a frame, %.4f%% over the path\n",
                what.c_str(), frames, path.size(), worst, 320 * 180,
                100.0 * total / (double(path.size()) * 320 * 180));
  }
}

// The cache holds one visibility per pixel and no cascade: frames with AOVs (which show the
// cascade), with MSAA (per-sample visibility) or with the cascade tint always look up.
TEST_F(VisibilityCacheTest, NotWithAovsMsaaOrTheCascadeTint) {
  struct Case {
    std::vector<std::string> sets;
    bool aovs;
  };
  for (const Case& c : {Case{{}, true}, Case{{"render.msaa=4"}, false},
                        Case{{"shadow.debug_cascades=true"}, false},
                        Case{{"render.visibility_cache=false"}, false}}) {
    auto loaded = load_scene(content_dir() / "scenes" / "default.json", c.sets);
    ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
    for (int f = 0; f < 3; ++f) {
      RenderRun run;
      run.width = 160;
      run.height = 90;
      run.write_aovs = c.aovs;
      auto t = render_frames(*player_, *loaded, run);
      ASSERT_TRUE(t.ok()) << t.error().to_string();
      EXPECT_FALSE(t->last.stats.visibility_reused)
          << (c.sets.empty() ? "aovs" : c.sets.front()) << ", frame " << f;
      EXPECT_EQ(t->last.stats.shadow_layers_rendered, f == 0 ? 0xfu : 0u);
    }
  }
}

}  // namespace
}  // namespace kaskad
