#if VARIANT_SHADOW_LAYERED
#extension GL_ARB_shader_viewport_layer_array : require
#endif
#define VERTEX_STAGE_INSTANCED
#include "common.glsl"

// World -> light clip space of the layer being drawn (set per layer by the renderer);
// dual-paraboloid maps: world -> hemisphere view.
layout(location = LOC_LIGHT_VIEW_PROJ) uniform mat4 u_light_view_proj;
#if VARIANT_SHADOW_LAYERED
// Layered pass (all of a view's layers at once): every instance carries the layer of the view it
// goes to (a caster in three layers is three instances), drawn with that layer's matrix into
// array layer u_layer_base + a_layer.
layout(location = LOC_LAYER_BASE) uniform int u_layer_base;
layout(location = LOC_LAYER_VIEW_PROJ) uniform mat4 u_layer_view_proj[MAX_CASCADES];
#endif
#if VARIANT_SHADOW_LAYERED || VARIANT_SHADOW_PEEL
// Layered: the layer of the view; peel (one layer per pass): 1 for a draw that receives
// shadows but does not cast them (stored so that it is shaded, never used as an occluder).
layout(location = ATTR_LAYER) in uint a_layer;
#endif
#if VARIANT_SHADOW_PEEL
flat out uint v_receiver_only;
#endif

layout(location = ATTR_POSITION) in vec3 a_position;
#if MATERIAL_HAS_ALPHA_MASK
layout(location = ATTR_UV) in vec2 a_uv;
out vec2 v_uv;
#endif
#if MATERIAL_HAS_TEXTURE_TRANSFORM
layout(location = ATTR_UV1) in vec2 a_uv1;  // a cut-out on TEXCOORD_1 (features.glsl, slot_uv)
out vec2 v_uv1;
#endif

void main() {
#if MATERIAL_HAS_ALPHA_MASK
  v_uv = a_uv;
#endif
#if MATERIAL_HAS_TEXTURE_TRANSFORM
  v_uv1 = a_uv1;
#endif
#if VARIANT_SHADOW_PEEL
  v_receiver_only = a_layer;
#endif
#if VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_DUAL_PARABOLOID
  // u_light_view_proj is the hemisphere's view; the paraboloid is not a matrix. xy as
  // paraboloid_project() (runtime/math/local_light_math.h), written with w = 1 - u.z so that
  // vertices behind the light (w -> 0) are clipped in clip space instead of divided by ~0. Depth
  // is the distance, linear in [near, far]. Rasterisation interpolates all of this linearly
  // between vertices: the tessellation error of paraboloid maps. The clip distance draws the
  // hemisphere a margin past its rim (z <= margin).
  vec3 v = (u_light_view_proj * (a_model * vec4(a_position, 1.0))).xyz;
  float d = length(v);
  vec3 u = v / max(d, 1e-20);
  // Paraboloid maps are view 0's (only the first shadow view may be a point light).
  float near = view_split(0, 0), far = view_split(0, 1), margin = u_shadow_views[0].params.z;
  float w = 1.0 - u.z;
  gl_Position = vec4(u.xy / (1.0 + margin), (2.0 * (d - near) / (far - near) - 1.0) * w, w);
  gl_ClipDistance[0] = margin - u.z;
#elif VARIANT_SHADOW_LAYERED
  int layer = int(a_layer);
  gl_Layer = u_layer_base + layer;
  gl_Position = u_layer_view_proj[layer] * (a_model * vec4(a_position, 1.0));
#else
  gl_Position = u_light_view_proj * (a_model * vec4(a_position, 1.0));
#endif
}
