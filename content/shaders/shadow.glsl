// The shadow lookup, shared by every pass that shades with shadows: the forward pass and the
// stability probe pass (shadow_points.*), so that both evaluate visibility with the same code.
// Needs common.glsl and features.glsl first.
#if VARIANT_HAS_SHADOW
layout(binding = UNIT_SHADOW) uniform sampler2DArrayShadow u_shadow_map;  // one layer per cascade
// The wide lookups (issue 14): PCF kernels past 3x3 and PCSS. They compare each tap against the
// receiver plane (receiver_slope()) and rotate their discs per point (stable_angle()).
#if VARIANT_SHADOW_TECHNIQUE != VARIANT_SHADOW_TECHNIQUE_PCF || \
    (VARIANT_SHADOW_FILTER == VARIANT_SHADOW_FILTER_PCF3X3 && \
     VARIANT_SHADOW_KERNEL != VARIANT_SHADOW_KERNEL_3X3)
#define SHADOW_WIDE 1
// The same map compared with linear filtering: each disc tap is a hardware 2x2 PCF, so few taps
// still give smooth ramps.
layout(binding = UNIT_SHADOW_LINEAR) uniform sampler2DArrayShadow u_shadow_linear;
#endif
#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_PCSS || \
    VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_BACKPROJECTION || \
    VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_LOM
#define SHADOW_SIZED 1  // lookups that use the light's size (PcssMap below)
#endif
#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_VSM || \
    VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_EVSM
#define SHADOW_MOMENTS 1  // variance shadow maps (MomentsPass, vsm() below)
// The moments of every layer (MomentsPass): blurred, mipmapped, read trilinear.
layout(binding = UNIT_VSM_MOMENTS) uniform sampler2DArray u_vsm_moments;
#endif
#if defined(SHADOW_SIZED) || defined(SHADOW_MOMENTS)
// The same map without compare: raw depths for PCSS's blocker search and backprojection, and
// for the moments pass.
layout(binding = UNIT_SHADOW_DEPTH) uniform sampler2DArray u_shadow_depth;
#endif
#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_LOM
// S1's layered occlusion map (LomPass, runtime/render/passes.h): per shadow-map layer, lom_layers
// depth peels plus one overflow peel (signed depths: negative for surfaces that receive shadows
// without casting them; 1 where a peel found nothing), and the occlusion factor of every stored
// point (the blocked fraction of the light), same layout. Nearest filtering, border depth 1.
layout(binding = UNIT_LOM_DEPTH) uniform sampler2DArray u_lom_depth;
layout(binding = UNIT_LOM_OCCLUSION) uniform sampler2DArray u_lom_occlusion;

// Depth layers per shadow-map layer (ShadowSettings::lom_layers).
int lom_layers() { return int(u_frame.z); }
// Array slice of peel j (0 .. lom_layers(), the last the overflow peel) of shadow-map layer
// `layer`: the peels of a layer follow each other.
int lom_slice(int layer, int j) { return layer * (lom_layers() + 1) + j; }
// The stored depth of peel j at texel t (signed as above).
float lom_depth(ivec2 t, int layer, int j) {
  return texelFetch(u_lom_depth, ivec3(t, lom_slice(layer, j)), 0).r;
}
#endif
#endif

// Visibility of shadow view k's light at world position p with geometric normal n: 1 lit, 0
// shadowed (S4, with S0's cascades). Every view goes through the same functions, indexed by k
// (u_shadow_views[k]); its layers are first_layer .. first_layer + layer count - 1 of the array.
// Clamp-to-border with border depth 1 and the z > 1 test keep everything outside a layer's light
// frustum lit. Cascade selection and blending: select_cascade_by_depth / select_cascade_by_map /
// cascade_blend_weight* in runtime/math/cascade_math.h, tested against this code in
// tests/render/cascade_selection_test.cpp. View 0 may be a spot or point light
// (VARIANT_SHADOW_PROJECTION != ORTHO; runtime/math/local_light_math.h): its layers are the spot map,
// cube faces or paraboloid hemispheres, view_split(0, 0..1) hold near and far (metres from the
// light), and view_texel(0, i) is metres per texel at 1 m from the light.
#if VARIANT_HAS_SHADOW
// Shadow views of this variant (u_counts.y holds the same number). A compile-time count, so the
// loops over views unroll and a frame with one shadowed light has no code for more: on llvmpipe
// a loop whose uniform bound is 0 still runs its body once with every lane masked off, which
// cost a quarter of the default scene's frame.
#define SHADOW_VIEWS VARIANT_SHADOW_LIGHTS

// Layer count and first layer of view k. View 0's are constants of the variant (its cascade
// count; layers start at 0), so its selection loops end at a constant; the others' are data.
int view_layers(int k) {
#if VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_ORTHO
  if (k == 0) return VARIANT_CASCADE_COUNT;
#endif
  return u_shadow_views[k].info.z;
}
int view_first_layer(int k) { return k == 0 ? 0 : u_shadow_views[k].info.y; }

