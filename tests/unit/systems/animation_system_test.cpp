#include "systems/animation_system.h"

#include <gtest/gtest.h>

#include "components/animation.h"
#include "components/bounds.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"

namespace kaskad {
namespace {

/// One node moved along x from 0 to 2 over 2 s (LINEAR), as clip 0 of an Animator.
struct OneClip {
  ecs::World world;
  AssetStore assets;
  ecs::Entity model, node;
  OneClip() {
    model = world.create();
    node = world.create();
    world.emplace<Transform>(node);
    AnimationClip clip;
    clip.name = "slide";
    AnimationClip::Channel ch;
    ch.node = 0;
    ch.path = AnimatedPath::translation;
    KeyTrack t;
    t.times = {0.0f, 2.0f};
    t.values = {glm::vec4(0.0f), glm::vec4(2.0f, 0.0f, 0.0f, 0.0f)};
    ch.tracks.push_back(t);
    clip.channels.push_back(ch);
    clip.duration = 2.0f;
    assets.animations.push_back(clip);
    Animator a;
    a.clips.resize(1);
    a.clips[0].playing = true;
    a.names = {"slide"};
    a.nodes = {node};
    a.cues.resize(1);
    world.emplace<Animator>(model, a);
  }
  float x() { return world.get<Transform>(node).translation.x; }
  AnimationState& state() { return world.get<Animator>(model).clips[0]; }
  /// The clip's time as a scene file or --set gives it: shown on the next frame.
  void set_time(float t) {
    state().time = t;
    world.get<Animator>(model).cues[0].pending = true;
  }
};

TEST(AnimationSystem, AFrameShowsTheClipNowThenTheClockMovesOn) {
  OneClip s;
  update_animations(s.world, s.assets, 0.5);
  EXPECT_FLOAT_EQ(s.x(), 0.0f);  // frame 0 shows t = 0
  update_animations(s.world, s.assets, 0.5);
  EXPECT_FLOAT_EQ(s.x(), 0.5f);
  EXPECT_FLOAT_EQ(s.state().time, 1.0f);
}

TEST(AnimationSystem, LoopingWrapsAndAClipThatDoesNotLoopStopsAtItsEnd) {
  OneClip s;
  s.state().time = 1.5f;
  update_animations(s.world, s.assets, 1.0);
  EXPECT_FLOAT_EQ(s.state().time, 0.5f);  // wrapped
  s.state().loop = false;
  s.state().time = 1.5f;
  update_animations(s.world, s.assets, 1.0);
  EXPECT_FLOAT_EQ(s.state().time, 2.0f);
  EXPECT_FALSE(s.state().playing);
  // A stopped clip holds its pose: nothing moves it back.
  s.world.get<Transform>(s.node).translation.x = 7.0f;
  update_animations(s.world, s.assets, 1.0);
  EXPECT_FLOAT_EQ(s.x(), 7.0f);
}

TEST(AnimationSystem, SetTimeScalesBySpeedAndPosesNextFrame) {
  OneClip s;
  s.state().speed = 0.5f;
  set_animation_time(s.world, s.assets, 3.0f);
  EXPECT_FLOAT_EQ(s.state().time, 1.5f);
  update_animations(s.world, s.assets, 0.0);
  EXPECT_FLOAT_EQ(s.x(), 1.5f);
  // dt 0 (a plan, a still re-render) poses without advancing.
  EXPECT_FLOAT_EQ(s.state().time, 1.5f);
}

// A time set past the clip's end is where the clock would put it: wrapped for a looping clip
// (3.9 s of a 2 s clip shows 1.9 s), at the end for one that does not loop. --time is seconds in
// double precision: 999999.9 s of a 2 s loop is 1.9 s, not a float's 1.875.
TEST(AnimationSystem, TimesPastTheEndWrapOrStopAndLongTimesStayPrecise) {
  OneClip s;
  s.set_time(3.9f);
  update_animations(s.world, s.assets, 0.0);
  EXPECT_NEAR(s.x(), 1.9f, 1e-5f);
  s.state().loop = false;
  s.set_time(3.9f);
  update_animations(s.world, s.assets, 0.0);
  EXPECT_FLOAT_EQ(s.x(), 2.0f);
  EXPECT_FALSE(s.state().playing);
  OneClip t;
  set_animation_time(t.world, t.assets, 999999.9);
  EXPECT_NEAR(t.state().time, 1.9f, 1e-4f);
}

// A morphed mesh's bounds hold the displaced vertices: one target lifts vertex 1 of a unit
// triangle by 2 in y, so at weight 0.75 the pose reaches y = 1.5 (above the mesh's own box).
// (Bounds without the morph growth fail it.)
TEST(DeformSystem, MorphedBoundsHoldTheWeightedDisplacement) {
  ecs::World world;
  AssetStore assets;
  MeshData mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.normals.assign(3, glm::vec3(0, 0, 1));
  mesh.indices = {0, 1, 2};
  mesh.compute_bounds();
  MeshDeform::Target target;
  target.positions = {{0, 0, 0}, {0, 2, 0}, {0, 0, 0}};
  target.normals.assign(3, glm::vec3(0));
  target.delta_bounds = Aabb::from_corners(glm::vec3(0), glm::vec3(0, 2, 0));
  mesh.deform.targets.push_back(target);
  mesh.deform.default_weights = {0.75f};
  const MeshId id = assets.add_mesh(mesh);
  const ecs::Entity e = world.create();
  world.emplace<Transform>(e);
  world.emplace<WorldTransform>(e);
  MeshRenderer mr;
  mr.mesh = id;
  world.emplace<MeshRenderer>(e, mr);
  world.emplace<Deformer>(e);
  update_deformers(world, assets);
  const Aabb box = world.get<WorldBounds>(e).box;
  EXPECT_GE(box.max.y, 1.5f - 1e-6f);
  // Conservative, no more: the mesh's box grown by the weighted target's box (1 + 0.75 x 2).
  EXPECT_LE(box.max.y, 2.5f + 1e-6f);
  EXPECT_FLOAT_EQ(box.min.y, 0.0f);
}

}  // namespace
}  // namespace kaskad
