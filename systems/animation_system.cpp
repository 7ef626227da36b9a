#include "systems/animation_system.h"

#include <cmath>

#include "components/animation.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "runtime/assets/mesh_pose.h"
#include "runtime/core/hash.h"

namespace kaskad {
namespace {

/// Clip time after `dt` more seconds: wrapped into [0, duration) when looping, else clamped
/// (and stopped) at the ends.
void advance(AnimationState& s, float duration, double dt) {
  double t = double(s.time) + dt * double(s.speed);
  if (duration <= 0.0f) {
    s.time = 0.0f;
    return;
  }
  if (s.loop) {
    t = std::fmod(t, double(duration));
    if (t < 0.0) t += double(duration);
  } else if (t >= double(duration) || t <= 0.0) {
    t = std::clamp(t, 0.0, double(duration));
    s.playing = false;
  }
  s.time = float(t);
}

void apply(ecs::World& world, const Animator& animator, const AnimationClip& clip, float time) {
  for (const AnimationClip::Channel& ch : clip.channels) {
    if (ch.node >= animator.nodes.size()) continue;
    const ecs::Entity e = animator.nodes[ch.node];
    if (!world.alive(e)) continue;
    if (ch.path == AnimatedPath::weights) {
      if (auto* w = world.try_get<MorphWeights>(e))
        for (std::size_t k = 0; k < ch.tracks.size() && k < w->weights.size(); ++k)
          w->weights[k] = sample(ch.tracks[k], time).x;
      continue;
    }
    auto* t = world.try_get<Transform>(e);
    if (t == nullptr) continue;
    const glm::vec4 v = sample(ch.tracks.front(), time);
    switch (ch.path) {
      case AnimatedPath::translation: t->translation = glm::vec3(v); break;
      case AnimatedPath::rotation: t->rotation = glm::quat(v.w, v.x, v.y, v.z); break;
      case AnimatedPath::scale: t->scale = glm::vec3(v); break;
      case AnimatedPath::weights: break;
    }
  }
}

}  // namespace

void update_animations(ecs::World& world, const AssetStore& assets, double dt) {
  world.view<Animator>().each([&](ecs::Entity, Animator& a) {
    a.cues.resize(a.clips.size());
    // In file order, so that the later clip wins where two drive one node.
    for (std::size_t k = 0; k < a.clips.size(); ++k) {
      const std::size_t at = a.first_clip + k;
      if (at >= assets.animations.size()) break;
      AnimationState& s = a.clips[k];
      const AnimationClip& clip = assets.animations[at];
      // A time set past either end (a scene file, --set) is where the clock would put it:
      // wrapped when the clip loops, else at that end, stopped.
      if (s.time > clip.duration || s.time < 0.0f) advance(s, clip.duration, 0.0);
      // The frame shows the clip at its time now; the clock then moves on for the next frame
      // (so frame n of a run shows n * dt, as playback files count time).
      if (s.playing || a.cues[k].pending) apply(world, a, clip, s.time);
      a.cues[k].pending = false;
      if (s.playing && dt != 0.0) advance(s, clip.duration, dt);
    }
  });
}

void set_animation_time(ecs::World& world, const AssetStore& assets, double seconds) {
  world.view<Animator>().each([&](ecs::Entity, Animator& a) {
    a.cues.resize(a.clips.size());
    for (std::size_t k = 0; k < a.clips.size(); ++k) {
      if (!a.clips[k].playing) continue;
      const std::size_t at = a.first_clip + k;
      const float duration = at < assets.animations.size() ? assets.animations[at].duration : 0.0f;
      AnimationState& s = a.clips[k];
      s.time = 0.0f;
      advance(s, duration, seconds);  // scene seconds times the clip's speed
      a.cues[k].pending = true;
    }
  });
}

void update_deformers(ecs::World& world, AssetStore& assets) {
  world.view<Deformer, MeshRenderer>().each([&](ecs::Entity e, Deformer& d, const MeshRenderer& mr) {
    if (index(mr.mesh) >= assets.meshes.size()) return;
    if (index(d.posed) >= assets.meshes.size()) {
      MeshData copy = assets.meshes[index(mr.mesh)];
      copy.name += " (posed)";
      copy.deform = {};  // the copy is a target, never a source
      d.posed = assets.add_mesh(std::move(copy));
    }
    const MeshData& base = assets.meshes[index(mr.mesh)];
    const SkinData* skin = d.skin < assets.skins.size() && base.deform.skinned()
                               ? &assets.skins[d.skin]
                               : nullptr;
    // Weights: the node's (the entity's parent), else the mesh's defaults.
    d.weights = base.deform.default_weights;
    if (const auto* t = world.try_get<Transform>(e))
      if (const auto* w = world.try_get<MorphWeights>(t->parent))
        for (std::size_t k = 0; k < d.weights.size() && k < w->weights.size(); ++k)
          d.weights[k] = w->weights[k];
    std::vector<glm::mat4> joint_world;
    d.skin_matrices.clear();
    if (skin != nullptr) {
      joint_world.reserve(d.joints.size());
      for (ecs::Entity j : d.joints) {
        const auto* wt = world.try_get<WorldTransform>(j);
        joint_world.push_back(wt ? wt->matrix : glm::mat4(1.0f));
      }
      d.skin_matrices = skin_matrices(joint_world, *skin);
      if (d.joint_boxes.empty()) d.joint_boxes = joint_boxes(base, *skin);
    }
    Hash h;
    h.add(index(mr.mesh));
    h.add_bytes(d.skin_matrices.data(), d.skin_matrices.size() * sizeof(glm::mat4));
    h.add_bytes(d.weights.data(), d.weights.size() * sizeof(float));
    d.pose = h.value();
    // Bounds of the pose: skinned poses are in world space; morphed ones in mesh space.
    Aabb box = pose_bounds(base, d.weights, joint_world, skin, d.joint_boxes);
    if (skin == nullptr)
      if (const auto* wt = world.try_get<WorldTransform>(e)) box = box.transformed(wt->matrix);
    if (auto* wb = world.try_get<WorldBounds>(e))
      wb->box = box;
    else
      world.emplace<WorldBounds>(e, WorldBounds{box});
  });
}

void pose_deformers_on_cpu(const ecs::World& world, AssetStore& assets) {
  world.view<Deformer, MeshRenderer>().each([&](ecs::Entity, const Deformer& d, const MeshRenderer& mr) {
    if (index(mr.mesh) >= assets.meshes.size() || index(d.posed) >= assets.meshes.size()) return;
    MeshData& posed = assets.meshes[index(d.posed)];
    pose_mesh(assets.meshes[index(mr.mesh)], d.weights, d.skin_matrices, posed);
    posed.compute_bounds();
  });
}

}  // namespace kaskad