// The filtered depth compare of array layer `layer` at c: xy texture coordinates, z depth in
// [0, 1].
float shadow_taps(int layer, vec3 c) {
  vec4 tc = vec4(c.xy, float(layer), c.z);
#if VARIANT_SHADOW_FILTER == VARIANT_SHADOW_FILTER_PCF3X3
  // S4's 3x3 PCF: the nine nearest-filtered compares of the texels t-1 .. t+1 around the point's
  // texel t, as four compare-gathers over the 4x4 block t-1 .. t+2 (the t+2 row and column are
  // left out). A gather at texel coordinate t returns texels t-1 and t (its footprint starts at
  // floor(t - 0.5)), half a texel from either edge, so rounding cannot shift it. Components:
  // x (i0, j1), y (i1, j1), z (i1, j0), w (i0, j0). Equal to nine textureOffset taps
  // (tests/render/shadow_lookup_test.cpp).
  vec2 size = vec2(textureSize(u_shadow_map, 0).xy);
  vec2 t = floor(c.xy * size);
  vec2 lo = t / size, hi = (t + 2.0) / size;
  vec4 g00 = textureGather(u_shadow_map, vec3(lo, tc.z), c.z);        // t-1, t  x  t-1, t
  vec4 g10 = textureGather(u_shadow_map, vec3(hi.x, lo.y, tc.z), c.z);  // t+1     x  t-1, t
  vec4 g01 = textureGather(u_shadow_map, vec3(lo.x, hi.y, tc.z), c.z);  // t-1, t  x  t+1
  vec4 g11 = textureGather(u_shadow_map, vec3(hi, tc.z), c.z);        // t+1     x  t+1
  float sum = g00.x + g00.y + g00.z + g00.w + g10.x + g10.w + g01.z + g01.w + g11.w;
  return sum / 9.0;
#else
  return texture(u_shadow_map, tc);  // filtering (nearest / linear) is set on the texture
#endif
}

#ifdef SHADOW_WIDE
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

#ifdef SHADOW_SIZED
// Percentage-closer soft shadows (Fernando, "Percentage-Closer Soft Shadows", SIGGRAPH 2005
// sketch) in layer i of view k at map coordinates c (receiver q). Light size l = soft.x
// (ShadowData::light_size), params.w along the map's y (an area light's rectangle; the others
// are square): the search takes the longer side, the round filter the side of the square of
// the same area. The blocker search and the filter take `taps` disc taps each.
//
// Perspective maps (spot light, cube face): a square light of width l at the centre of
// projection, the receiver at distance d_r along the axis and a blocker at d_b. The ray from
// the receiver to a light point s off the centre (|s| <= l / 2) crosses depth d_b at map
// coordinate (tangent units) x_r / d_r + s (1 / d_b - 1 / d_r): blockers that can hide part of
// the light lie within (l / 2) (d_r - d_b) / (d_b d_r) of the receiver's map point. With
// d_b >= near that is the search radius; with d_b = the average blocker depth it is the filter
// radius, and it is half of Fernando's penumbra w = l (d_r - d_b) / d_b measured at the receiver
// (w / d_r tangent units). view_texel(k, i) is the texel in tangent units (metres at 1 m).
//
// Ortho maps (a directional light's cascades): the light is a cone of directions of apex angle
// theta, l = 2 tan(theta / 2). A ray from the receiver at angle phi <= theta / 2 from the axis
// is D tan(phi) off the receiver's map point at height D above it: the radius is (l / 2) D with
// D = (d_r - d_b) in metres, i.e. the penumbra w = l (d_r - d_b) = 2 (d_r - d_b) tan(theta / 2)
// (~ (d_r - d_b) tan(theta) for small angles), Fernando's similar triangles with the light at
// infinity. Each cascade converts metres to its own texels (view_texel(k, i)) and depth to
// metres by its projection (depth per metre = |third row of view_proj| / 2), so the penumbra is
// the same width in every cascade.
struct PcssMap {
  bool perspective;
  float near, far;         // perspective: the projection's near and far, metres
  float depth_per_metre;   // ortho
  float texel;             // ortho: metres; perspective: tangent units
};

// Depth in [0, 1] -> distance: metres from the map's near plane (ortho), metres from the light
// along the axis (perspective, GL's [-1, 1] clip depth).
float pcss_distance(PcssMap m, float z) {
  return m.perspective ? 2.0 * m.near * m.far / (m.far + m.near - (2.0 * z - 1.0) * (m.far - m.near))
                       : z / m.depth_per_metre;
}

// Radius in texels of the map region where a blocker at distance d_b can hide part of the light
// from a receiver at d_r (above).
float pcss_radius(PcssMap m, float l, float d_r, float d_b) {
  return m.perspective ? 0.5 * l * (d_r - d_b) / (d_b * d_r * m.texel)
                       : 0.5 * l * (d_r - d_b) / m.texel;
}

// Layer i of view k as the sized lookups see it.
PcssMap pcss_map(int k, int i) {
  PcssMap map;
  map.perspective = false;
#if VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_PERSPECTIVE || \
    VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_CUBE
  map.perspective = k == 0;
#endif
  map.near = view_split(k, 0);
  map.far = view_split(k, 1);
  mat4 m = u_shadow_views[k].view_proj[i];
  map.depth_per_metre = 0.5 * length(vec3(m[0][2], m[1][2], m[2][2]));
  map.texel = view_texel(k, i);
  return map;
}

