// A light (KHR_lights_punctual semantics, plus S1's rectangular area light). It shines along the
// entity's local -Z axis (world direction = rotation * (0,0,-1)); spot, point and area lights sit
// at the entity's position.
// Shadow parameters live in ShadowSettings, a separate component on the same entity.
#pragma once

#include <algorithm>
#include <cmath>

#include <array>
#include <string_view>
#include <tuple>

#include <glm/glm.hpp>

#include "components/limits.h"
#include "runtime/fields/fields.h"

namespace kaskad {

/// The values are the shaders' LIGHT_* numbers (render::shader_interface_defines()).
enum class LightType {
  directional,
  spot,
  point,
  /// S1's area light: a rectangle of Light::size (local X by local Y) facing along -Z, a
  /// Lambertian emitter (intensity falls with the cosine from its axis) lighting the cone of
  /// outer_cone_deg; shaded from its centre, shadowed with one perspective map from its centre
  /// whose axes are the rectangle's, soft shadows from its size.
  area,
};
constexpr std::array<std::string_view, 4> enum_names(LightType) {
  return {"directional", "spot", "point", "area"};
}
static_assert(enum_names(LightType{}).size() == std::size_t(LightType::area) + 1);

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
  /// Area only: width (local X) and height (local Y) of the rectangle, metres, each in (0, 100].
  /// 2 x 2: S1's experiments.
  glm::vec2 size{2.0f, 2.0f};
};

/// The fields of Light, once (runtime/fields/fields.h); which type each size is for is a rule
/// across fields (the scene reader's).
constexpr auto field_table(fields::Of<Light>) {
  using L = Light;
  using namespace fields;
  return std::tuple{
      choice("type", &L::type, "Directional, spot, point or rectangular area light"),
      vector("color", &L::color, 0, 1.0e4, "Linear RGB colour"),
      number("intensity", &L::intensity, 0, 1.0e9,
             "Directional: illuminance-like scale; spot, point, area: candela-like"),
      number("range", &L::range, 0, kMaxCoordinate, "Spot and point: range in metres; 0 = infinite"),
      number("inner_cone_deg", &L::inner_cone_deg, 0, 90,
             "Spot: full intensity inside this half-angle, degrees"),
      number("outer_cone_deg", &L::outer_cone_deg, 0, 90,
             "Spot, area: no light outside this half-angle, degrees"),
      flag("cast_shadows", &L::cast_shadows, "Gets shadow maps (a scene's first sun: on unless false)"),
      number("angular_size_deg", &L::angular_size_deg, 0, 45,
             "Directional: apex angle of the cone the light arrives from, degrees; 0 = punctual"),
      number("radius", &L::radius, 0, 100, "Spot and point: emitter radius, metres; 0 = punctual"),
      vector("size", &L::size, 1e-3, 100, "Area: width and height of the rectangle, metres"),
  };
}

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
  float cos_outer = 0.7f;                  ///< spot, area: cos(outer cone half-angle)
};

/// How much of a light's intensity leaves towards a point in direction `l` from it (unit, from
/// the point to the light), before distance attenuation: the spot's smooth cone; an area light's
/// cone times its Lambertian cosine; 1 for the others. The CPU twin of forward.frag's.
inline float light_emission(const LightShading& s, const glm::vec3& l) {
  if (s.type != LightType::spot && s.type != LightType::area) return 1.0f;
  const float cd = glm::dot(-l, s.direction);
  // GLSL's smoothstep(cos_outer, cos_inner, cd), with a step where the edges meet (GLSL leaves
  // e0 >= e1 undefined).
  const float e0 = s.cos_outer, e1 = s.cos_inner;
  float cone = cd >= e1 ? 1.0f : 0.0f;
  if (e1 > e0) {
    const float t = glm::clamp((cd - e0) / (e1 - e0), 0.0f, 1.0f);
    cone = t * t * (3.0f - 2.0f * t);
  }
  return s.type == LightType::area ? cone * std::max(cd, 0.0f) : cone;
}

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
