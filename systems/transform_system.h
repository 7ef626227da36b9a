// TransformSystem: derives WorldTransform from Transform parent chains and WorldBounds from the
// mesh bounds of MeshRenderers.
#pragma once

#include <cstddef>

#include "components/bounds.h"
#include "components/transform.h"
#include "runtime/assets/asset_store.h"
#include "runtime/ecs/world.h"

namespace kaskad {

/// What one update_transforms call recomputed.
struct TransformStats {
  std::size_t transforms = 0;  ///< WorldTransforms recomputed
  std::size_t bounds = 0;      ///< WorldBounds recomputed
};

/// After this, every entity with a Transform has a current WorldTransform, and every entity with
/// a MeshRenderer and a Transform has a current WorldBounds. Parent cycles and stale parents are
/// treated as roots (reported once through the log).
/// Only what changed is recomputed: an entity whose Transform, applied parent (and that parent's
/// world matrix), mesh id and mesh bounds are what they were at its last recompute keeps its
/// WorldTransform and WorldBounds. Changes are found by comparing with the system-owned
/// TransformCache / BoundsCache (components/transform_cache.h), so writers of Transform and
/// MeshRenderer need no discipline; WorldTransform and WorldBounds of entities with a Transform
/// are derived data that only this function writes. A WorldTransform on an entity without a
/// Transform is someone else's: the bounds of such entities are recomputed every call.
TransformStats update_transforms(ecs::World& world, const AssetStore& assets);

/// Union of all WorldBounds (empty when there are none).
Aabb scene_bounds(const ecs::World& world);

/// Local-to-parent matrix of a Transform (T * R * S).
glm::mat4 local_matrix(const Transform& t);

}  // namespace kaskad
