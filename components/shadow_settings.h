// Shadow parameters of one shadowed light, kept apart from Light (Bevy's CascadeShadowConfig
// beside DirectionalLight): the map and its bias/filter, and the cascades of a directional light
// (S0, with S2's stabilisation). Plain data; validate_shadow_settings() names the first bad value.
// Each default says where it comes from. The maths lives in runtime/math/cascade_math.h.
#pragma once

#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <tuple>

#include "components/limits.h"
#include "runtime/fields/fields.h"

namespace kaskad {

/// The faces of single-sided casters that a light's shadow leaves out (ShadowSettings::cull);
/// caster_face_blocks() is the whole rule.
enum class CullMode { back, front, none };
constexpr std::array<std::string_view, 3> enum_names(CullMode) { return {"back", "front", "none"}; }
static_assert(enum_names(CullMode{}).size() == std::size_t(CullMode::none) + 1);

/// The faces the shadow pass culls for a caster whose material has Material::double_sided =
/// `double_sided`, under a light with ShadowSettings::cull = `cull`: none for double-sided
/// materials (glTF 2.0 "Double Sided": back-face culling is disabled), else the light's.
constexpr CullMode caster_cull(CullMode cull, bool double_sided) {
  return double_sided ? CullMode::none : cull;
}

/// Which caster faces block a light, the one rule of the shadow pass (depth_draws.cpp: GL face
/// culling by caster_cull()) and of the ray-traced references (ray_tracer.cpp: an occlusion
/// filter) (docs/guide/scenes.md, "Which faces cast shadows"):
///   A triangle of a double-sided material blocks the light with both faces. A triangle of a
///   single-sided material blocks it only with its front face when the light's cull is back
///   (the default), only with its back face when cull is front, and with both when cull is
///   none. The front face is the one whose vertices wind counter-clockwise as authored, after
///   the world transform: a mirroring transform (negative determinant) swaps the faces (glTF
///   2.0 "Transformations"). A face faces the light when the light lies on the side of the
///   triangle's plane its normal points to: its normal points against a directional light's
///   direction, or towards a spot or point light's position. For a light with a size, the
///   shadow map (drawn from the light's centre) decides by the centre and the reference by each
///   point of the emitter it samples: the same for closed meshes, different only for open
///   single-sided faces nearly edge-on to the light.
/// `front_faces_light`: whether the triangle's front face faces the light.
constexpr bool caster_face_blocks(CullMode cull, bool double_sided, bool front_faces_light) {
  switch (caster_cull(cull, double_sided)) {
    case CullMode::back: return front_faces_light;
    case CullMode::front: return !front_faces_light;
    case CullMode::none: break;
  }
  return true;
}
/// none: one hardware-compared tap (nearest); bilinear: one tap with GL_LINEAR compare
/// (hardware 2x2 PCF); pcf3x3: average of a 3x3 neighbourhood of compares (S4).
enum class ShadowFilter { none, bilinear, pcf3x3 };
constexpr std::array<std::string_view, 3> enum_names(ShadowFilter) {
  return {"none", "bilinear", "pcf3x3"};
}
static_assert(enum_names(ShadowFilter{}).size() == std::size_t(ShadowFilter::pcf3x3) + 1);

/// How the view depth range [near, far] is cut into cascades (S0 eq. (1)-(3)).
enum class SplitScheme {
  uniform,  ///< S0 eq. (1): d_i = d_n + (d_f - d_n) i / N
  log,      ///< S0 eq. (2): d_i = d_n (d_f / d_n)^(i / N)
  mixed,    ///< S0 eq. (3): lambda * (2) + (1 - lambda) * (1)
  /// "auto": sample-distribution splits (Lauritzen, Salvi, Lefohn, "Sample Distribution Shadow
  /// Maps", I3D 2011): S0 eq. (2) over the view-depth range the visible receivers actually
  /// occupy (the range every scheme uses, see ShadowSettings::max_distance). Log splits are
  /// the right partition once that range is tight; lambda is not used.
  automatic,
};
constexpr std::array<std::string_view, 4> enum_names(SplitScheme) {
  return {"uniform", "log", "mixed", "auto"};
}
static_assert(enum_names(SplitScheme{}).size() == std::size_t(SplitScheme::automatic) + 1);

/// Depth attachment format of the shadow maps.
enum class DepthFormat { d16, d24, d32f };
constexpr std::array<std::string_view, 3> enum_names(DepthFormat) { return {"d16", "d24", "d32f"}; }
static_assert(enum_names(DepthFormat{}).size() == std::size_t(DepthFormat::d32f) + 1);

/// How visibility is estimated from the depth map. A frame shader feature
/// (VARIANT_SHADOW_TECHNIQUE), never a uniform branch.
enum class ShadowTechnique {
  pcf,   ///< percentage-closer filtering with a fixed footprint (filter, pcf_kernel): hard shadows
         ///< smoothed over the kernel, whatever the light's size
  pcss,  ///< percentage-closer soft shadows (Fernando 2005): blocker search over a region sized
         ///< by the light, average blocker depth, penumbra width w = l (d_r - d_b) / d_b, then
         ///< PCF over w (Poisson-like disc of pcf_taps taps). Needs a light with a size
         ///< (Light::angular_size_deg or Light::radius); a punctual light gives hard shadows
  backprojection,  ///< Guennebaud, Barthe, Paulin 2006: every depth-map texel in the region
                   ///< PCSS searches that lies in front of the receiver is back-projected from
                   ///< the receiver onto the light and the covered parts of the light summed
                   ///< (overlaps are counted twice: too dark where blockers overlap, S1's point)
  /// S1's layered occlusion map (Xu 2016): pass 1 peels lom_layers depth layers from the light
  /// and stores, per stored point, the fraction of the light its nearest occluders block
  /// (backprojection, each part of the light counted once); pass 2 interpolates those factors
  /// trilinearly at the shaded point. Needs a light with a size, as pcss.
  lom,
  /// Variance shadow maps (Donnelly, Lauritzen, "Variance Shadow Maps", I3D 2006; S2 names
  /// them): the map's moments E[z], E[z^2] of linear depth, blurred (vsm_blur) and mipmapped,
  /// bound the lit fraction by Chebyshev's inequality, p_max = s^2 / (s^2 + (t - mu)^2); the
  /// bound lets light bleed where occluders overlap, cut by vsm_bleed_reduction. A filtered hard
  /// shadow: the penumbra is the blur's, not the light's size.
  vsm,
  /// Exponential variance shadow maps (Lauritzen, McCool, "Layered Variance Shadow Maps", GI
  /// 2008): the moments of a positive and a negative exponential warp of depth, four in all; the
  /// lower of their two Chebyshev bounds. Bleeds much less than vsm.
  evsm,
};
constexpr std::array<std::string_view, 6> enum_names(ShadowTechnique) {
  return {"pcf", "pcss", "backprojection", "lom", "vsm", "evsm"};
}
static_assert(enum_names(ShadowTechnique{}).size() == std::size_t(ShadowTechnique::evsm) + 1);

/// The PCF footprint when filter is pcf3x3 and technique pcf.
enum class PcfKernel {
  k3x3,     ///< S4's 3x3 box of nearest compares (four compare-gathers)
  k5x5,     ///< N x N boxes of nearest compares, from compare-gathers (one per 2x2 texels)
  k7x7,
  k9x9,
  poisson,  ///< pcf_taps taps on a disc of radius pcf_radius texels, rotated per point by a hash
            ///< of its position in the light's texel grid (still when the camera moves)
};
/// Files give the boxes by their side (the JSON integers 3, 5, 7, 9) and the disc by name.
constexpr std::array<std::string_view, 5> enum_names(PcfKernel) {
  return {"3", "5", "7", "9", "poisson"};
}
static_assert(enum_names(PcfKernel{}).size() == std::size_t(PcfKernel::poisson) + 1);

/// How a cascade's light projection is fitted.
enum class FitMode {
  crop,    ///< S0 steps 2-5: M_proj = M_crop * M_Lprj, tight around the slice's 8 corners; the
           ///< size changes as the camera turns, so edges shimmer when the camera moves
  stable,  ///< S2: the slice's bounding sphere (size fixed by the slice's shape), origin snapped
           ///< to whole texels; wastes some area but shadow edges stay still
  scene,   ///< the basic map (S4 with S2's basics): one orthographic light around the bounds of
           ///< the whole scene, independent of the camera. Needs cascade_count = 1
};
constexpr std::array<std::string_view, 3> enum_names(FitMode) { return {"crop", "stable", "scene"}; }
static_assert(enum_names(FitMode{}).size() == std::size_t(FitMode::scene) + 1);

/// How a point light's omnidirectional shadow is stored.
enum class PointShadowMode {
  cube,             ///< six 90-degree perspective faces (+X, -X, +Y, -Y, +Z, -Z), picked by the
                    ///< major axis of the direction from the light; exact up to texel size
  dual_paraboloid,  ///< S0's earlier work: two hemispheres, each projected onto a paraboloid
                    ///< ((x, y) / (1 + z) of the unit direction); 2 maps instead of 6, but the
                    ///< projection is not linear, so rasterised triangles are only approximations
                    ///< (tessellation error: large triangles need subdividing)
};
constexpr std::array<std::string_view, 2> enum_names(PointShadowMode) {
  return {"cube", "dual_paraboloid"};
}
static_assert(enum_names(PointShadowMode{}).size() == std::size_t(PointShadowMode::dual_paraboloid) + 1);

/// The projection of a light's shadow maps, derived from the light type and point_mode (not
/// authored): directional cascades are orthographic, a spot light has one perspective map, a
/// point light six cube faces or two paraboloid hemispheres. Selects shader code
/// (VARIANT_SHADOW_PROJECTION).
enum class ShadowProjection { ortho, perspective, cube, dual_paraboloid };
constexpr std::array<std::string_view, 4> enum_names(ShadowProjection) {
  return {"ortho", "perspective", "cube", "dual_paraboloid"};
}
static_assert(enum_names(ShadowProjection{}).size() == std::size_t(ShadowProjection::dual_paraboloid) + 1);

/// How a shaded point picks its cascade.
enum class CascadeSelection {
  depth,       ///< S0: slice i where D[i] <= |z_view| < D[i+1]
  map_bounds,  ///< the first cascade whose map contains the point (uses the stable fit's slack)
};
constexpr std::array<std::string_view, 2> enum_names(CascadeSelection) {
  return {"depth", "map_bounds"};
}
static_assert(enum_names(CascadeSelection{}).size() == std::size_t(CascadeSelection::map_bounds) + 1);

/// Per shadowed light, except the fields for_each_shared_field() lists: every light's layers share
/// one texture array and the shader features are per frame, so the first shadowed light's values
/// of these apply to all (update_shadows() warns once, naming the fields, when another light's
/// own differ).
struct ShadowSettings {
  /// Texels per side of the map (of each cascade); power of two in [64, 16384]. 2048: engine
  /// choice, the size of the first basic map.
  int map_size = 2048;
  float constant_bias = 2.0f;     ///< glPolygonOffset units (multiples of the depth resolution)
  float slope_bias = 3.0f;        ///< glPolygonOffset factor (scales with the depth slope, S2).
                                  ///< 3 because the 3x3 PCF taps reach 1.5 texels along each axis,
                                  ///< where depth changes by up to 1.5 (|dz/dx| + |dz/dy|), at most
                                  ///< 3x the max slope that glPolygonOffset scales by; 2 leaves acne
                                  ///< rings on the default scene's ground plane
  /// Faces of single-sided casters left out of this light's shadow (caster_face_blocks(), the
  /// shadow pass and the references alike; double-sided materials cast from both faces). back
  /// is the default for the shadow pass (S2); front reduces acne but loses single-sided casters
  /// that face the light, such as planes and open meshes (S4, S2); none casts from both faces.
  CullMode cull = CullMode::back;
  ShadowFilter filter = ShadowFilter::pcf3x3;  ///< S4's 3x3 PCF by default
  /// pcf: today's hard-edged PCF (the default); pcss: soft shadows from the light's size.
  ShadowTechnique technique = ShadowTechnique::pcf;
  /// Footprint of filter pcf3x3 with technique pcf. 3x3 by default (S4). Wider kernels reach
  /// (N - 1) / 2 texels and use a receiver-plane depth bias (Isidoro 2006) on top of slope_bias.
  PcfKernel pcf_kernel = PcfKernel::k3x3;
  /// Taps of the Poisson-like disc, in [8, 64], for pcf_kernel poisson and for pcss's blocker
  /// search and filter. 16: NVIDIA's PCSS sample (Bavoil, "Integrating Realistic Soft Shadows
  /// into Your Game Engine", 2008) uses 16 Poisson taps for each of the two steps.
  int pcf_taps = 16;
  /// Radius of the poisson kernel in texels, in [1, 16]. 2.5: about the reach of a 5x5 box.
  float pcf_radius = 2.5f;
  /// technique lom: depth layers peeled per shadow-map layer, in [2, 16]. 8: S1's experiments.
  /// Each costs one more scene render per cascade (or face) and map_size^2 x 5 bytes.
  int lom_layers = 8;
  /// technique vsm/evsm: side in texels of the separable Gaussian blur of the moments, odd, in
  /// [1, 15] (1: no blur; sigma = side / 4, so the kernel ends at two sigmas). 5: the reach of
  /// the 5x5 PCF box and of the default poisson disc (2.5 texels); Lauritzen (GPU Gems 3,
  /// ch. 8) blurs with small separable kernels and leaves larger footprints to the mipmaps.
  int vsm_blur = 5;
  /// technique vsm/evsm: light-bleeding reduction, in [0, 1): Chebyshev bounds below it read as
  /// shadow and the rest is rescaled to [0, 1] (linstep(amount, 1, p_max), Lauritzen, GPU Gems 3
  /// ch. 8). 0.2: the low end of the 0.2-0.3 the chapter suggests; more darkens penumbrae.
  float vsm_bleed_reduction = 0.2f;

