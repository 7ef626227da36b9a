// The frame's Cascades phase: one shadow view per shadowed light, all in one depth texture array.
// A view holds the cascades of a directional light (S0 with S2's stabilisation), the perspective
// map of a spot light, or the six cube faces or two paraboloid hemispheres of a point light.
// Maths on the CPU only (cascade_math.h, local_light_math.h); the renderer draws one depth layer
// per cascade (or face, or hemisphere) from the views published here (systems/frame.cpp turns
// them into render::ShadowView, the shaders read them as u_shadow_views).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "components/bounds.h"
#include "components/light.h"
#include "components/shadow_settings.h"
#include "runtime/ecs/world.h"
#include "components/limits.h"
#include "runtime/render/frame_input.h"
#include "systems/camera_system.h"
#include "runtime/math/cascade_math.h"
#include "systems/shadow_map_system.h"

namespace kaskad {

/// One shadowed light's view this frame: what the renderer and the stats need of it.
/// The size of `light` in the units soft shadows need (ShadowData::light_size). A directional
/// light of angular size theta is a cone of directions: a blocker at distance D above a receiver
/// (along the light) hides it from directions within theta / 2 of the axis up to D tan(theta / 2)
/// to each side, so the penumbra is 2 D tan(theta / 2) wide (= D tan(theta) to first order):
/// 2 tan(theta / 2) per metre of D. A spot or point light is a square of side l = 2 radius, an
/// area light its rectangle. x: along the map's x axis (an area light's width, local X), y:
/// along its y axis (height, local Y); x = y for the others.
glm::vec2 light_size_for_shadows(const Light& light);

struct ShadowData {
  ecs::Entity light = ecs::kNullEntity;  ///< the shadowed light, null when there is none
  /// The light's own (else defaults), except the fields that belong to the shared texture array
  /// and the frame's shader features (for_each_shared_field()) are the first view's in every view
  /// (update_shadows() warns when they differ).
  ShadowSettings settings;
  /// ortho: a directional light's cascades; perspective: a spot light's map; cube or
  /// dual_paraboloid: a point light's maps (settings.point_mode).
  ShadowProjection projection = ShadowProjection::ortho;
  /// Layers published, 0: none. Directional: the cascades (settings.cascade_count); spot: 1;
  /// cube: 6 faces (+X, -X, +Y, -Y, +Z, -Z); dual_paraboloid: 2 hemispheres. "Cascade" below
  /// means layer for the local lights.
  int cascade_count = 0;
  /// Its first layer in the shared depth texture array: views follow each other, layers
  /// first_layer .. first_layer + cascade_count - 1.
  int first_layer = 0;
  /// World -> light clip space per cascade (cascade 0 is the basic map with FitMode::scene);
  /// dual_paraboloid: world -> hemisphere view (paraboloid_views(); the projection is not a
  /// matrix).
  std::array<glm::mat4, kMaxCascades> view_proj{};
  /// S0's D: D[0] = camera near .. D[count] = the end of the last cascade, metres of view depth.
  /// FitMode::scene: [0, 3.4e38] (one map covers every depth). Spot and point lights: [near, far]
  /// of the maps, metres from the light (local_light_near_far()).
  std::array<float, kMaxCascades + 1> splits{};
  /// dual_paraboloid: how far past its rim each hemisphere is drawn (paraboloid_margin()).
  float paraboloid_margin = 0.0f;
  /// The light's size as soft shadows use it (light_size_for_shadows()): directional, the
  /// penumbra width per metre between blocker and receiver, 2 tan(angular size / 2); spot and
  /// point, the emitter's width l = 2 radius, metres; area, its width and height. 0: punctual.
  glm::vec2 light_size{0.0f};
  /// Metres per shadow-map texel of each cascade (the larger of x and y). Spot and point lights:
  /// metres per texel at 1 m from the light (the shader scales by the distance).
  std::array<float, kMaxCascades> texel_size{};
  /// No receiver lies in the cascade's volume: its layer is cleared, nothing drawn.
  std::array<bool, kMaxCascades> skipped{};
  /// Shadow casters overlapping each cascade's light volume, sorted: only these are drawn into
  /// that layer.
  std::array<std::vector<ecs::Entity>, kMaxCascades> casters{};
  /// The part of each layer the lookups can read, in the layer's NDC x/y (min x, min y, max x,
  /// max y): the receivers within the cascade's camera slice (from the start of the previous
  /// cascade's blend band) by receiver_rect(), grown by the lookup's reach, the normal offset
  /// and a texel. The depth pass clears and draws only this rectangle. The whole layer,
  /// [-1, 1]^2, where no slice bounds the lookups: map-bounds selection, the basic map (fit
  /// scene), spot and point lights. Empty (min > max) when no receiver lies in the slice.
  std::array<glm::vec4, kMaxCascades> read_rect = render::whole_layers();
  /// Bit i: cascade i kept last frame's fit (ShadowSettings::far_cascade_interval): matrix,
  /// texel size, read rectangle and casters; the renderer keeps its depth.
  std::uint32_t held = 0;
  /// The view-depth range the cascades could span, [camera near, min(camera far,
  /// max_distance)], and the one they span: the visible receivers' range
  /// (visible_receiver_depths()) clipped to it and rounded outwards (quantize_depth_range()).
  float near_requested = 0.0f, far_requested = 0.0f;
  float near_used = 0.0f, far_used = 0.0f;
  /// Why there is no shadow (a non-finite transform, a bad camera), or an entity left out; empty
  /// when all is well.
  std::string error;

