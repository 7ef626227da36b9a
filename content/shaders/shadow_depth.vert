#include "common.glsl"

// World -> light clip space of the cascade being drawn (set per layer by the renderer).
layout(location = 12) uniform mat4 u_light_view_proj;

layout(location = 0) in vec3 a_position;
#if MATERIAL_HAS_ALPHA_MASK
layout(location = 2) in vec2 a_uv;
out vec2 v_uv;
#endif

void main() {
#if MATERIAL_HAS_ALPHA_MASK
  v_uv = a_uv;
#endif
  gl_Position = u_light_view_proj * (u_model * vec4(a_position, 1.0));
}
