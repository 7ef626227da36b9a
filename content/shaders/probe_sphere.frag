// A sphere map from a probe's cube map, S3 eq. (2), for the current camera: the map is made in
// that camera's view space, so forward.frag looks it up per eq. (4)-(5) with the view-space R.
// Texel (s, t) in [-1, 1]^2 (t up, GL texture convention); outside the unit circle the rim
// direction R = (0, 0, -1) (S3: every rim point maps there), so filtering near the rim stays sane.
in vec2 v_uv;
layout(location = 0) out vec4 o_color;

layout(binding = 0) uniform samplerCube u_cube;
layout(location = 0) uniform mat3 u_view_to_world;  // inverse (transpose) of the view rotation

void main() {
  vec2 st = v_uv * 2.0 - 1.0;
  float r2 = dot(st, st);
  vec3 r_view = vec3(0.0, 0.0, -1.0);
  if (r2 < 1.0) {
    vec3 a = vec3(st, sqrt(1.0 - r2));
    r_view = vec3(2.0 * a.z * a.x, 2.0 * a.z * a.y, 2.0 * a.z * a.z - 1.0);  // S3 eq. (2)
  }
  o_color = vec4(textureLod(u_cube, u_view_to_world * r_view, 0.0).rgb, 1.0);
}
