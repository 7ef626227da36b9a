// The shadow-points pass: the visibility the forward pass writes to the AOV (the shadowed light
// u_counts.w names: 0 the first, k the k-th extra one) at a fixed world point, through the
// forward pass's own lookup (shadow.glsl), with the same view depth the forward pass would use
// for a surface at that point. Output: x visibility (1 without a shadow pass), y cascade (-1
// outside every cascade).
#include "common.glsl"
#include "features.glsl"
#include "shadow.glsl"

flat in vec3 v_point;
flat in vec3 v_point_normal;

layout(location = 0) out vec2 o_visibility;

void main() {
  float visibility = 1.0;
  int cascade = -1;
#if VARIANT_HAS_SHADOW
  float view_depth = -(u_view * vec4(v_point, 1.0)).z;
  vec3 n = normalize(v_point_normal);
  visibility = shadow_visibility(v_point, n, view_depth, cascade);
#if EXTRA_SHADOWS > 0
  for (int k = 0; k < EXTRA_SHADOWS; ++k)  // as forward.frag picks the AOV's light
    if (k + 1 == u_counts.w) {
      int c;
      visibility = extra_shadow_visibility(k, v_point, n, view_depth, c);
      cascade = c;
    }
#endif
#endif
  o_visibility = vec2(visibility, float(cascade));
}
