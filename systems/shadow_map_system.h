// The basic shadow map of one directional light (S4 with S2's basics): an orthographic light
// projection fitted to the scene bounds. It is the baseline the cascades are measured against.
// Maths only; the renderer draws the pass.
#pragma once

#include <glm/glm.hpp>

#include "components/bounds.h"
#include "components/light.h"  // light_direction()
#include "runtime/ecs/world.h"

namespace kaskad {

struct LightProjection {
  glm::mat4 view{1.0f};
  glm::mat4 proj{1.0f};
  glm::mat4 view_proj() const { return proj * view; }
};

/// An orthographic light looking along `direction` (unit, the way light travels) whose x/y extent
/// and near/far enclose `bounds` tightly (the 8 corners in light space). A non-empty box is
/// required; degenerate (flat) extents are widened to a small epsilon so the matrix stays
/// invertible. The up vector is the world axis least parallel to the direction, so straight-down
/// lights work.
LightProjection fit_ortho_light_to_bounds(const glm::vec3& direction, const Aabb& bounds);

/// The basic map's projection: fits the first directional Light with cast_shadows (entity order)
/// to the bounds of all mesh renderers, or nothing (light null). The baseline of FitMode::scene.
struct BasicShadow {
  ecs::Entity light = ecs::kNullEntity;
  LightProjection projection;
};
BasicShadow update_basic_shadow(const ecs::World& world);

/// The first directional Light with cast_shadows (entity order) and its world matrix; a null
/// entity when there is none. The basic map shadows this light (the cascade system shadows the
/// first shadowed light of any type).
ecs::Entity first_shadowed_directional_light(const ecs::World& world, glm::mat4& world_matrix);


}  // namespace kaskad
