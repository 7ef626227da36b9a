// The shadow-points pass: the visibility the forward pass writes to the AOV (the shadow view
// u_counts.z names) at a fixed world point, through the
// forward pass's own lookup (shadow.glsl), with the same view depth the forward pass would use
// for a surface at that point. Output: x visibility (1 without a shadow pass), y cascade (-1
// outside every cascade), z the blend weight of the next cascade that the lookup used (0 where it
// did not blend).
#include "common.glsl"
#include "features.glsl"
#include "shadow.glsl"

flat in vec3 v_point;
flat in vec3 v_point_normal;

layout(location = 0) out vec4 o_visibility;

void main() {
  float visibility = 1.0, blend = 0.0;
  int cascade = -1;
#if VARIANT_HAS_SHADOW
  int k = u_counts.z;
  float view_depth = -(u_view * vec4(v_point, 1.0)).z;
  visibility = shadow_visibility(k, v_point, normalize(v_point_normal), view_depth, cascade);
  bool cascades = true;  // spot and point views do not blend
#if VARIANT_SHADOW_PROJECTION != VARIANT_SHADOW_PROJECTION_ORTHO
  cascades = k != 0;
#endif
  if (cascades && cascade >= 0) blend = blend_weight(k, cascade, v_point, view_depth);
#endif
  o_visibility = vec4(visibility, float(cascade), blend, 0.0);
}