  /// Bit i set when `e` is drawn into cascade i.
  std::uint8_t cascade_mask(ecs::Entity e) const;
};

/// State the system owns between frames (the player keeps it): the last error per shadowed light
/// and the last notice, so each is logged once, not every frame.
struct ShadowCascadeState {
  std::array<std::string, kMaxShadowedLights> last_errors;
  std::string last_notice;
  /// Each slot's last result: ShadowSettings::freeze_cascades keeps its splits and matrices.
  std::array<ShadowData, kMaxShadowedLights> previous;
  /// Frames fitted so far (the far-cascade cadence counts them).
  std::uint64_t frame = 0;
};

/// The view of the first Light with cast_shadows (entity order), as update_shadows() fits it, or
/// one with a null light and the reason (`error`) when that light has no maps. Tests and tools
/// that look at one light. A spot light gets one
/// perspective map around its outer cone, a point light six cube faces or two paraboloid
/// hemispheres (settings.point_mode), all with near/far fitted to the casters and receivers within
/// the light's range (layers without receivers skipped, casters culled per layer; the cascade
/// settings do not apply). A directional light: fits its
/// cascades to `camera`: splits (S0 eq. (1)-(3)) between the camera near and min(camera far,
/// max_distance, farthest visible receiver), each cascade by fit_cascade() (crop or stable) with
/// the near plane pulled back to the casters; cascades without receivers are skipped; casters are
/// culled per cascade. FitMode::scene reproduces the basic map (fit_ortho_light_to_bounds).
/// A non-finite light or camera transform gives no shadow and an error, never a crash; entities
/// with non-finite bounds are left out. Needs current WorldTransform/WorldBounds.
ShadowData update_shadow_cascades(const ecs::World& world, const CameraState& camera,
                                  ShadowCascadeState& state);

/// Phase 3: one view per shadowed light (Lights with cast_shadows among the first kMaxLights
/// lights, entity order), at most kMaxShadowedLights, each fitted with its own settings as S0
/// asks of several lights; empty when no light casts. Views share the texture array's and the
/// shaders' settings (see ShadowData::settings; a warning logged once names the fields when a
/// light's own differ). A spot or point light gets a view only as the first shadowed light
/// (its projection is a shader feature); later ones are lit without shadows, and lights beyond
/// kMaxShadowedLights are left out, each with a warning logged once. A light whose settings or
/// transform are invalid gets no view (its error is logged once); the others keep theirs.
/// first_layer numbers the layers of the views in order.
std::vector<ShadowData> update_shadows(const ecs::World& world, const CameraState& camera,
                                       ShadowCascadeState& state);

// ---- Pure parts, exposed for tests -------------------------------------------------------------

/// A view-depth interval (metres, -z of view space); empty when nothing was seen.
struct DepthRange {
  float near = 0.0f, far = 0.0f;
  bool empty() const { return !(far >= near && far > 0.0f); }
};

/// The view depths that the visible parts of `receivers` occupy: every box is clipped exactly to
/// the frustum of `view_proj` (the vertices of box-and-frustum: clipped box faces and the frustum
/// corners inside the box), so a ground plane seen in part counts only where it is seen. This is
/// the [min, max] of Sample Distribution Shadow Maps (Lauritzen et al. 2011) taken from the
/// receivers' bounds on the CPU instead of a depth-buffer reduction: exact for the bounds, no
/// frame of latency, no GPU read-back; conservative for what lies inside a box.
DepthRange visible_receiver_depths(const glm::mat4& view, const glm::mat4& view_proj,
                                   std::span<const Aabb> receivers);

/// `r` rounded outwards to a geometric grid (4 steps per octave: near down, far up), so that a
/// small camera move keeps the same range, splits and stable-fit sizes (S2: a stable cascade
/// needs a fixed projection size). Needs 0 < near <= far.
DepthRange quantize_depth_range(DepthRange r);

/// The receivers' part of an orthographic map: the NDC x/y bounds, through `light_view_proj`, of
/// each box of `receivers` that meets the camera slice with corners `slice_corners` (the points
/// that read the map; slice_corners_world() order; tested against its six face planes and
/// against its NDC bounds in x, y and z), clipped to those bounds in x/y; their union grown
/// by `margin_ndc` on every side, within [-1, 1]^2. As (min x, min y, max x, max y); empty
/// (min > max) when no box overlaps.
/// `touched`, when given, gets the world bounds of the boxes that overlap.
glm::vec4 receiver_rect(const glm::mat4& light_view_proj,
                        const std::array<glm::vec3, 8>& slice_corners,
                        std::span<const Aabb> receivers, float margin_ndc,
                        Aabb* touched = nullptr);

/// Whether a caster in `caster` can shadow a point in `receivers` under a directional light
/// travelling along `light_dir`. False when a face plane of the caster's box that faces the
/// light has the whole receiver box on its lit side: a ray from such a point towards the light
/// never goes back across the plane to the caster (a ray along the plane counts only when the
/// receiver box lies strictly beside the caster). A flat caster (a ground plane) lies in its own
/// face plane, so it may serve as its own receiver. True when neither is proven.
bool may_shadow(const Aabb& caster, const Aabb& receivers, const glm::vec3& light_dir);

/// Indices of the boxes that overlap the clip volume [-1, 1]^3 of `light_view_proj` (corner test
/// against each plane; conservative), in order.
std::vector<std::uint32_t> cull_casters(const glm::mat4& light_view_proj,
                                        std::span<const Aabb> casters);

}  // namespace kaskad
