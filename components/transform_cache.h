// The TransformSystem's own state (STYLE.md 5): what update_transforms last derived an entity's
// WorldTransform and WorldBounds from. Added and written by the system only; it lets the system
// recompute only what changed without asking anything of the code that writes Transforms.
#pragma once

#include <cstdint>

#include "components/bounds.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "runtime/ecs/entity.h"

namespace kaskad {

/// On every entity with a Transform. WorldTransform is current while the Transform's bits, the
/// parent actually applied and that parent's version all equal what is recorded here.
struct TransformCache {
  Transform local;                         ///< the Transform values last applied
  ecs::Entity parent = ecs::kNullEntity;   ///< the parent applied (null: root, also for a cycle
                                           ///< or a parent that is gone)
  std::uint64_t parent_version = 0;        ///< that parent's `version` when it was applied
  /// The stamp of the update_transforms call that last recomputed WorldTransform (unique per
  /// call in the process, so it changes whenever WorldTransform does); 0: never computed.
  std::uint64_t version = 0;
};

/// On every entity with a MeshRenderer and a WorldTransform: the inputs of its WorldBounds.
struct BoundsCache {
  MeshId mesh = kNoMesh;          ///< MeshRenderer::mesh applied
  Aabb local;                     ///< that mesh's local bounds applied (empty for no mesh)
  std::uint64_t world_version = 0;///< TransformCache::version applied; 0: recompute every call
};

}  // namespace kaskad