// The light's extent along the map's x and y (ShadowData::light_size).
vec2 light_extent(int k) { return vec2(u_shadow_views[k].soft.x, u_shadow_views[k].params.w); }

// Half the light's extent along the map's axes in the units backprojection works in: metres
// (perspective), or tangent units for a cone (ortho), taken as the square of the same solid
// angle, side l sqrt(pi) / 2.
vec2 light_half_extent(int k, bool perspective) {
  return 0.5 * light_extent(k) * (perspective ? 1.0 : 0.88622693);  // sqrt(pi) / 2
}
#endif

#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_PCSS
float pcss(int k, int i, int layer, vec3 c, vec2 g, float angle) {
  vec2 extent = light_extent(k);
  float l = max(extent.x, extent.y);  // the search: every blocker that can hide part of it
  int taps = int(u_shadow_views[k].soft.z);
  PcssMap map = pcss_map(k, i);
  float d_r = pcss_distance(map, c.z);
  // 1. Blocker search over the region of every blocker between the map's near plane and the
  //    receiver (ortho: the near plane is depth 0).
  float search = clamp(pcss_radius(map, l, d_r, map.perspective ? map.near : 0.0), 1.0,
                       PCSS_MAX_RADIUS);
  float scale = search / u_frame.y;
  float blockers = 0.0, sum = 0.0;
  for (int t = 0; t < taps; ++t) {
    vec2 o = disc_tap(t, taps, angle) * scale;
    float z = texture(u_shadow_depth, vec3(c.xy + o, float(layer))).r;
    if (z < c.z + dot(g, o)) {
      sum += z;
      blockers += 1.0;
    }
  }
  if (blockers == 0.0) return 1.0;  // nothing between the light and the receiver
  // 2. Average blocker depth -> 3. penumbra radius (above) -> 4. PCF over it, at least the
  //    3x3 kernel's reach so contact shadows stay filtered.
  float d_b = pcss_distance(map, sum / blockers);
  if (!map.perspective) {  // a cone of directions: a round filter
    float radius = clamp(pcss_radius(map, sqrt(extent.x * extent.y), d_r, d_b), 1.5, PCSS_MAX_RADIUS);
    return disc_pcf(layer, c, g, radius, taps, angle);
  }
  // A square or rectangular emitter (spot, point, area): the filter has the light's own shape,
  // half-widths pcss_radius() per axis; the disc's taps are carried onto the square by an
  // area-preserving map, so they stay as even (a round filter over a square light's straight
  // edge gave penumbrae 12% too narrow, 10-90%).
  vec2 radius = vec2(pcss_radius(map, extent.x, d_r, d_b), pcss_radius(map, extent.y, d_r, d_b));
  radius = clamp(radius, vec2(1.5), vec2(PCSS_MAX_RADIUS));
  float sum_lit = 0.0;
  for (int t = 0; t < taps; ++t) {
    vec2 o = square_from_disc(disc_tap(t, taps, angle)) * radius / u_frame.y;
    sum_lit += texture(u_shadow_linear, vec4(c.xy + o, float(layer), c.z + dot(g, o)));
  }
  return sum_lit / float(taps);
}
#endif

#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_BACKPROJECTION
// Cells per side of the backprojection kernel: 2 BP_HALF + 1.
#define BP_HALF 12

// Length of [a0, a1] inside [-h, h].
float overlap_1d(float a0, float a1, float h) { return max(0.0, min(a1, h) - max(a0, -h)); }

