// Local transform of an entity, with an optional parent. World matrices are derived by the
// TransformSystem into WorldTransform; authored data lives only here.
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "runtime/ecs/entity.h"

namespace kaskad {

struct Transform {
  glm::vec3 translation{0.0f};                     ///< metres, in the parent's space
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};      ///< unit quaternion (w, x, y, z)
  glm::vec3 scale{1.0f};                           ///< per-axis scale factor
  ecs::Entity parent = ecs::kNullEntity;           ///< null for a root entity
};

/// Derived by the TransformSystem: local-to-world matrix (parent chain applied).
struct WorldTransform {
  glm::mat4 matrix{1.0f};
};

}  // namespace kaskad
