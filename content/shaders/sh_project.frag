// Nine spherical-harmonic coefficients of a cube map's radiance (IblMaps::project_sh): drawn
// over a 9 x 1 viewport, fragment i sums texel * Y_i(direction) * solid angle over every texel of
// one small mip level of the source (u_params.x its level, y its size), normalised so the solid
// angles add up to 4 pi. project_sh9() in runtime/assets/env_lighting.cpp is the CPU twin.
#include "cube_face.glsl"

layout(location = 0) out vec4 o_coefficient;

layout(binding = 0) uniform samplerCube u_source;
layout(location = 1) uniform vec4 u_params;  // x source level, y its size (texels)

float sh9_basis(int i, vec3 d) {
  if (i == 0) return 0.282095;
  if (i == 1) return 0.488603 * d.y;
  if (i == 2) return 0.488603 * d.z;
  if (i == 3) return 0.488603 * d.x;
  if (i == 4) return 1.092548 * d.x * d.y;
  if (i == 5) return 1.092548 * d.y * d.z;
  if (i == 6) return 0.315392 * (3.0 * d.z * d.z - 1.0);
  if (i == 7) return 1.092548 * d.x * d.z;
  return 0.546274 * (d.x * d.x - d.y * d.y);
}

void main() {
  int i = int(gl_FragCoord.x);
  int size = int(u_params.y);
  vec3 sum = vec3(0.0);
  float total = 0.0;
  for (int face = 0; face < 6; ++face)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        vec2 st = (vec2(x, y) + 0.5) / float(size);
        vec3 d = cube_face_direction(face, st);
        float r2 = dot(d, d);
        float solid_angle = inversesqrt(r2) / r2;  // (1 + sc^2 + tc^2)^(-3/2), times 4 / size^2
        vec3 dir = d * inversesqrt(r2);
        sum += textureLod(u_source, dir, u_params.x).rgb * (sh9_basis(i, dir) * solid_angle);
        total += solid_angle;
      }
  o_coefficient = vec4(sum * (4.0 * 3.14159265358979323846 / total), 1.0);
}
