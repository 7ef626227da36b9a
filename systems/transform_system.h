// TransformSystem: derives WorldTransform from Transform parent chains and WorldBounds from the
// mesh bounds of MeshRenderers.
#pragma once

#include "components/bounds.h"
#include "components/transform.h"
#include "runtime/assets/asset_store.h"
#include "runtime/ecs/world.h"

namespace kaskad {

/// After this, every entity with a Transform has a current WorldTransform, and every entity with
/// a MeshRenderer and a Transform has a current WorldBounds. Parent cycles and stale parents are
/// treated as roots (reported once through the log).
void update_transforms(ecs::World& world, const AssetStore& assets);

/// Union of all WorldBounds (empty when there are none).
Aabb scene_bounds(const ecs::World& world);

/// Local-to-parent matrix of a Transform (T * R * S).
glm::mat4 local_matrix(const Transform& t);

}  // namespace kaskad
