// Depth only: colour writes are off; the rasteriser writes depth (with glPolygonOffset bias).
// Alpha-masked materials discard their cut-out texels so they cast cut-out shadows; blended
// materials come here as alpha-masked ones (VariantKey::filtered_for()): they cast where
// alpha >= alpha_cutoff.
//
// Peeling (VARIANT_SHADOW_PEEL, S1's multi-layer depth map, LomPass): layer j keeps the nearest
// surface strictly behind layer j - 1 (u_peel_previous, read at the same texel): fragments at or
// in front of it are discarded and the depth test keeps the nearest of the rest. The same
// program and state draw every layer, so a surface's fragments have bit-identical depths in
// each pass and an exact compare peels it once. The depth goes to a colour target, negated for
// draws that receive shadows without casting them.
#include "common.glsl"
#include "features.glsl"

#if MATERIAL_HAS_ALPHA_MASK
in vec2 v_uv;
#endif
#if VARIANT_SHADOW_PEEL
layout(binding = UNIT_PEEL_PREVIOUS) uniform sampler2D u_peel_previous;  // signed depth, 0: none
flat in uint v_receiver_only;
layout(location = 0) out float o_depth;
#endif

void main() {
#if MATERIAL_HAS_ALPHA_MASK
  if (ENABLED(BIT_ALPHA_MASK)) {
    vec2 uv = slot_uv(UV_SLOT_BASE_COLOR, v_uv);
    float alpha = u_base_color.a * texture(u_base_color_tex, uv).a;
    if (alpha < u_material.w) discard;
  }
#endif
#if VARIANT_SHADOW_PEEL
  if (gl_FragCoord.z <= abs(texelFetch(u_peel_previous, ivec2(gl_FragCoord.xy), 0).r)) discard;
  o_depth = v_receiver_only != 0u ? -gl_FragCoord.z : gl_FragCoord.z;
#endif
}