  /// N, in [1, 8]. 4: S0 recommends 3..5 (fewer is barely better than one map; each more costs
  /// a scene render).
  int cascade_count = 4;
  /// auto by default: the splits follow the visible receivers at any scale (SDSM, above);
  /// mixed (S0 eq. (3), the paper's choice) with a fixed max_distance is the fully
  /// camera-independent alternative.
  SplitScheme split_scheme = SplitScheme::automatic;
  /// Mixed-split weight of the log scheme, in [0, 1]. 0.5: S0's default.
  float lambda = 0.5f;
  /// Scene units of view depth where the last cascade ends at most: a user cap. 0 (JSON also
  /// "auto", the default) = no cap. Whatever the cap, the cascades span only the view depths of
  /// the visible receivers, [nearest, farthest] (S0 step 3 and S2's tight near/far, taken to the
  /// receivers; the range SDSM measures), clipped to the camera's near and far, so models from
  /// millimetres to kilometres get shadows with no setting changed.
  float max_distance = 0.0f;
  /// S2: 16 bits suffice when near/far are tight; 24 because S0 step 3 pulls the near plane back
  /// to distant casters, which loosens the range (and the basic map's format).
  DepthFormat depth_format = DepthFormat::d24;
  /// S2: stabilised cascades do not shimmer as the camera moves.
  FitMode fit_mode = FitMode::stable;
  /// Metres, >= 0: S0's searchlight cylinder radius R around the light axis (through the light
  /// entity's position); 0 = fit to the scene. Used by FitMode::crop only.
  float beam_radius = 0.0f;
  /// Texels of the cascade, in [0, 16]: shading points move this far along the normal before
  /// the lookup. 1 texel as in MJP's 2015 shadow sample update (offset scaled by texel size).
  /// Not used by FitMode::scene (the basic map is biased by polygon offset only).
  float normal_offset_bias = 1.0f;
  /// Fraction of a cascade's depth range, in [0, 1], over which it fades into the next one
  /// (with map_bounds selection: fraction of the map's half-width); 0 = hard seams. 0.1: engine
  /// choice.
  float blend_band = 0.1f;
  /// S0's D array by default.
  CascadeSelection selection = CascadeSelection::depth;
  /// Colours each cascade in the forward pass (MJP's "visualise cascades", Filament's
  /// d.shadowmap.visualize_cascades). A debug view, off by default.
  bool debug_cascades = false;
  /// Keeps the cascades' splits and matrices of the frame it was turned on while the camera
  /// moves on (MJP's "freeze cascades"), to look at them from elsewhere. Directional lights; a
  /// debug toggle, off by default.
  bool freeze_cascades = false;
  /// Draw every cascade (or cube face) of a light in one pass: one instanced draw per caster,
  /// the vertex shader picks the layer (gl_Layer, GL_ARB_shader_viewport_layer_array; drivers
  /// without it fall back to false). false: one pass per layer. Same maps either way (render
  /// test, exact). false by default: on llvmpipe, once the terrain was tiled (so casters overlap
  /// few cascades), one pass per layer made content/scenes/terrain.json's frame faster and
  /// default.json no slower (docs/design/batching.md, "Layered shadow pass"). Dual-paraboloid
  /// maps always draw per layer. Taken from the first shadowed light for all.
  bool layered = false;
  /// Directional lights with view-depth selection: leave out of a cascade the casters whose
  /// shadow cannot fall on the receivers it serves (may_shadow(): e.g. a ground plane when every
  /// receiver of the cascade lies above it). Same images (render test); off for comparisons.
  bool cull_by_receivers = true;
  /// Directional lights with view-depth selection: clear and draw only the part of each cascade
  /// that its receivers' lookups read (ShadowData::read_rect), not the whole layer. Same images
  /// (render test); off for comparisons.
  bool scissor_to_receivers = true;
  /// Directional lights, in [1, 16]: cascade i >= 1 is refitted and redrawn at most every k-th
  /// frame (staggered: when (frame + i) % k == 0); between, it keeps its matrix and depth while
  /// that map still covers every point that reads it (else it is refitted at once). Moving
  /// casters' shadows in those cascades lag by up to k - 1 frames. 1 (off) by default, as in
  /// Godot's and Unity's optional far-cascade update rates.
  int far_cascade_interval = 1;
  /// Point lights only. cube by default: exact for any tessellation; dual_paraboloid draws 2
  /// maps instead of 6 (S0's earlier work).
  PointShadowMode point_mode = PointShadowMode::cube;
};

/// The fields of ShadowSettings, once (runtime/fields/fields.h). kShared marks those every
/// shadowed light takes from the first (one texture array, one set of shader features).
constexpr auto field_table(fields::Of<ShadowSettings>) {
  using S = ShadowSettings;
  using namespace fields;
  return std::tuple{
      integer("map_size", &S::map_size, 64, 16384, "Texels per side of each map (cascade, face)",
              kPowerOfTwo | kShared),
      number("constant_bias", &S::constant_bias, 0, 1.0e4,
             "Depth bias in glPolygonOffset units (multiples of the depth resolution)"),
      number("slope_bias", &S::slope_bias, 0, 100,
             "Depth bias scaled by the depth slope (glPolygonOffset factor)"),
      choice("cull", &S::cull,
             "Faces of single-sided casters that cast no shadow (shadow pass and references)"),
      choice("filter", &S::filter, "Depth compares per lookup: one, hardware 2x2, or a kernel",
             kShared),
      choice("technique", &S::technique, "How visibility is estimated from the map", kShared),
      choice("pcf_kernel", &S::pcf_kernel,
             "Footprint of filter pcf3x3 with technique pcf: box side or a Poisson disc", kShared),
      integer("pcf_taps", &S::pcf_taps, 8, 64,
              "Taps of the Poisson disc (pcf_kernel poisson, pcss's search and filter)"),
      number("pcf_radius", &S::pcf_radius, 1, 16, "Radius of the Poisson disc, texels"),
      integer("lom_layers", &S::lom_layers, 2, 16,
              "technique lom: depth layers peeled per map layer", kShared),
      integer("vsm_blur", &S::vsm_blur, 1, 15,
              "technique vsm/evsm: side of the moments' Gaussian blur, texels", kOdd | kShared),
      number("vsm_bleed_reduction", &S::vsm_bleed_reduction, 0, 1,
             "technique vsm/evsm: Chebyshev bounds below this read as shadow",
             kBelowHi | kShared),
      integer("cascade_count", &S::cascade_count, 1, 8, "Cascades of a directional light"),
      choice("split_scheme", &S::split_scheme,
             "How the view depth range is cut into cascades (auto follows the receivers)"),
      number("lambda", &S::lambda, 0, 1, "Weight of the log scheme in mixed splits"),
      number("max_distance", &S::max_distance, 0, kMaxCoordinate,
             "View depth where the last cascade ends at most; 0 or auto: no cap", kAutoIsZero),
      choice("depth_format", &S::depth_format, "Depth format of the maps", kShared),
      choice("fit_mode", &S::fit_mode, "How a cascade's projection is fitted"),
      number("beam_radius", &S::beam_radius, 0, kMaxCoordinate,
             "fit_mode crop: radius of the light's beam around its axis; 0 fits the scene"),
      number("normal_offset_bias", &S::normal_offset_bias, 0, 16,
             "Texels a shaded point moves along its normal before the lookup"),
      number("blend_band", &S::blend_band, 0, 1,
             "Fraction of a cascade over which it fades into the next; 0: hard seams"),
      choice("selection", &S::selection, "How a shaded point picks its cascade", kShared),
      flag("debug_cascades", &S::debug_cascades, "Colours each cascade", kDebug | kShared),
      choice("point_mode", &S::point_mode, "How a point light's shadow is stored"),
      flag("freeze_cascades", &S::freeze_cascades,
           "Keeps the cascades of the frame it was turned on while the camera moves on", kDebug),
      flag("layered", &S::layered, "Draws every layer of a light in one pass", kShared),
      flag("cull_by_receivers", &S::cull_by_receivers,
           "Leaves out of a cascade the casters whose shadow cannot reach its receivers"),
      flag("scissor_to_receivers", &S::scissor_to_receivers,
           "Draws only the part of each cascade its receivers read"),
      integer("far_cascade_interval", &S::far_cascade_interval, 1, 16,
              "Cascade i >= 1 is redrawn at most every k-th frame"),
  };
}

/// The fields every shadowed light takes from the first (kShared in the table): calls
/// visit(key, a.field, b.field) for each.
template <typename A, typename B, typename Visit>
void for_each_shared_field(A& a, B& b, Visit&& visit) {
  fields::for_each_field<ShadowSettings>([&](const auto& f) {
    if (f.has(fields::kShared)) visit(f.key.data(), a.*f.member, b.*f.member);
  });
}

// filter_reach_texels(): components/shadow_technique.h, from the technique table.

/// Empty string when valid, else a message naming the first bad value, e.g.
/// "lambda must be in [0, 1], was 1.2": the table's ranges, then the rules across fields.
inline std::string validate_shadow_settings(const ShadowSettings& s) {
  if (std::string bad = fields::validate_fields(s); !bad.empty()) return bad;
  if (s.fit_mode == FitMode::scene && s.cascade_count != 1)
    return "fit_mode scene needs cascade_count 1, was " + std::to_string(s.cascade_count);
  return {};
}

}  // namespace kaskad
