// The shadow-points pass: the visibility the forward pass writes to the AOV (the shadow view
// u_counts.z names) at a fixed world point, through the
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
  visibility = shadow_visibility(u_counts.z, v_point, normalize(v_point_normal), view_depth, cascade);
#endif
  o_visibility = vec2(visibility, float(cascade));
}
