// The world direction through face coordinates (s, t) in [0, 1]^2 of cube face `face` (GL order
// +X -X +Y -Y +Z -Z), OpenGL 4.5 section 8.13, table 8.19 (runtime/assets/env_map.h has the
// same table): sc = 2s - 1, tc = 2t - 1.
#ifndef KASKAD_CUBE_FACE_GLSL
#define KASKAD_CUBE_FACE_GLSL

vec3 cube_face_direction(int face, vec2 st) {
  vec2 c = st * 2.0 - 1.0;
  if (face == 0) return vec3(1.0, -c.y, -c.x);
  if (face == 1) return vec3(-1.0, -c.y, c.x);
  if (face == 2) return vec3(c.x, 1.0, c.y);
  if (face == 3) return vec3(c.x, -1.0, -c.y);
  if (face == 4) return vec3(c.x, -c.y, 1.0);
  return vec3(-c.x, -c.y, -1.0);
}

#endif
