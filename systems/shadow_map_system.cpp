#include "systems/shadow_map_system.h"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "components/light.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "runtime/math/cascade_math.h"

namespace kaskad {

LightProjection fit_ortho_light_to_bounds(const glm::vec3& direction, const Aabb& bounds) {
  const glm::vec3 dir = glm::normalize(direction);
  // Up = the world axis least parallel to the light, so lookAt never degenerates (shared with
  // the cascades' light view).
  const glm::vec3 up = light_up_vector(dir);
  const glm::vec3 center = bounds.center();
  LightProjection out;
  out.view = glm::lookAt(center - dir, center, up);
  // 1. The box's 8 corners in light view space give x/y/z extents (tight fit, S2).
  Aabb ls = bounds.transformed(out.view);
  // 2. Guard flat extents (a single plane seen edge-on) so the projection stays invertible.
  const float eps = 1e-3f * std::max(1.0f, glm::length(bounds.extent()));
  for (int i = 0; i < 3; ++i) {
    if (ls.max[i] - ls.min[i] < eps) {
      ls.min[i] -= eps;
      ls.max[i] += eps;
    }
  }
  // 3. View space looks down -z: near = -max.z, far = -min.z. A small margin keeps casters that
  //    touch the box faces inside the clip volume.
  const float margin = 0.01f * (ls.max.z - ls.min.z) + eps;
  out.proj = glm::ortho(ls.min.x, ls.max.x, ls.min.y, ls.max.y, -ls.max.z - margin,
                        -ls.min.z + margin);
  return out;
}

ecs::Entity first_shadowed_directional_light(const ecs::World& world, glm::mat4& world_matrix) {
  ecs::Entity found;
  world.view<Light, WorldTransform>().each(
      [&](ecs::Entity e, const Light& light, const WorldTransform& wt) {
        if (found.valid() || !light.cast_shadows || light.type != LightType::directional) return;
        found = e;
        world_matrix = wt.matrix;
      });
  return found;
}

BasicShadow update_basic_shadow(const ecs::World& world) {
  BasicShadow out;
  glm::mat4 light_matrix(1.0f);
  out.light = first_shadowed_directional_light(world, light_matrix);
  if (!out.light.valid()) return out;
  const glm::vec3 dir = light_direction(light_matrix);
  Aabb bounds;
  world.view<MeshRenderer, WorldBounds>().each(
      [&](ecs::Entity, const MeshRenderer&, const WorldBounds& b) { bounds.expand(b.box); });
  if (bounds.empty()) {
    out.light = ecs::kNullEntity;  // nothing to shadow
    return out;
  }
  out.projection = fit_ortho_light_to_bounds(dir, bounds);
  return out;
}

}  // namespace kaskad
