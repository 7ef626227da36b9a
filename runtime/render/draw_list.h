// The frame's draw list: every draw's program key per pass and the order draws are submitted in,
// computed once per frame, and culling against a view. Pure: no GL (the passes in
// runtime/render/passes.h record from it).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "components/shadow_technique.h"
#include "components/transform.h"
#include "runtime/render/frame_input.h"
#include "runtime/features/variant_key.h"

namespace kaskad::render {

/// The frame features of a frame (shadow, filter, AOVs): the VARIANT_* part of every key.
VariantKey frame_variant(const FrameInput& frame);
/// The traits of the shadow technique of frame features `frame` (pcf's when it has no shadow).
inline const ShadowTechniqueTraits& shadow_technique_of(VariantKey frame) {
  return traits(ShadowTechnique(frame.get(VariantKey::kShadowTechnique)));
}
/// The name of technique `t` as files and the VARIANT_SHADOW_TECHNIQUE_* defines spell it.
constexpr std::string_view technique_name(ShadowTechnique t) {
  return kFeatureTable[feature_index("shadow_technique")].values[std::size_t(t)];
}
// The key's technique field names one value per row of the technique table.
static_assert(kFeatureTable[feature_index("shadow_technique")].value_count() ==
                  int(kShadowTechniqueCount),
              "the shadow_technique feature needs one value per ShadowTechnique");
/// The frame features of a probe capture of a frame with features `frame`: no AOVs, and cascades
/// selected by map bounds. S0's view-depth selection measures the main camera's depth, which
/// says nothing about a point behind it or beside it that a probe face sees: that point would
/// fall into cascade 0, whose map does not hold it, and come out lit.
VariantKey capture_frame_variant(VariantKey frame);
/// render.visibility_reproject: whether a frame whose camera alone moved may reproject the
/// stored visibility: with one shadow view, whose stored target has room for the reprojection
/// code beside the visibility (forward.frag).
bool reprojects_visibility(const FrameInput& frame);
/// The frame features of the multisampled colour pass (FrameInput::msaa > 1) of a frame with
/// features `frame`: no AOVs (a single-sample pass draws them), and alpha to coverage.
VariantKey msaa_frame_variant(VariantKey frame);
/// The deform features of a deform job (DEFORM_*: the deform pass's program).
VariantKey deform_variant(const DeformJob& job);
/// The material features of a draw (MATERIAL_* part): from the material's data.
VariantKey material_variant(const DrawItem& draw);
/// The order of materials within draws of one program key (DrawList's orders): textures first
/// (the costliest binds), then the factors. Materials that compare equal (operator==) are
/// neither before the other.
bool material_sorts_before(const Material& a, const Material& b);
// mirrors(): components/transform.h. Draws that mirror and draws that do not are never one call.

/// Every (pass, key) a frame draws with, sorted and unique: what prewarm compiles and what
/// `kaskad variants` lists. Pure: no GL.
std::vector<ProgramRequest> required_programs(const FrameInput& frame);

struct DrawList {
  VariantKey frame_key;  ///< frame_variant() as the driver can build it
  /// Per draw: material_variant() | the frame key, | the capture frame key (probe faces), and |
  /// msaa_frame_variant() of the frame key (the multisampled colour pass; only when
  /// FrameInput::msaa > 1). forward_order serves both: two draws have equal keys exactly when
  /// they have equal msaa_keys, so its runs of one program and material are the same.
  std::vector<VariantKey> keys, capture_keys, msaa_keys;
  /// Draw indices in submission order: sorted by the pass's program key, then by winding
  /// (mirrors()), material and mesh, so program and material state change as rarely as possible
  /// and draws that may be one call are neighbours (stable: ties keep draw order). The forward
  /// and capture orders hold the opaque and alpha-masked draws only; the depth order every draw.
  std::vector<std::uint32_t> depth_order, forward_order, capture_order;
  /// The blended draws (VariantKey::kAlphaBlend), in draw order: each view draws them after its
  /// opaque draws, sorted for it by back_to_front().
  std::vector<std::uint32_t> blend_draws;

  /// The depth-pass key of draw i in shadow view `view`: views after the first are cascades and
  /// use the plain depth program whatever the first view's projection is.
  VariantKey depth_key(std::size_t view, std::uint32_t i) const;
};

/// Keys and orders of `frame` with frame features `frame_key` (capture keys and order only
/// when the frame has probes).
DrawList build_draw_list(const FrameInput& frame, VariantKey frame_key);

/// The plane whose value at a point (dot(plane, (p, 1))) is its distance in front of the camera
/// of world-to-view matrix `view`, along the view direction.
inline glm::vec4 view_depth_plane(const glm::mat4& view) {
  return -glm::vec4(view[0][2], view[1][2], view[2][2], view[3][2]);
}
/// The same plane of a perspective view-projection `view_proj` (a probe face's): its clip w
/// is the distance along the view direction.
inline glm::vec4 clip_depth_plane(const glm::mat4& view_proj) {
  return glm::vec4(view_proj[0][3], view_proj[1][3], view_proj[2][3], view_proj[3][3]);
}

/// `draws` (DrawList::blend_draws) in the order a view draws them: back to front by the
/// distance of each draw's bounds' centre (its model's origin without bounds) along the view
/// direction, dot(depth_plane, (centre, 1)), farthest first; equal distances keep their order.
/// Per object, not per triangle: objects that interpenetrate or overlap in depth may blend in
/// the wrong order (docs/guide/materials.md, "Transparency").
std::vector<std::uint32_t> back_to_front(const FrameInput& frame,
                                         std::span<const std::uint32_t> draws,
                                         const glm::vec4& depth_plane);

/// The draws of `order` that a view with `view_proj` can see, in order: those whose bounds
/// overlap its clip volume (draws without bounds always). `capture`: a probe face's view, which
/// also leaves out the probe's own reflector and its excluded layers. `culled` counts the draws
/// left out for being outside the view.
std::vector<std::uint32_t> visible_draws(const FrameInput& frame,
                                         std::span<const std::uint32_t> order,
                                         const glm::mat4& view_proj, const ProbeJob* capture,
                                         int& culled);

}  // namespace kaskad::render
