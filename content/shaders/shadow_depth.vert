#include "common.glsl"

layout(location = 0) in vec3 a_position;

void main() {
  gl_Position = u_light_view_proj * (u_model * vec4(a_position, 1.0));
}