// Backprojection soft shadows (Guennebaud, Barthe, Paulin, "Real-time Soft Shadow Mapping by
// Backprojection", EGSR 2006) in layer i of view k at map coordinates c. Every depth-map cell in
// PCSS's search region (pcss()) that lies in front of the receiver is a micro-occluder: a square
// as wide as the cell at its stored depth. It is back-projected from the receiver onto the light
// and the part of the light it covers is summed; visibility = 1 - the sum, clamped. Overlapping
// micro-occluders are all counted, so where blockers overlap as seen from the receiver the
// shadow comes out too dark (S1's criticism; layered occlusion maps fix it).
//
// The region: PCSS's blocker search (disc taps over the widest region) finds the blocker nearest
// the light, d_min; only blockers up to there can hide part of the light, so the region is
// pcss_radius(d_min) (S1's kernel from the nearest occluder). It is covered by
// (2 BP_HALF + 1)^2 cells of `step` texels each (step = 1 up to a radius of BP_HALF texels;
// wider regions read one depth per coarser cell, the stand-in for the paper's hierarchical
// map).
//
// Light plane coordinates of a cell u tangent units (perspective) off the receiver's map point,
// at depth d_b, seen from the receiver at d_r: the line from the receiver through it reaches the
// light's plane (distance 0) at u d_r d_b / (d_r - d_b) metres, and the light is the rectangle
// [-w/2, w/2] x [-h/2, h/2] (light_extent(): 2 Light::radius a side, or an area light's size). Ortho: a cell x metres off the receiver's map point at height
// D = d_r - d_b above it is seen in direction x / D (tangent units); the light is the cone of
// half-angle theta / 2, taken as the square of the same solid angle, side
// l sqrt(pi) / 2 (l = 2 tan(theta / 2)).
float backprojection(int k, int i, int layer, vec3 c, vec2 g, float angle) {
  vec2 extent = light_extent(k);
  float l = max(extent.x, extent.y);  // the search, as pcss()
  if (l <= 0.0) return texture(u_shadow_map, vec4(c.xy, float(layer), c.z));  // punctual
  PcssMap map = pcss_map(k, i);
  float size = u_frame.y;
  vec2 half_light = light_half_extent(k, map.perspective);
  float d_r = pcss_distance(map, c.z);
  float search = clamp(pcss_radius(map, l, d_r, map.perspective ? map.near : 0.0), 1.0,
                       PCSS_MAX_RADIUS);
  int taps = int(u_shadow_views[k].soft.z);
  float z_min = c.z;
  for (int t = 0; t < taps; ++t) {
    vec2 o = disc_tap(t, taps, angle) * (search / size);
    float z = texture(u_shadow_depth, vec3(c.xy + o, float(layer))).r;
    if (z < c.z + dot(g, o)) z_min = min(z_min, z);
  }
  if (z_min >= c.z) return 1.0;  // no blocker found
  float radius = clamp(pcss_radius(map, l, d_r, pcss_distance(map, z_min)) + 1.0, 1.0, search);
  float step = max(1.0, ceil(radius / float(BP_HALF)));
  vec2 centre = (floor(c.xy * size) + 0.5) / size;  // the receiver's texel
  float blocked = 0.0;
  for (int y = -BP_HALF; y <= BP_HALF; ++y) {
    for (int x = -BP_HALF; x <= BP_HALF; ++x) {
      vec2 uv = centre + vec2(float(x), float(y)) * (step / size);
      float z = texture(u_shadow_depth, vec3(uv, float(layer))).r;
      if (z >= c.z + dot(g, uv - c.xy)) continue;  // not in front of the receiver
      float d_b = pcss_distance(map, z);
      if (d_b >= d_r) continue;
      // The cell's extent relative to the receiver's map point, in texels, then on the light.
      vec2 lo = (uv - c.xy) * size - 0.5 * step, hi = lo + step;
      float f = map.perspective ? map.texel * d_r * d_b / (d_r - d_b) : map.texel / (d_r - d_b);
      blocked += overlap_1d(lo.x * f, hi.x * f, half_light.x) *
                 overlap_1d(lo.y * f, hi.y * f, half_light.y);
    }
  }
  return clamp(1.0 - blocked / (4.0 * half_light.x * half_light.y), 0.0, 1.0);
}
#endif

#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_LOM
// S1 pass 2: the visibility of the receiver at map coordinates c (its depth plane has slope g)
// in shadow-map layer `layer`, from the occlusion factors of the
// stored points around it. The 4 map samples nearest c (bilinear weights); in each, the stored
// layers whose depths bracket the receiver plane there (depth c.z + g . offset): the upper
// bound is the last layer in front of it, the lower the next one (usually the receiver's own
// surface, which lies on the plane up to a tolerance). Each sample's factor is linear in depth
// between its two bounds, and the four are mixed bilinearly: S1's trilinear interpolation.
// S1's special cases:
//  - no layer in front: a virtual layer at the light (depth 0), factor 0 (lit);
//  - no layer behind (the receiver's surface was not stored, or the layers ran out: the peels
//    found more than lom_layers surfaces there): a virtual layer at the far plane (depth 1),
//    factor 1, so a point below lom_layers light-facing surfaces is taken as in umbra (LomPass
//    counts the texels where the layers ran out: FrameStats::lom_overflow_texels);
//  - the four upper bounds in the same layer: the upper factor is 1 (the receiver is under the
//    same occluder at all four samples, so it is not in penumbra from their lit upper faces).
float lom(int layer, vec3 c, vec2 g) {
  int layers = lom_layers();
  float size = u_frame.y;
  vec2 f = c.xy * size - 0.5;
  ivec2 base = ivec2(floor(f));
  vec2 w = f - vec2(base);
  // A layer within two texels of the plane's slope of it (curvature, slopes past
  // receiver_slope()'s clamp) plus rounding, on either side, is the receiver's own surface: the
  // lower bound. Only layers in front of that are upper bounds.
  float own = 2.0 * (abs(g.x) + abs(g.y)) / size + 4e-6;
  vec4 upper, lower, t, on_surface;  // per sample: factors, the receiver's place between them
  ivec4 upper_layer;
  for (int s = 0; s < 4; ++s) {
    ivec2 texel = clamp(base + ivec2(s & 1, s >> 1), ivec2(0), ivec2(int(size) - 1));
    float z_r = c.z + dot(g, (vec2(texel) + 0.5) / size - c.xy);
    float z_up = 0.0, z_lo = 1.0, f_up = 0.0, f_lo = 1.0;
    int j_up = -1;
    for (int j = 0; j < layers; ++j) {
      float z = abs(lom_depth(texel, layer, j));
      if (z < z_r - own) {
        z_up = z;
        j_up = j;
        continue;
      }
      if (z < 1.0) {
        z_lo = z;
        f_lo = texelFetch(u_lom_occlusion, ivec3(texel, lom_slice(layer, j)), 0).r;
      }
      break;
    }
    if (j_up >= 0) f_up = texelFetch(u_lom_occlusion, ivec3(texel, lom_slice(layer, j_up)), 0).r;
    upper[s] = f_up;
    lower[s] = f_lo;
    upper_layer[s] = j_up;
    on_surface[s] = abs(z_lo - z_r) <= own ? 1.0 : 0.0;
    t[s] = clamp((z_r - z_up) / max(z_lo - z_up, 1e-12), 0.0, 1.0);
  }
  if (upper_layer.x >= 0 && all(equal(upper_layer, upper_layer.xxxx))) upper = vec4(1.0);
  vec4 v = mix(upper, lower, t);
  // Bilinear weights. Beyond S1: where some of the four samples hold the receiver's own surface
  // and others do not (the receiver is near the edge of its surface as the light sees it), only
  // those that do are mixed; the others' bounds are another surface, whose factor says nothing
  // about this one (S1's plain mix darkens lit edges with the shadowed ground below them).
  vec4 weight = vec4((1.0 - w.x) * (1.0 - w.y), w.x * (1.0 - w.y), (1.0 - w.x) * w.y, w.x * w.y);
  if (any(greaterThan(on_surface, vec4(0.0)))) weight = max(weight, 1e-4) * on_surface;
  float factor = dot(weight, v) / dot(weight, vec4(1.0));
  return 1.0 - factor;
}
#endif

