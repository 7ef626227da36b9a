// Local transform of an entity, with an optional parent. World matrices are derived by the
// TransformSystem into WorldTransform; authored data lives only here.
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>

#include "runtime/ecs/entity.h"

namespace kaskad {

struct Transform {
  glm::vec3 translation{0.0f};                     ///< metres, in the parent's space
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};      ///< unit quaternion (w, x, y, z)
  glm::vec3 scale{1.0f};                           ///< per-axis scale factor
  ecs::Entity parent = ecs::kNullEntity;           ///< null for a root entity
};

/// The rotation that turns the local -Z axis (where lights shine and cameras look) to the unit
/// `direction`, keeping +Y up (-Z up when looking straight up or down). The one definition of
/// "direction" and "look_at" in scene files, --set and playback files.
inline glm::quat look_rotation(const glm::vec3& direction) {
  const glm::vec3 up = std::abs(direction.y) > 0.999f ? glm::vec3(0, 0, -1) : glm::vec3(0, 1, 0);
  // lookAt builds world->view; its inverse rotation is the entity's orientation.
  return glm::quat_cast(glm::inverse(glm::mat3(glm::lookAt(glm::vec3(0), direction, up))));
}

/// Translation, rotation and scale of an affine matrix (its projective part ignored): a negative
/// determinant goes into scale.x, a zero scale keeps the identity rotation, and shear, if any, is
/// approximated by the rotation of the normalised axes. The parent is left null.
inline Transform decompose(const glm::mat4& matrix) {
  Transform t;
  t.translation = glm::vec3(matrix[3]);
  glm::vec3 axis[3] = {glm::vec3(matrix[0]), glm::vec3(matrix[1]), glm::vec3(matrix[2])};
  t.scale = {glm::length(axis[0]), glm::length(axis[1]), glm::length(axis[2])};
  if (glm::determinant(glm::mat3(axis[0], axis[1], axis[2])) < 0.0f) {
    t.scale.x = -t.scale.x;
    axis[0] = -axis[0];
  }
  const float smallest = std::min({std::abs(t.scale.x), std::abs(t.scale.y), std::abs(t.scale.z)});
  if (!(smallest > 1e-12f)) return t;  // a zero scale has no recoverable rotation: keep identity
  for (glm::vec3& a : axis) a = glm::normalize(a);
  t.rotation = glm::normalize(glm::quat_cast(glm::mat3(axis[0], axis[1], axis[2])));
  return t;
}

/// Derived by the TransformSystem: local-to-world matrix (parent chain applied).
struct WorldTransform {
  glm::mat4 matrix{1.0f};
};

/// Whether `model` mirrors (negative determinant): its triangles wind the other way, so the
/// front face is the clockwise one (glTF 2.0, "Transformations"). The passes flip glFrontFace
/// for such draws; the ray-traced reference reverses their triangles' normals.
inline bool mirrors(const glm::mat4& model) {
  return glm::determinant(glm::mat3(model)) < 0.0f;
}

}  // namespace kaskad
