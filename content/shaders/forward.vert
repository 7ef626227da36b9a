#define VERTEX_STAGE_INSTANCED
#include "common.glsl"

layout(location = ATTR_POSITION) in vec3 a_position;
layout(location = ATTR_NORMAL) in vec3 a_normal;
layout(location = ATTR_UV) in vec2 a_uv;

out vec3 v_world_pos;
out vec3 v_world_normal;
out vec2 v_uv;

void main() {
  vec4 world = a_model * vec4(a_position, 1.0);
  v_world_pos = world.xyz;
  v_world_normal = a_normal_matrix * a_normal;
  v_uv = a_uv;
  gl_Position = u_view_proj * world;
}