#ifdef SHADOW_MOMENTS
// Variance shadow maps (Donnelly, Lauritzen, "Variance Shadow Maps", I3D 2006) and exponential
// variance shadow maps (Lauritzen, McCool, "Layered Variance Shadow Maps", GI 2008; the EVSM of
// Lauritzen's thesis). MomentsPass stores per texel the moments of vsm_warp(linear depth),
// blurred over vsm_blur texels and mipmapped; a lookup filters them over the pixel's footprint
// and bounds the lit fraction of the filter region from them (Chebyshev).

// Depth in [0, 1] of the map -> linear depth in [0, 1]: ortho maps (cascades) are linear
// already; a perspective map (view 0 of a spot or point light) goes through its near and far
// (metres from the light), so the moments are of distance, as the paper's.
float vsm_depth(int k, float z) {
#if VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_PERSPECTIVE || \
    VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_CUBE
  if (k == 0) {
    float n = view_split(0, 0), f = view_split(0, 1);
    float d = 2.0 * n * f / (f + n - (2.0 * z - 1.0) * (f - n));
    return clamp((d - n) / (f - n), 0.0, 1.0);
  }
#endif
  return z;
}

#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_EVSM
// EVSM's exponents c+ and c- of the warps of x = 2 d - 1 in [-1, 1]: 40 and 5, MJP's Shadows
// sample's defaults for 32-bit moments. Both must stay at most 42: the second moment of the
// positive warp reaches e^(2 c+), and e^84 = 3e36 is below the float maximum 3.4e38 (e^88.7); the
// blur and the mipmaps only average. The larger c+, the less light bleeds.
const vec2 EVSM_EXPONENTS = vec2(40.0, 5.0);

// The four moments of linear depth d: e^(c+ x), its square, -e^(-c- x), its square. Both warps
// increase with depth, so a receiver behind its occluders lies above both means.
vec4 vsm_warp(float d) {
  float x = 2.0 * d - 1.0;
  float p = exp(EVSM_EXPONENTS.x * x), n = -exp(-EVSM_EXPONENTS.y * x);
  return vec4(p, p * p, n, n * n);
}
#else
// VSM's moments of linear depth d: d, d^2.
vec4 vsm_warp(float d) { return vec4(d, d * d, 0.0, 0.0); }
#endif

// The smallest variance of depth the lookups accept (VSM's "minimum variance"): 2^-23, the
// rounding of a 32-bit E[d^2] near 1, so E[d^2] - E[d]^2 below it is noise. As a standard
// deviation 3.5e-4 of the map's depth range.
const float VSM_MIN_VARIANCE = 1.1920929e-7;

// The moments of `layer` filtered over the footprint spanned by the gradients dx, dy (texture
// units) around uv. The blur already averages vsm_blur texels (u_counts.w), so a footprint
// within that reads one bilinear tap of level 0; a longer one takes N = min(ceil(P_max /
// max(P_min, blur)), VSM_MAX_ANISOTROPY) trilinear taps spread evenly along its longer axis,
// at the level where each tap's share of it, P_max / N, is one blur wide. Anisotropic filtering
// done here so that it follows these gradients on every driver, costs at most
// VSM_MAX_ANISOTROPY taps, and keeps to level 0 (whole-texel shifts of a stable cascade change
// nothing) while the blur covers the footprint. The sampler's own anisotropy was tried:
// llvmpipe's takes the ellipse from the coordinates' screen derivatives, not from textureGrad's,
// and in non-uniform control flow or at a spot map's near plane scanned thousands of texels per
// pixel (seconds a frame).
const int VSM_MAX_ANISOTROPY = 8;

