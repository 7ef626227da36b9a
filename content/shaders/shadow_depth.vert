#if VARIANT_SHADOW_LAYERED
#extension GL_ARB_shader_viewport_layer_array : require
#endif
#include "common.glsl"

// World -> light clip space of the cascade being drawn (set per layer by the renderer);
// dual-paraboloid maps: world -> hemisphere view.
layout(location = 12) uniform mat4 u_light_view_proj;
#if VARIANT_SHADOW_LAYERED
// Layered pass (all of a light's layers at once): instance i of a draw goes to the i-th set bit
// of u_layer_mask, layer u_layer_base + that bit, with that layer's matrix.
layout(location = 13) uniform uint u_layer_mask;
layout(location = 14) uniform int u_layer_base;
layout(location = 16) uniform mat4 u_layer_view_proj[MAX_CASCADES];
#endif

layout(location = 0) in vec3 a_position;
#if MATERIAL_HAS_ALPHA_MASK
layout(location = 2) in vec2 a_uv;
out vec2 v_uv;
#endif

void main() {
#if MATERIAL_HAS_ALPHA_MASK
  v_uv = a_uv;
#endif
#if VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_DUAL_PARABOLOID
  // u_light_view_proj is the hemisphere's view; the paraboloid is not a matrix. xy as
  // paraboloid_project() (systems/local_light_math.h), written with w = 1 - u.z so that
  // vertices behind the light (w -> 0) are clipped in clip space instead of divided by ~0. Depth
  // is the distance, linear in [near, far]. Rasterisation interpolates all of this linearly
  // between vertices: the tessellation error of paraboloid maps. The clip distance draws the
  // hemisphere a margin past its rim (z <= margin).
  vec3 v = (u_light_view_proj * (u_model * vec4(a_position, 1.0))).xyz;
  float d = length(v);
  vec3 u = v / max(d, 1e-20);
  // Paraboloid maps are view 0's (only the first shadow view may be a point light).
  float near = view_split(0, 0), far = view_split(0, 1), margin = u_shadow_views[0].params.z;
  float w = 1.0 - u.z;
  gl_Position = vec4(u.xy / (1.0 + margin), (2.0 * (d - near) / (far - near) - 1.0) * w, w);
  gl_ClipDistance[0] = margin - u.z;
#elif VARIANT_SHADOW_LAYERED
  uint mask = u_layer_mask;
  for (int i = 0; i < gl_InstanceID; ++i) mask &= mask - 1u;  // drop the lowest set bits
  int layer = findLSB(mask);
  gl_Layer = u_layer_base + layer;
  gl_Position = u_layer_view_proj[layer] * (u_model * vec4(a_position, 1.0));
#else
  gl_Position = u_light_view_proj * (u_model * vec4(a_position, 1.0));
#endif
}
