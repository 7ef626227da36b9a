#include "systems/animation_system.h"

#include <gtest/gtest.h>

#include "components/animation.h"
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

}  // namespace
}  // namespace kaskad
