// Cascaded shadow maps, the maths only (STYLE.md 4): split distances (S0 eq. (1)-(3)), slice
// corners (S0 step 1), the light view, the two fits of a cascade's light projection (S0's crop
// matrix, S2's stabilised bounding sphere with texel snapping), near/far clipping (S2's
// ComputeNearAndFar, S0 step 3's caster pull-back) and the shading helpers the shader mirrors
// (cascade selection, blend weight, S0's M_bias). Pure GLM: no GL, no ECS.
//
// Conventions: OpenGL clip space (x, y, z in [-1, 1]); view spaces look down -z; a "depth" is a
// distance in front of a view's origin along its view axis (= -z_view), the zNear/zFar convention
// of glm::ortho. Matrices are column-major glm. Internally the fits run in double precision;
// results are float.
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "components/bounds.h"
#include "components/camera.h"
#include "components/limits.h"
#include "components/shadow_settings.h"

namespace kaskad {

// ---- Splits (S0 eq. (1)-(3)) --------------------------------------------------------------------

/// The N+1 split distances D[0] = near < D[1] < ... < D[N] = far (metres of view depth), by S0
/// eq. (1) uniform, (2) log or (3) mixed = lambda * (2) + (1 - lambda) * (1). D[0] and D[N] are
/// exactly `near` and `far`; the values strictly increase. Preconditions (KASKAD_CHECK):
/// 0 < near < far, both finite, count in [1, kMaxCascades], lambda in [0, 1] (used by mixed only),
/// and [near, far] wide enough to hold N distinct floats.
std::vector<float> split_distances(SplitScheme scheme, int count, float near, float far,
                                   float lambda);

// ---- Camera slices (S0 step 1) ------------------------------------------------------------------

/// One slice F_i of the camera frustum: the camera's shape plus the depths d_i, d_{i+1}.
struct CameraSlice {
  glm::mat4 camera_world{1.0f};  ///< view -> world (M_cam), rigid: rotation and translation only
  Projection projection = Projection::perspective;
  float fov_y_rad = 0.8726646f;  ///< perspective: full vertical field of view, radians, in (0, pi)
  float ortho_height = 10.0f;    ///< orthographic: full view height, metres, > 0
  float aspect = 1.0f;           ///< width / height, > 0
  float near = 0.1f;             ///< d_i: view depth where the slice starts, metres, >= 0
  float far = 1.0f;              ///< d_{i+1}: view depth where it ends, metres, > near
};

/// S0 step 1 for a perspective camera, in world space: h = d tan(fov_y / 2), w = h * aspect;
/// P0(-w, h, -d_near), P1(w, h, -d_near), P2(w, -h, -d_near), P3(-w, -h, -d_near), P4..P7 the same
/// at d_far; each transformed by camera_world (view -> world).
std::array<glm::vec3, 8> slice_corners_world(const glm::mat4& camera_world, float fov_y_rad,
                                             float aspect, float d_near, float d_far);

/// The orthographic camera's slice: a box, h = ortho_height / 2 at both depths, same corner order.
std::array<glm::vec3, 8> slice_corners_world_ortho(const glm::mat4& camera_world,
                                                   float ortho_height, float aspect, float d_near,
                                                   float d_far);

/// Either of the above, by slice.projection.
std::array<glm::vec3, 8> slice_corners_world(const CameraSlice& slice);

/// A sphere enclosing the slice. The radius is a function of the slice's shape only (near, far,
/// fov or ortho height, aspect), never of camera_world, so a fit sized by it keeps its size
/// while the camera moves and turns (S2). It is the smallest sphere through the slice's corners:
/// centred on the view axis where the near and far corner circles are equidistant, or at the far
/// rectangle's centre when that circle alone dominates (wide slices).
struct BoundingSphere {
  glm::vec3 center{0.0f};  ///< world space
  float radius = 0.0f;     ///< metres
};
BoundingSphere slice_bounding_sphere(const CameraSlice& slice);

// ---- The light ----------------------------------------------------------------------------------

/// The world axis least parallel to `light_dir`, used as lookAt's up so that no light direction
/// (straight down, along any axis) degenerates. Ties prefer y, then x. Shared with the basic map
/// (shadow_map_system.cpp).
inline glm::vec3 light_up_vector(const glm::vec3& light_dir) {
  const glm::vec3 a = glm::abs(light_dir);
  if (a.y <= a.x && a.y <= a.z) return {0.0f, 1.0f, 0.0f};
  if (a.x <= a.z) return {1.0f, 0.0f, 0.0f};
  return {0.0f, 0.0f, 1.0f};
}

/// World -> light view (M_light): eye at `origin`, looking along `light_dir` (the way light
/// travels; any non-zero length), up from light_up_vector(). Right-handed like glm::lookAt.
/// The x/y axes depend on the direction only, so a fixed origin gives a fixed texel grid.
glm::mat4 light_view_matrix(const glm::vec3& light_dir, const glm::vec3& origin);

/// A directional light as the fits see it.
struct LightFrame {
  glm::vec3 direction{0.0f, -1.0f, 0.0f};  ///< the way light travels; non-zero, finite
  glm::vec3 origin{0.0f};  ///< a point on the light axis (the light entity's position). Keep it
                           ///< fixed while the camera moves: the stable fit snaps relative to it.
                           ///< S0's beam cylinder (radius R) is centred on this axis
  /// The light entity's local +Y: an area light's map is oriented by it (its rectangle's
  /// height along the map's y). Need not be unit or perpendicular to `direction`.
  glm::vec3 up{0.0f, 0.0f, 1.0f};
};

// ---- Near / far (S2 ComputeNearAndFar, S0 step 3) -----------------------------------------------

/// A depth range of the light view (distances along the light from its origin). `empty` when
/// nothing was found; near/far are then 0.
struct NearFar {
  float near = 0.0f;
  float far = 0.0f;
  bool empty = true;
};

/// S2's ComputeNearAndFar: the 12 triangles of `scene_bounds` (world space), taken to light view
/// space, clipped against the 4 side planes x = min_x, x = max_x, y = min_y, y = max_y of the light
/// frustum; near/far are the min/max depth of what remains. This is exactly the depth range of
/// the box inside the prism (every vertex of the box-prism intersection lies on the box's surface). Empty when
/// the box misses the rectangle or is empty.
NearFar compute_near_far(const glm::mat4& light_view, const Aabb& scene_bounds, float min_x,
                         float max_x, float min_y, float max_y);

/// Tighter depth range from per-object boxes (world space), for a slice covering the light-space
/// rectangle and the depths [slice_near, slice_far]:
///  - far: the farthest point of any receiver inside the slice volume (rectangle x depths);
///  - near: the nearest receiver point in that volume, pulled back (S0 step 3) to the nearest
///    caster inside the rectangle that lies in front of that far (so it can shadow a receiver),
///    even when the caster is outside the camera's view.
/// Each box's range inside the rectangle is exact (compute_near_far per box). Empty when no
/// receiver overlaps the slice volume: the cascade has nothing to shadow.
NearFar tighten_near_far(const glm::mat4& light_view, std::span<const Aabb> casters,
                         std::span<const Aabb> receivers, float min_x, float max_x, float min_y,
                         float max_y, float slice_near, float slice_far);

// ---- Fitting one cascade ------------------------------------------------------------------------

/// What the scene offers the depth fit; every part may be empty. When casters or receivers are
/// given, tighten_near_far() is used; else the scene box through compute_near_far(); else the
/// slice's own depth range.
struct ShadowGeometry {
  Aabb scene;                       ///< world bounds of everything (S2's scene AABB)
  std::span<const Aabb> casters;    ///< world bounds of each shadow caster
  std::span<const Aabb> receivers;  ///< world bounds of each shadow receiver
};

/// How far the depth range is tightened.
enum class DepthFit {
  enclose_slice,  ///< [min(slice near, caster near), slice far]: the whole slice is inside the
                  ///< light clip volume, casters in front of it too (S0 step 3)
  tight,          ///< [nearest caster or receiver, farthest receiver in the slice] (S2's "tighter
                  ///< still"); slice parts where there is no geometry may fall outside
};

struct CascadeFitOptions {
  FitMode mode = FitMode::stable;
  int map_size = 2048;       ///< texels per side, >= 2
  float beam_radius = 0.0f;  ///< crop only: S0's R, metres; 0 = the scene box's light-space extent
  DepthFit depth = DepthFit::enclose_slice;
  bool clip_to_light_bounds = false;  ///< crop only: intersect the crop with M_Lprj's rectangle
                                      ///< (beam or scene): nothing outside it is lit or casts.
                                      ///< S2 notes this changes the size frame to frame
};

/// One cascade's light camera. view_proj() maps every point of the slice into [-1, 1]^3 (with
/// DepthFit::enclose_slice and clip_to_light_bounds off), up to float resolution: a cascade only
/// millimetres wide, far from the world origin, is placed to about 1e-7 x |coordinates|.
struct CascadeFit {
  glm::mat4 view{1.0f};  ///< world -> light view (M_light)
  glm::mat4 proj{1.0f};  ///< light view -> clip (M_proj,i = M_crop,i * M_Lprj,i for crop)
  float near = 0.0f;     ///< depth of the near plane along the light, metres
  float far = 1.0f;      ///< depth of the far plane, metres
  float world_units_per_texel = 0.0f;  ///< metres per texel (the larger of x and y for crop)
  glm::vec2 ortho_min{0.0f};           ///< light-view x/y of the map's lower-left edge, metres
  glm::vec2 ortho_max{0.0f};  ///< upper-right edge; the map spans exactly ortho_max - ortho_min
  bool empty = false;  ///< nothing to shadow (no receiver in the slice, or the slice is outside
                       ///< the clipped beam); the matrices are still valid
  glm::mat4 view_proj() const { return proj * view; }
};

/// Fits the light camera of one cascade (procedure in cascade_math.cpp, steps cite S0/S2).
/// crop: S0 steps 2-5. stable: S2's bounding sphere of side 2r, origin snapped to whole texels;
/// texels are u = 2r / (map_size - 1) wide so the map (map_size * u = 2r + u) is one texel larger
/// than the fitted area, as S2 requires; its depth range snapped outwards to whole steps of r / 2,
/// so a small camera move changes only the x/y translation, by whole texels (the renderer then
/// scrolls the layer instead of redrawing it). Preconditions (KASKAD_CHECK): validate_camera_slice()
/// and validate_light_frame() pass, map_size >= 2, beam_radius finite and >= 0.
CascadeFit fit_cascade(const CameraSlice& slice, const LightFrame& light,
                       const CascadeFitOptions& options, const ShadowGeometry& geometry = {});

// ---- Shading helpers (the shader's shadow.glsl computes the same; tests/render/
// cascade_selection_test.cpp compares the two) -----------------------------------------------------

/// S0: the cascade i with D[i] <= view_depth < D[i+1] (view_depth = |z_view|), -1 outside
/// [D[0], D[N]) or for fewer than 2 distances.
int select_cascade_by_depth(std::span<const float> D, float view_depth);

/// The first cascade whose clip volume holds world_pos: x and y in [-1 + border, 1 - border]
/// (border in NDC units, e.g. a PCF kernel's reach), z in [-1, 1]. -1 when none does.
int select_cascade_by_map(std::span<const glm::mat4> light_view_proj, const glm::vec3& world_pos,
                          float border_ndc = 0.0f);

/// Weight of cascade + 1 when blending from `cascade` (depth selection): 0 before the last
/// `blend_band` fraction of [D[i], D[i+1]], rising linearly to 1 at D[i+1]. 0 for the last
/// cascade, outside the range, or blend_band <= 0. Shader: mix(shadow_i, shadow_i+1, weight).
float cascade_blend_weight(std::span<const float> D, int cascade, float view_depth,
                           float blend_band);

/// The same for map selection: the point's NDC in its cascade; 0 inside, rising linearly to 1
/// over the outer `blend_band` fraction of the usable half-width 1 - border_ndc (the border
/// select_cascade_by_map() keeps free), reaching 1 where that cascade stops being selected.
float cascade_blend_weight_map(const glm::vec3& ndc, float blend_band, float border_ndc = 0.0f);

/// S0's M_bias: NDC [-1, 1]^3 -> texture space [0, 1]^3 (P_tex = M_bias * P_LNDCS).
glm::mat4 shadow_bias_matrix();

// ---- Validation (for errors instead of crashes) -------------------------------------------------

/// Empty when every element is finite, else e.g. "element [3][1] is NaN".
std::string validate_transform(const glm::mat4& m);

/// Empty when the slice can be fitted: finite rigid camera_world, fov in (0, pi), aspect > 0,
/// ortho_height > 0, 0 <= near < far, all finite. Else a message naming the bad value.
std::string validate_camera_slice(const CameraSlice& slice);

/// Empty when direction is finite and non-zero and origin is finite.
std::string validate_light_frame(const LightFrame& light);

}  // namespace kaskad
