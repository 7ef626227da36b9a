// The PCF kernels past 3x3 (technique pcf, shadow_filter.glsl): N x N boxes of compare-gathers
// and the rotated Poisson-like disc, with the helpers every wide lookup shares: map coordinates,
// the receiver plane, the per-point disc rotation and the disc itself.
// Map coordinates of world point x in layer i of view k: xy texture coordinates, z depth in
// [0, 1] (S0's M_bias after the projection).
vec3 map_coords(int k, int i, vec3 x) {
  vec4 clip = u_shadow_views[k].view_proj[i] * vec4(x, 1.0);
  return clip.xyz / clip.w * 0.5 + 0.5;
}

// The way view k's light travels at q (unit).
vec3 light_travel(int k, vec3 q) {
  int light = u_shadow_views[k].info.x;
  return u_light_info[light].x == LIGHT_DIRECTIONAL ? u_light_dir[light].xyz
                                                     : normalize(q - u_light_pos[light].xyz);
}

// Receiver plane depth bias (Isidoro, "Shadow Mapping: GPU-based Tips and Techniques", GDC
// 2006): d depth / d uv of the plane through q (map coordinates c) with normal n, so a tap at
// uv offset o compares against c.z + dot(g, o), the plane's own depth there, instead of the
// centre's; kernels wider than 3x3 then need no more slope_bias than 3x3. From the map
// coordinates of two points of the plane `step` metres from q, not from screen derivatives (the
// points pass has none). Clamped to the slope of a plane 83 degrees from facing the light
// (tan = 8), so a plane seen edge-on cannot push the taps' references far behind the map.
vec2 receiver_slope(int k, int i, vec3 q, vec3 n, vec3 c, float step) {
  vec3 t1 = normalize(cross(n, abs(n.y) < 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
  vec3 t2 = cross(n, t1);
  vec3 a = map_coords(k, i, q + step * t1) - c;
  vec3 b = map_coords(k, i, q + step * t2) - c;
  float det = a.x * b.y - a.y * b.x;
  if (abs(det) < 1e-20) return vec2(0.0);
  // g . a.xy = a.z and g . b.xy = b.z (Cramer's rule).
  vec2 g = vec2(a.z * b.y - a.y * b.z, a.x * b.z - a.z * b.x) / det;
  // Depth per uv of that steepest plane: depth per metre along the light x metres per uv x 8.
  float along = abs(map_coords(k, i, q + step * light_travel(k, q)).z - c.z);
  float lateral = length(a.xy) + length(b.xy);  // uv per `step` metres, two directions
  float limit = 8.0 * along * 2.0 / max(lateral, 1e-20);
  float len = length(g);
  return len > limit ? g * (limit / len) : g;
}

// PCG3D (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020).
uvec3 pcg3d(uvec3 v) {
  v = v * 1664525u + 1013904223u;
  v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
  v ^= v >> 16u;
  v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
  return v;
}

// The disc kernels' rotation at world point q (map coordinates c in layer i of view k): a hash
// of the cell, an eighth of a texel wide, of the map's texel grid that q falls in, numbered in
// world-fixed coordinates, so a surface point keeps its angle while the camera moves and rotated
// kernels trade banding for noise without shimmering. A cascade's grid moves in whole texels
// (stable fit), which renumbers map coordinates: its cells are numbered from the projection's
// linear part alone (no translation), i.e. from q's position along the light's axes in texels.
// A spot map or cube face does not move: its map coordinates serve.
float stable_angle(int k, int i, vec3 q, vec3 c) {
  vec2 grid = c.xy;
  bool ortho = true;
#if VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_PERSPECTIVE || \
    VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_CUBE
  ortho = k != 0;
#endif
  if (ortho) grid = 0.5 * (mat3(u_shadow_views[k].view_proj[i]) * q).xy;
  ivec2 cell = ivec2(floor(grid * (8.0 * u_frame.y)));
  uvec3 h = pcg3d(uvec3(uvec2(cell), uint(view_first_layer(k) + i)));
  return float(h.x >> 8u) * (6.28318531 / 16777216.0);
}

// Tap i of n of a disc of radius 1: Vogel's sunflower spiral (r = sqrt((i + 1/2) / n), angle i x
// the golden angle), a Poisson-disc-like pattern that stays even for every n (the first n of a
// stored Poisson set do not), turned by `angle`.
vec2 disc_tap(int i, int n, float angle) {
  float r = sqrt((float(i) + 0.5) / float(n));
  float a = float(i) * 2.39996323 + angle;
  return r * vec2(cos(a), sin(a));
}

// The point of [-1, 1]^2 that Shirley and Chiu's concentric map ("A Low Distortion Map Between
// Disk and Square", 1997) sends to p of the unit disc: the inverse map, area-preserving, so
// taps even over the disc stay even over the square.
vec2 square_from_disc(vec2 p) {
  float r = length(p);
  if (r <= 0.0) return vec2(0.0);
  float phi = atan(p.y, p.x);  // (-pi, pi]
  if (phi < -0.78539816) phi += 6.28318531;  // [-pi/4, 7 pi/4)
  const float k = 1.27323954;  // 4 / pi
  if (phi < 0.78539816) return vec2(r, phi * k * r);
  if (phi < 2.35619449) return vec2(-(phi - 1.57079633) * k * r, r);
  if (phi < 3.92699082) return vec2(-r, -(phi - 3.14159265) * k * r);
  return vec2((phi - 4.71238898) * k * r, -r);
}

// PCF over a disc of `radius` texels, `taps` linear-filtered compares, each against the receiver
// plane (slope g).
float disc_pcf(int layer, vec3 c, vec2 g, float radius, int taps, float angle) {
  float scale = radius / u_frame.y;
  float sum = 0.0;
  for (int i = 0; i < taps; ++i) {
    vec2 o = disc_tap(i, taps, angle) * scale;
    sum += texture(u_shadow_linear, vec4(c.xy + o, float(layer), c.z + dot(g, o)));
  }
  return sum / float(taps);
}

#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_PCF && \
    VARIANT_SHADOW_KERNEL != VARIANT_SHADOW_KERNEL_POISSON
// Side of the N x N box: 5, 7 or 9 (VARIANT_SHADOW_KERNEL 1, 2, 3).
#define PCF_SIDE (2 * VARIANT_SHADOW_KERNEL + 3)
// The N x N nearest compares of texels t - h .. t + h around the point's texel t (h = (N - 1) / 2)
// as compare-gathers over the (N + 1)^2 block, as the 3x3 in shadow_taps() (which this equals
// for N = 3 up to the receiver plane): a gather at texel coordinate t - h + 1 + 2i returns
// texels t - h + 2i and t - h + 2i + 1, and the last gather of each row and column drops its
// texel t + h + 1. Components: x (i0, j1), y (i1, j1), z (i1, j0), w (i0, j0). Each gather
// compares against the receiver plane at its centre.
float box_pcf(int layer, vec3 c, vec2 g) {
  const int h = (PCF_SIDE - 1) / 2;
  vec2 size = vec2(textureSize(u_shadow_map, 0).xy);
  vec2 t = floor(c.xy * size);
  float sum = 0.0;
  for (int j = 0; j <= h; ++j) {
    for (int i = 0; i <= h; ++i) {
      vec2 uv = (t + vec2(float(2 * i + 1 - h), float(2 * j + 1 - h))) / size;
      vec4 s = textureGather(u_shadow_map, vec3(uv, float(layer)), c.z + dot(g, uv - c.xy));
      float wi = i < h ? 1.0 : 0.0, wj = j < h ? 1.0 : 0.0;
      sum += s.w + wi * s.z + wj * s.x + wi * wj * s.y;
    }
  }
  return sum / float(PCF_SIDE * PCF_SIDE);
}
#endif

#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_PCF
float wide_taps(int k, int i, vec3 c, vec3 q, vec3 n, float texel) {
  int layer = view_first_layer(k) + i;
  vec2 g = receiver_slope(k, i, q, n, c, texel);
#if VARIANT_SHADOW_KERNEL == VARIANT_SHADOW_KERNEL_POISSON
  return disc_pcf(layer, c, g, u_shadow_views[k].soft.y, int(u_shadow_views[k].soft.z),
                  stable_angle(k, i, q, c));
#else
  return box_pcf(layer, c, g);
#endif
}
#endif
