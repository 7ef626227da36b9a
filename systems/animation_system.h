// Phase 0 and 1b of the frame (systems/frame.h): clips played into transforms and morph
// weights on a deterministic clock, and deformed meshes posed (their skin matrices, morph
// weights and conservative bounds) once the transforms are current.
#pragma once

#include <string>

#include "runtime/assets/asset_store.h"
#include "runtime/ecs/world.h"

namespace kaskad {

/// Advances every playing clip by `dt` seconds times its speed (looping clips wrap, others stop
/// at their end) and writes the pose of every playing clip, and of any whose time was set since
/// (Animator::cues), into its nodes' Transform and MorphWeights. dt 0 poses without
/// advancing. Clips later in the file win where two drive the same node.
void update_animations(ecs::World& world, const AssetStore& assets, double dt);

/// Puts every playing clip where `seconds` of play from its start take it (times its speed,
/// wrapped or clamped as advancing would): `kaskad render --time`. Posed there next frame.
void set_animation_time(ecs::World& world, const AssetStore& assets, double seconds);

/// After the transforms: every Deformer entity gets its posed mesh (allocated on first use, a
/// copy of its MeshRenderer's mesh), this frame's skin matrices and weights and their hash, and
/// WorldBounds that hold the pose (runtime/assets/mesh_pose.h, pose_bounds()).
void update_deformers(ecs::World& world, AssetStore& assets);

/// Poses every Deformer's mesh on the CPU into its posed copy in `assets` (what the deform pass
/// draws on the GPU), for the ray-traced references. After update_deformers().
void pose_deformers_on_cpu(const ecs::World& world, AssetStore& assets);

}  // namespace kaskad
