// Depth only: colour writes are off; the rasteriser writes depth (with glPolygonOffset bias).
// Alpha-masked materials discard their cut-out texels so they cast cut-out shadows.
#include "common.glsl"
#include "features.glsl"

#if MATERIAL_HAS_ALPHA_MASK
in vec2 v_uv;
#endif

void main() {
#if MATERIAL_HAS_ALPHA_MASK
  if (ENABLED(BIT_ALPHA_MASK)) {
    vec2 uv = slot_uv(UV_SLOT_BASE_COLOR, v_uv);
    float alpha = u_base_color.a * texture(u_base_color_tex, uv).a;
    if (alpha < u_material.w) discard;
  }
#endif
}
