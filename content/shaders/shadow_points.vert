// The shadow-points pass (Renderer::shadow_at_points): one GL_POINTS vertex per world point,
// placed on its own pixel of a row-major R/G float target (point i -> pixel (i % width, i / width)).
#include "common.glsl"

layout(location = LOC_TARGET_SIZE) uniform ivec2 u_target_size;

layout(location = ATTR_POSITION) in vec3 a_position;
layout(location = ATTR_NORMAL) in vec3 a_normal;

flat out vec3 v_point;
flat out vec3 v_point_normal;

void main() {
  v_point = a_position;
  v_point_normal = a_normal;
  ivec2 pixel = ivec2(gl_VertexID % u_target_size.x, gl_VertexID / u_target_size.x);
  gl_Position = vec4((vec2(pixel) + 0.5) / vec2(u_target_size) * 2.0 - 1.0, 0.0, 1.0);
  gl_PointSize = 1.0;
}