vec4 moments_filtered(int layer, vec2 uv, vec2 dx, vec2 dy) {
  vec2 size = vec2(textureSize(u_vsm_moments, 0).xy);
  vec2 a = dx * size, b = dy * size;  // texels
  float la = dot(a, a), lb = dot(b, b);
  vec2 axis = la >= lb ? dx : dy;
  float major = sqrt(max(la, lb)), minor = sqrt(min(la, lb));
  float blur = float(u_counts.w);
  // Non-finite gradients (a receiver at the light's plane) read the coarsest level, one tap.
  if (!(major < 1e30)) return textureLod(u_vsm_moments, vec3(uv, float(layer)), 64.0);
  int n = clamp(int(ceil(major / max(minor, blur))), 1, VSM_MAX_ANISOTROPY);
  float lod = max(log2(major / (float(n) * blur)), 0.0);
  vec4 sum = vec4(0.0);
  for (int j = 0; j < VSM_MAX_ANISOTROPY; ++j) {
    if (j >= n) break;
    vec2 at = uv + axis * ((float(j) + 0.5) / float(n) - 0.5);
    sum += textureLod(u_vsm_moments, vec3(at, float(layer)), lod);
  }
  return sum / float(n);
}

// Chebyshev's one-tailed bound (Donnelly, Lauritzen 2006, eq. 5) on the fraction of the filter
// region whose depth is at least t: p_max = s^2 / (s^2 + (t - mu)^2), with mu = m.x, s^2 =
// m.y - m.x^2 (at least min_variance); 1 when t <= mu.
float chebyshev(vec2 m, float t, float min_variance) {
  float variance = max(m.y - m.x * m.x, min_variance);
  float d = t - m.x;
  return t <= m.x ? 1.0 : variance / (variance + d * d);
}

// The camera's pixel at q, metres (u_camera_pos.w, FrameBlock): the side of the region of the
// receiver a pixel covers, ignoring how the view tilts it (the map footprint below includes the
// light's).
float pixel_footprint(vec3 q) {
  float w = u_camera_pos.w;
  return w >= 0.0 ? w * max(-(u_view * vec4(q, 1.0)).z, 0.0)
                  : -w * distance(q, u_camera_pos.xyz);
}

