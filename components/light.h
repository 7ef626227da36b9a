// A punctual light (KHR_lights_punctual semantics). It shines along the entity's local -Z axis
// (world direction = rotation * (0,0,-1)); spot and point lights sit at the entity's position.
// Shadow parameters live in ShadowSettings, a separate component on the same entity.
#pragma once

#include <cmath>

#include <glm/glm.hpp>

namespace kaskad {

enum class LightType { directional, spot, point };

struct Light {
  LightType type = LightType::directional;
  glm::vec3 color{1.0f};        ///< linear RGB
  float intensity = 1.0f;       ///< directional: illuminance-like scale; spot/point: candela-like
  float range = 0.0f;           ///< metres; 0 = infinite (spot/point only)
  float inner_cone_deg = 0.0f;  ///< spot: full intensity inside this half-angle (degrees)
  float outer_cone_deg = 45.0f; ///< spot: zero intensity outside this half-angle (degrees)
  /// Only shadowed lights get shadow maps. Scene files and glTF imports turn it on for their
  /// first directional light unless the file says false (scene_io, gltf_loader).
  bool cast_shadows = false;
  /// Directional only: apex angle of the cone of directions the light arrives from, degrees, in
  /// [0, 45] (the sun: about 0.53). 0 = punctual. The ray-traced reference's area visibility and
  /// ShadowTechnique::pcss use it.
  float angular_size_deg = 0.0f;
  /// Spot and point only: the emitter's radius in metres, in [0, 100]; 0 = punctual. Shadows see
  /// it as a square of side 2 * radius centred on the light and facing along its direction (the
  /// ray-traced reference's square emitter, S1's square light; pcss's light width l = 2 radius).
  /// Shading stays punctual.
  float radius = 0.0f;
};

/// World-space direction a light shines along: its world matrix applied to local (0, 0, -1),
/// normalised (straight down when the matrix collapses the axis). The one definition of the
/// convention above, shared by the shadow systems and the ray-traced reference.
inline glm::vec3 light_direction(const glm::mat4& world_matrix) {
  const glm::vec3 d = glm::vec3(world_matrix * glm::vec4(0.0f, 0.0f, -1.0f, 0.0f));
  const float len = glm::length(d);
  return len > 0.0f ? d / len : glm::vec3(0.0f, -1.0f, 0.0f);
}

/// A light as the shading model sees it: the forward pass's per-light uniforms (the renderer's
/// LightItem) and the reflection reference's lights. `color` includes the intensity.
struct LightShading {
  LightType type = LightType::directional;
  glm::vec3 color{1.0f};                   ///< linear colour * intensity
  glm::vec3 direction{0.0f, -1.0f, 0.0f};  ///< the way the light travels (unit)
  glm::vec3 position{0.0f};                ///< spot/point: world position, metres
  float range = 0.0f;                      ///< spot/point: KHR window radius; 0 = infinite
  float cos_inner = 1.0f;                  ///< spot: cos(inner cone half-angle)
  float cos_outer = 0.7f;                  ///< spot: cos(outer cone half-angle)
};

/// The shading parameters of a Light on an entity with this world matrix.
inline LightShading light_shading(const Light& light, const glm::mat4& world_matrix) {
  LightShading s;
  s.type = light.type;
  s.color = light.color * light.intensity;
  s.direction = light_direction(world_matrix);
  s.position = glm::vec3(world_matrix[3]);
  s.range = light.range;
  s.cos_inner = std::cos(glm::radians(light.inner_cone_deg));
  s.cos_outer = std::cos(glm::radians(light.outer_cone_deg));
  return s;
}

}  // namespace kaskad
