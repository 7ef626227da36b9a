// Shadow maps of spot and point lights, the maths only (STYLE.md 4): the depth range of a light
// at a position, a spot light's perspective map (S4: perspective for spot lights; S0 names
// perspective spot maps among its authors' earlier work), the six faces of a cube map and the two
// hemispheres of a dual-paraboloid map (S0's earlier work). Pure GLM: no GL, no ECS.
//
// Conventions as cascade_math.h: OpenGL clip space, view spaces look down -z. The shader mirrors
// cube_face_of() and paraboloid_project() (content/shaders/shadow.glsl: cube_face(),
// paraboloid_visibility()). The CPU side is checked by the unit tests
// LocalLightMath.CubeFaceOfEveryDirectionHoldsIt and ParaboloidProjectionCoversEachHemisphere,
// the shader side by the render tests (LocalLightTest)
// PointLightCubeMapAgreesWithRayCastsAwayFromEdges and
// PointLightDualParaboloidAgreesWithRayCastsAwayFromEdges: a face or hemisphere the shader picks
// differently from the one these views drew would fail them.
#pragma once

#include <array>
#include <glm/glm.hpp>
#include <span>

#include "components/bounds.h"
#include "runtime/math/cascade_math.h"  // NearFar

namespace kaskad {

/// Distances from `position` (metres) that hold every box: near = the smallest distance from the
/// point to any box (0 when the point is inside one), far = the largest distance to a box corner.
/// Boxes farther than `range` (> 0) are left out and far is clamped to range. Empty when no box
/// is left.
NearFar local_light_near_far(const glm::vec3& position, std::span<const Aabb> boxes,
                             float range = 0.0f);

/// The near plane actually used for a map: 0.9 x the nearest box's view depth, but at least
/// far / 1000 so a light inside a box keeps 24-bit depth precision (1000:1 leaves about 6e-5 x
/// far of depth resolution at the far plane). A perspective map with tan(half fov) = tan_half
/// sees a point at distance d at a view depth down to d / sqrt(1 + 2 tan_half^2) (towards the
/// frustum's corners), so the plane moves that much closer; paraboloid maps clip by distance
/// (tan_half = 0).
float local_light_near(const NearFar& range, float tan_half = 0.0f);

/// tan(half field of view) widened so that a map of `map_size` texels keeps `border_texels`
/// texels outside the cone of half-angle atan(tan_half) on each side: a PCF kernel and the normal
/// offset at the cone's edge stay inside the map. tan_half > 0, map_size > 2 * border_texels.
float widen_tan_half_fov(float tan_half, int map_size, float border_texels);

/// One perspective shadow map: a spot light or one cube face.
struct PerspectiveShadow {
  glm::mat4 view{1.0f};  ///< world -> light view
  glm::mat4 proj{1.0f};  ///< perspective, square
  /// Metres per texel at 1 m from the light along the view axis (the shader multiplies by the
  /// distance: the normal offset bias scales with the texel footprint).
  float texel_at_unit_distance = 0.0f;
  glm::mat4 view_proj() const { return proj * view; }
};

/// tan(half field of view) of a spot light's map: outer_cone_deg widened by border_texels
/// (widen_tan_half_fov), at most tan(89 degrees) (90-degree outer cones keep a 178-degree map,
/// and the cone's rim is not shadowed beyond it).
float spot_tan_half_fov(float outer_cone_deg, int map_size, float border_texels);

/// A spot (or area) light's map: looking along `direction` from `position` with
/// spot_tan_half_fov(), its y axis towards `up` (an area light's local +Y, so its x axis is the
/// light's +X) when that is finite and not parallel to the direction, else light_up_vector().
/// Preconditions: direction non-zero, tan_half > 0, 0 < near < far.
PerspectiveShadow fit_spot_shadow(const glm::vec3& position, const glm::vec3& direction,
                                  float tan_half, float near, float far, int map_size,
                                  const glm::vec3& up = glm::vec3(0.0f));

/// Cube faces in GL order: +X, -X, +Y, -Y, +Z, -Z.
inline constexpr int kCubeFaces = 6;
/// The face a direction from the light falls on: its major axis (ties prefer x, then y), as
/// the GL cube-map face selection. The shader's cube_face() mirrors this (checked as above).
int cube_face_of(const glm::vec3& direction);
/// tan(half field of view) of a cube face: 90 degrees widened by border_texels, so the PCF kernel
/// at a face edge reads this face's own texels, never the border.
inline float cube_tan_half_fov(int map_size, float border_texels) {
  return widen_tan_half_fov(1.0f, map_size, border_texels);
}
/// Face `face` of a cube map at `position`, tan_half from cube_tan_half_fov().
PerspectiveShadow cube_face_shadow(const glm::vec3& position, int face, float tan_half, float near,
                                   float far, int map_size);

// ---- Dual-paraboloid maps -----------------------------------------------------------------------

/// World -> view of hemisphere 0 (looking along `direction`, the light's -Z) and of hemisphere 1
/// (the same turned 180 degrees about its y axis: a rotation, so triangle winding and culling stay
/// as authored). Each hemisphere is the half space z <= 0 of its view.
std::array<glm::mat4, 2> paraboloid_views(const glm::vec3& position, const glm::vec3& direction);

/// Margin of the paraboloid maps: hemispheres are drawn slightly past their rim (to z <= margin
/// of the unit direction) and the disk is scaled by 1 / (1 + margin) so the PCF kernel and the
/// normal offset at the rim read drawn texels. margin = 2 * border_texels / map_size, at most 0.25.
float paraboloid_margin(int map_size, float border_texels);

/// The dual-paraboloid projection of a point given in its hemisphere's view space (z <= 0 is the
/// hemisphere): u = v / |v|; map xy = u.xy / (1 - u.z) / (1 + margin) (the paraboloid of the
/// hemisphere looking down -z), in [-1, 1] inside the hemisphere; z = the distance |v| mapped
/// linearly from [near, far] to [-1, 1]. The depth pass computes it per vertex, so straight
/// edges are drawn straight where the exact image is curved: the tessellation error of
/// paraboloid maps.
glm::vec3 paraboloid_project(const glm::vec3& view_pos, float near, float far, float margin);

/// Metres per texel at 1 m from the light of a paraboloid map: 4 / map_size at the hemisphere's
/// centre (the coarsest place: d(u.x / (1 - u.z)) / dangle = 1/2 there, 1 at the rim).
float paraboloid_texel_at_unit_distance(int map_size, float margin);

}  // namespace kaskad