// Visibility from the moments of layer i of view k at map coordinates c (receiver q, normal n).
// The filter region is the pixel's footprint on the receiver's plane, mapped into the layer:
// two tangents of the plane, a pixel long, as the gradients of moments_filtered() (no screen
// derivatives: the points pass has none, and lookups sit in non-uniform control flow). Then
// Chebyshev's bound and the light-bleeding reduction (Lauritzen, GPU Gems 3 ch. 8):
// p -> linstep(a, 1, p), a = vsm_bleed_reduction (u_frame.w): bounds below a, the light that
// bleeds where a second occluder lies between the receiver and the nearest one, become shadow.
float vsm(int k, int i, int layer, vec3 c, vec3 q, vec3 n) {
  float f = pixel_footprint(q);
  vec3 t1 = normalize(cross(n, abs(n.y) < 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
  vec3 t2 = cross(n, t1);
  vec2 dx = map_coords(k, i, q + f * t1).xy - c.xy;
  vec2 dy = map_coords(k, i, q + f * t2).xy - c.xy;
  vec4 m = moments_filtered(layer, c.xy, dx, dy);
  float d = vsm_depth(k, c.z);
  vec4 w = vsm_warp(d);
#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_EVSM
  // The least variance in each warp: VSM_MIN_VARIANCE of depth through the warp's slope
  // (dw / dd = 2 c w), as MJP's sample scales it. The lower of the two bounds.
  vec2 slope = 2.0 * EVSM_EXPONENTS * abs(w.xz);
  float p = min(chebyshev(m.xy, w.x, VSM_MIN_VARIANCE * slope.x * slope.x),
                chebyshev(m.zw, w.z, VSM_MIN_VARIANCE * slope.y * slope.y));
#else
  float p = chebyshev(m.xy, d, VSM_MIN_VARIANCE);
#endif
  float a = u_frame.w;
  return clamp((p - a) / (1.0 - a), 0.0, 1.0);
}
#endif

// The wide lookup of layer i of view k at map coordinates c, for the receiver q (offset point)
// with normal n; texel: metres per texel at q.
float wide_taps(int k, int i, vec3 c, vec3 q, vec3 n, float texel) {
  int layer = view_first_layer(k) + i;
#ifdef SHADOW_MOMENTS
  return vsm(k, i, layer, c, q, n);
#else
  vec2 g = receiver_slope(k, i, q, n, c, texel);
#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_PCSS
  return pcss(k, i, layer, c, g, stable_angle(k, i, q, c));
#elif VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_BACKPROJECTION
  return backprojection(k, i, layer, c, g, stable_angle(k, i, q, c));
#elif VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_LOM
  // At the receiver itself, not the normal-offset point q: pass 1 already kept each stored
  // point's own surface out of its occluders, and the offset would move the four samples
  // sideways off a surface the light grazes (a sphere's rim), onto what lies beside it.
  vec3 p = map_coords(k, i, q - n * (u_shadow_views[k].params.x * texel));
  if (any(lessThan(p.xy, vec2(0.0))) || any(greaterThan(p.xy, vec2(1.0)))) return 1.0;  // border
  return lom(layer, p, g);
#elif VARIANT_SHADOW_KERNEL == VARIANT_SHADOW_KERNEL_POISSON
  return disc_pcf(layer, c, g, u_shadow_views[k].soft.y, int(u_shadow_views[k].soft.z),
                  stable_angle(k, i, q, c));
#else
  return box_pcf(layer, c, g);
#endif
#endif
}
#endif

// Cascade c of view k. The point moves along the normal by normal_offset texels of this cascade
// (MJP's normal offset), so the bias follows each cascade's resolution.
float cascade_visibility(int k, int c, vec3 p, vec3 n) {
  vec3 q = p + n * (u_shadow_views[k].params.x * view_texel(k, c));
  vec4 clip = u_shadow_views[k].view_proj[c] * vec4(q, 1.0);
  vec3 t = clip.xyz / clip.w * 0.5 + 0.5;  // S0's M_bias
  if (t.z > 1.0) return 1.0;
#ifdef SHADOW_WIDE
  return wide_taps(k, c, t, q, n, view_texel(k, c));
#else
  return shadow_taps(view_first_layer(k) + c, t);
#endif
}

#if VARIANT_SHADOW_PROJECTION != VARIANT_SHADOW_PROJECTION_ORTHO
vec3 view_light_position(int k) { return u_light_pos[u_shadow_views[k].info.x].xyz; }

// Spot and point lights: the normal offset in texels of `layer` at the point's distance (a
// perspective texel grows with the distance from the light).
vec3 local_offset_point(int k, int layer, vec3 p, vec3 n) {
  float dist = distance(p, view_light_position(k));
  return p + n * (u_shadow_views[k].params.x * view_texel(k, layer) * dist);
}
#endif

#if VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_PERSPECTIVE || \
    VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_CUBE
// A spot map or one cube face: a perspective projection, otherwise as a cascade.
float perspective_visibility(int k, int layer, vec3 p, vec3 n) {
  vec3 q = local_offset_point(k, layer, p, n);
  vec4 clip = u_shadow_views[k].view_proj[layer] * vec4(q, 1.0);
  if (clip.w <= 0.0) return 1.0;  // behind the light
  vec3 c = clip.xyz / clip.w * 0.5 + 0.5;
  if (c.z > 1.0) return 1.0;
#ifdef SHADOW_WIDE
  return wide_taps(k, layer, c, q, n, view_texel(k, layer) * distance(q, view_light_position(k)));
#else
  return shadow_taps(view_first_layer(k) + layer, c);
#endif
}
#endif

#if VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_CUBE
// The face of direction d (+X, -X, +Y, -Y, +Z, -Z): its major axis, ties prefer x then y.
// Mirrors cube_face_of() in runtime/math/local_light_math.cpp.
int cube_face(vec3 d) {
  vec3 a = abs(d);
  if (a.x >= a.y && a.x >= a.z) return d.x >= 0.0 ? 0 : 1;
  if (a.y >= a.z) return d.y >= 0.0 ? 2 : 3;
  return d.z >= 0.0 ? 4 : 5;
}
#endif

#if VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_DUAL_PARABOLOID
// Dual-paraboloid lookup (S0's earlier work): hemisphere 0 is z <= 0 of the view in
// view_proj[0], hemisphere 1 the rest, seen from the same view turned 180 degrees about y.
// Mirrors paraboloid_views() / paraboloid_project() (runtime/math/local_light_math.h) and
// shadow_depth.vert.
float paraboloid_visibility(int k, vec3 p, vec3 n, out int hemisphere) {
  vec3 q = local_offset_point(k, 0, p, n);
  vec3 v = (u_shadow_views[k].view_proj[0] * vec4(q, 1.0)).xyz;
  hemisphere = v.z <= 0.0 ? 0 : 1;
  if (hemisphere == 1) v = vec3(-v.x, v.y, -v.z);
  float d = length(v);
  vec3 u = v / max(d, 1e-20);
  float near = view_split(k, 0), far = view_split(k, 1), margin = u_shadow_views[k].params.z;
  vec2 xy = u.xy / ((1.0 - u.z) * (1.0 + margin));
  float z = (d - near) / (far - near);
  if (z > 1.0) return 1.0;
  return shadow_taps(view_first_layer(k) + hemisphere, vec3(xy * 0.5 + 0.5, z));
}
#endif

#if VARIANT_CASCADE_SELECTION == VARIANT_CASCADE_SELECTION_MAP_BOUNDS
// Texels the lookup reaches from the point's texel (filter_reach_texels(), in soft.w).
float filter_reach(int k) { return u_shadow_views[k].soft.w; }
// Border kept free in NDC: the lookup's reach plus the normal offset, in texels.
float map_border(int k) { return 2.0 * (filter_reach(k) + u_shadow_views[k].params.x) / u_frame.y; }
#endif

// The cascade of view k at a point, -1 outside all. depth: view depth |z_view|.
int select_cascade(int k, vec3 p, float depth) {
  int count = view_layers(k);
#if VARIANT_CASCADE_SELECTION == VARIANT_CASCADE_SELECTION_MAP_BOUNDS
  float limit = 1.0 - map_border(k);
  for (int i = 0; i < count; ++i) {
    vec4 clip = u_shadow_views[k].view_proj[i] * vec4(p, 1.0);
    vec3 ndc = clip.xyz / clip.w;
    if (abs(ndc.x) <= limit && abs(ndc.y) <= limit && abs(ndc.z) <= 1.0) return i;
  }
  return -1;
#else
  // S0: D[i] <= depth < D[i+1]; nearer than D[0] (the camera near plane) counts as cascade 0.
  if (depth >= view_split(k, count)) return -1;
  int cascade = 0;
  for (int i = 1; i < count; ++i)
    if (depth >= view_split(k, i)) cascade = i;
  return cascade;
#endif
}

// Weight of cascade + 1 of view k in the blend band at the end of `cascade` (0 for the last).
float blend_weight(int k, int cascade, vec3 p, float depth) {
  float band = u_shadow_views[k].params.y;
  if (cascade >= view_layers(k) - 1 || band <= 0.0) return 0.0;
#if VARIANT_CASCADE_SELECTION == VARIANT_CASCADE_SELECTION_MAP_BOUNDS
  vec4 clip = u_shadow_views[k].view_proj[cascade] * vec4(p, 1.0);
  vec2 ndc = abs(clip.xy / clip.w);
  float edge = 1.0 - map_border(k);
  return clamp((max(ndc.x, ndc.y) - (edge - band * edge)) / (band * edge), 0.0, 1.0);
#else
  float d0 = view_split(k, cascade), d1 = view_split(k, cascade + 1);
  float width = band * (d1 - d0);
  return clamp((depth - (d1 - width)) / width, 0.0, 1.0);
#endif
}

// The lookup of `cascade` mixed with the next cascade's by w, the next one's weight in the blend
// band: (1 - w) v_c + w v_c+1, one lookup where w = 0. Written as a loop that ends on a value
// (not `if (w > 0.0)` and not a counted loop, which the compiler unrolls into ifs): llvmpipe
// runs the body of a divergent if for every pixel with the others masked off, so the second
// lookup cost as much as the first; a loop it leaves once no pixel of the SIMD vector wants
// another trip, so only vectors that touch the band pay (on llvmpipe, issue 13: about a tenth of
// the default scene's frame). A GPU branches either way.
float blended_visibility(int k, int cascade, float w, vec3 p, vec3 n) {
  float v = 0.0, weight = 1.0 - w;
  int c = cascade;
  do {
    v += weight * cascade_visibility(k, c, p, n);
    weight = c == cascade ? w : 0.0;
    ++c;
  } while (weight > 0.0);
  return v;
}

// Whether the surface at p with geometric normal n faces light `light` (an index into u_light_*).
// One facing away shadows itself: forward.frag skips its lookup where no AOV shows it.
bool faces_light(int light, vec3 p, vec3 n) {
  vec3 to_light = u_light_info[light].x == LIGHT_DIRECTIONAL ? -u_light_dir[light].xyz
                                                              : u_light_pos[light].xyz - p;
  return dot(n, to_light) > 0.0;
}

// Visibility of shadow view k's light; `cascade` is the layer of the view it read (-1: none).
float shadow_visibility(int k, vec3 p, vec3 n, float depth, out int cascade) {
#if VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_PERSPECTIVE
  if (k == 0) {
    cascade = 0;
    return perspective_visibility(0, 0, p, n);
  }
#elif VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_CUBE
  if (k == 0) {
    cascade = cube_face(p - view_light_position(0));
    return perspective_visibility(0, cascade, p, n);
  }
#elif VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_DUAL_PARABOLOID
  if (k == 0) return paraboloid_visibility(0, p, n, cascade);
#endif
  cascade = select_cascade(k, p, depth);
  if (cascade < 0) return 1.0;
  return blended_visibility(k, cascade, blend_weight(k, cascade, p, depth), p, n);
}

#if VARIANT_DEBUG_CASCADES
// Tints per cascade: red, green, blue, yellow, magenta, cyan, orange, violet.
vec3 cascade_tint(int cascade) {
  const vec3 tints[8] = vec3[8](vec3(1.0, 0.35, 0.35), vec3(0.35, 1.0, 0.35), vec3(0.4, 0.5, 1.0),
                                vec3(1.0, 1.0, 0.3), vec3(1.0, 0.35, 1.0), vec3(0.3, 1.0, 1.0),
                                vec3(1.0, 0.65, 0.25), vec3(0.65, 0.4, 1.0));
  return cascade < 0 ? vec3(1.0) : tints[cascade];
}
#endif
#endif
