// S1 pass 1, second half (Xu 2016, "Layered occlusion map soft shadows"): the occlusion factor of
// every point stored in peel j of one shadow-map layer, i.e. the fraction of the light that the
// scene hides from it. One fullscreen draw per peel into that peel's slice of the occlusion map
// (LomPass). Reads the peeled depths (shadow_lom.glsl's u_lom_depth).
//
// For a stored point P (texel t, depth z_P, distance d from the light):
//  1. The nearest occluder: the smallest depth of peel 0 (nearest the light) in front of P over
//     the widest region where anything between the light and P could block it (PCSS's blocker
//     search, disc taps), at distance z.
//  2. The kernel, S1 eqs. (1) and (2), whose bodies are missing from the text; by similar
//     triangles. The light, of width l, seen from P at distance d passes through the plane of an
//     occluder at distance z from the light in a square of width l (d - z) / d: only occluders
//     in it can hide part of the light (the penumbra an occluder at z casts on a receiver at d is
//     l (d - z) / z wide; this is the same region seen from the other end). On the map, whose
//     near plane at distance n is w wide over r texels, a width x at distance z covers
//     x n r / (w z) texels. So
//       (1)  z' = l n r / (w z)        the light's width through the occluder's plane, in texels
//                                      of the map, as if P were infinitely far;
//       (2)  w_k = z' (d - z) / d      the kernel width for P at d.
//     n r / w is 1 / view_texel (texels per tangent unit at 1 m), so w_k / 2 is pcss_radius()
//     with d_b = z (shadow_pcss.glsl). Ortho (a directional light): l = 2 tan(theta / 2) and
//     w_k = l (d - z) / texel, the limit of (2) with the light at infinity.
//  3. Every stored point in the kernel in front of P, in any peel, is a micro-occluder (a square
//     as wide as its kernel cell at its depth), back-projected from P onto the light as in
//     backprojection() (shadow_pcss.glsl). S1 counts only the occluder nearest P: overlapping
//     projections must not be summed (plain backprojection's over-darkening). Here the light is
//     64 sample points (a 64-bit mask, light_cells()), and a sample is blocked when the
//     projection of some micro-occluder covers it: each part of the light counts once,
//     whichever occluders cover it, which is what keeping only the nearest occluder along each
//     ray from P to the light gives. The factor is the blocked fraction of the 64 samples.
// Surfaces that receive shadows without casting them (negative stored depths) are stored to be
// shaded but never occlude.
#include "common.glsl"
#include "features.glsl"
#include "shadow.glsl"

// x shadow view k, y its layer i, z peel j, w 1 when this draw counts the overflow texels.
layout(location = LOC_LOM_TARGET) uniform ivec4 u_lom_target;
// Texels of the layer with a surface in the overflow peel: the layers ran out there.
layout(binding = 0, offset = 0) uniform atomic_uint u_overflow_texels;

layout(location = 0) out float o_factor;

// Cells per side of the widest kernel: 2 LOM_HALF + 1 (coarser cells past LOM_HALF texels of
// radius). As backprojection()'s BP_HALF: a cell of `step` texels samples one depth, so an
// occluder's edge moves by up to half a cell with P; fewer cells made penumbrae wider
// (docs/design/soft_shadows.md, lom).
#define LOM_HALF 12

// The light's 64 sample points, one per bit of a 64-bit mask (uvec2: bits 0-31, 32-63): bit
// 8 b + a (a, b in 0..7) sits at x rank 8 a + b and y rank 8 b + a of 64 even steps across the
// light, x = -h + (rank + 0.5) 2 h / 64. Every column and every row of the 64 x 64 grid holds one
// sample (an N-rooks lattice), so a straight shadow edge parallel to either axis uncovers the
// light in 64 steps, not the 8 of a plain 8 x 8 grid.

// Bits lo .. hi (0 <= lo, hi <= 63) of a 64-bit mask.
uvec2 bit_range(int lo, int hi) {
  if (lo > hi) return uvec2(0u);
  uvec2 below_hi = uvec2(hi >= 31 ? 0xffffffffu : (2u << hi) - 1u,
                         hi >= 63 ? 0xffffffffu : hi < 32 ? 0u : (2u << (hi - 32)) - 1u);
  uvec2 below_lo = uvec2(lo >= 32 ? 0xffffffffu : (1u << lo) - 1u,
                         lo <= 32 ? 0u : (1u << (lo - 32)) - 1u);
  return below_hi & ~below_lo;
}

// The samples in column a (x ranks 8 a .. 8 a + 7) whose b lies in [b0, b1].
uvec2 column_part(int a, int b0, int b1) {
  uvec2 column = uvec2(0x01010101u << a);  // bit a of every byte: b = 0 .. 7
  return column & bit_range(8 * b0, 8 * b1 + 7);
}

// The ranks [k0, k1] (clamped to 0 .. 63) of samples at -h + (k + 0.5) 2 h / 64 in [lo, hi].
ivec2 ranks(float lo, float hi, float h) {
  float scale = 32.0 / h;  // 64 / (2 h)
  int k0 = int(ceil(clamp((lo + h) * scale - 0.5, -1.0, 64.0)));
  int k1 = int(floor(clamp((hi + h) * scale - 0.5, -1.0, 64.0)));
  return ivec2(max(k0, 0), min(k1, 63));
}

// The samples of the light [-h.x, h.x] x [-h.y, h.y] that the rectangle [lo, hi] covers.
uvec2 light_cells(vec2 lo, vec2 hi, vec2 h) {
  ivec2 kx = ranks(lo.x, hi.x, h.x), ky = ranks(lo.y, hi.y, h.y);
  if (kx.x > kx.y || ky.x > ky.y) return uvec2(0u);
  // y rank 8 b + a is the bit index: a contiguous range of bits.
  uvec2 in_y = bit_range(ky.x, ky.y);
  // x rank 8 a + b: whole columns a0 < a < a1, and the ends of columns a0 and a1.
  int a0 = kx.x >> 3, b0 = kx.x & 7, a1 = kx.y >> 3, b1 = kx.y & 7;
  uvec2 in_x;
  if (a0 == a1) {
    in_x = column_part(a0, b0, b1);
  } else {
    uint middle = ((1u << a1) - 1u) & ~((2u << a0) - 1u);  // columns a0 + 1 .. a1 - 1
    in_x = column_part(a0, b0, 7) | column_part(a1, 0, b1) | uvec2(middle * 0x01010101u);
  }
  return in_x & in_y;
}

// Texel t of layer i of view k numbered in world-fixed coordinates: a cascade's grid moves with
// the camera in whole texels (stable fit), by its projection's translation; spot maps and cube
// faces do not move. What varies per stored point (the blocker search's rotation)
// hashes this, so it stays with the surface when the camera moves (as stable_angle()).
ivec2 fixed_texel(int k, int i, ivec2 t, float size) {
  bool ortho = true;
#if VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_PERSPECTIVE || \
    VARIANT_SHADOW_PROJECTION == VARIANT_SHADOW_PROJECTION_CUBE
  ortho = k != 0;
#endif
  if (!ortho) return t;
  return t - ivec2(round(u_shadow_views[k].view_proj[i][3].xy * 0.5 * size));
}

// d depth / d texel of the surface stored at texel s of peel m (depth z, in [0, 1]). Per axis,
// the one-sided difference whose side continues the surface linearly (the next difference
// beyond it is alike): at the edge of a face the neighbour across the edge belongs to another
// surface, and the step to it is not continued by that surface's own slope. Where neither side
// does (a crease, a one-texel feature), the smaller difference; where neither neighbour holds a
// surface, 0.
vec2 surface_slope(ivec2 s, int layer, int m, float z, float size) {
  vec2 g;
  int last = int(size) - 1;
  for (int axis = 0; axis < 2; ++axis) {
    ivec2 e = axis == 0 ? ivec2(1, 0) : ivec2(0, 1);
    float z1 = abs(lom_depth(min(s + e, ivec2(last)), layer, m));
    float z2 = abs(lom_depth(min(s + 2 * e, ivec2(last)), layer, m));
    float y1 = abs(lom_depth(max(s - e, ivec2(0)), layer, m));
    float y2 = abs(lom_depth(max(s - 2 * e, ivec2(0)), layer, m));
    float ahead = z1 < 1.0 ? z1 - z : 1e9, behind = y1 < 1.0 ? z - y1 : 1e9;
    bool ahead_linear = z1 < 1.0 && z2 < 1.0 && abs((z2 - z1) - ahead) <= 0.25 * abs(ahead) + 1e-7;
    bool behind_linear = y1 < 1.0 && y2 < 1.0 && abs((y1 - y2) - behind) <= 0.25 * abs(behind) + 1e-7;
    float d;
    if (ahead_linear && behind_linear) d = 0.5 * (ahead + behind);
    else if (ahead_linear) d = ahead;
    else if (behind_linear) d = behind;
    else d = abs(ahead) < abs(behind) ? ahead : behind;
    g[axis] = abs(d) < 1e8 ? d : 0.0;
  }
  return g;
}

// The light samples that the micro-occluder of peel m at texel s (stored depth z, `offset` texels
// from P, a cell `step` texels wide) hides from P at distance d_r: the line from P through a
// point of it reaches the light plane at (texels from P) x f, f = texel d_r d_b / (d_r - d_b)
// (perspective, texel in tangent units, light plane at distance 0) or texel / (d_r - d_b) in
// tangent units (ortho), d_b its distance, as backprojection() (shadow_pcss.glsl). Each of its
// edges is projected at the distance the stored surface has there (surface_slope(), steeper
// than 8 texels per texel taken as an edge, as receiver_slope()), so the projections of
// neighbouring cells of one surface meet on the light: no gaps for light to leak through
// between cells at different depths (backprojection's gaps, which Guennebaud et al. fill with a
// separate step).
uvec2 micro_occluder(PcssMap map, ivec2 s, int layer, int m, float z, vec2 offset, float step,
                     float d_r, vec2 half_light, float size) {
  float d_b = pcss_distance(map, z);
  vec2 dz = surface_slope(s, layer, m, z, size) * (0.5 * step);
  vec2 d_lo = vec2(pcss_distance(map, z - dz.x), pcss_distance(map, z - dz.y));
  vec2 d_hi = vec2(pcss_distance(map, z + dz.x), pcss_distance(map, z + dz.y));
  float texel_m = map.perspective ? map.texel * d_b : map.texel;
  float limit = 8.0 * texel_m * 0.5 * step;  // steeper: an edge, the cell's own distance
  d_lo = mix(d_lo, vec2(d_b), greaterThan(abs(d_lo - d_b), vec2(limit)));
  d_hi = mix(d_hi, vec2(d_b), greaterThan(abs(d_hi - d_b), vec2(limit)));
  d_lo = clamp(d_lo, 1e-4, d_r - 1e-4);
  d_hi = clamp(d_hi, 1e-4, d_r - 1e-4);
  vec2 f_lo = map.perspective ? map.texel * d_r * d_lo / (d_r - d_lo) : map.texel / (d_r - d_lo);
  vec2 f_hi = map.perspective ? map.texel * d_r * d_hi / (d_r - d_hi) : map.texel / (d_r - d_hi);
  vec2 lo = (offset - 0.5 * step) * f_lo, hi = (offset + 0.5 * step) * f_hi;
  // Half a sample spacing wider on each side: closes the hairline gaps the slope estimates leave
  // at creases (a box's top meeting its wall: one sample of light, 1/64, leaked into a closed
  // box). Covering a sample twice costs nothing; a silhouette moves by 1/128 of the light.
  vec2 pad = half_light / 64.0;
  return light_cells(min(lo, hi) - pad, max(lo, hi) + pad, half_light);
}

float occlusion_factor(int k, int i, int layer, ivec2 t, float z_p) {
  int layers = lom_layers();
  float size = u_frame.y;
  vec2 extent = light_extent(k);
  float l = max(extent.x, extent.y);  // the search, as pcss()
  vec2 c = (vec2(t) + 0.5) / size;
  // The stored surface's plane (d depth / d uv): a point of it in another texel is not in front
  // of P.
  vec2 g = surface_slope(t, layer, u_lom_target.z, z_p, size) * size;
  float margin = 1.5 * (abs(g.x) + abs(g.y)) / size + 2e-6;
  if (l <= 0.0) {  // a punctual light: hard shadows, from peel 0 at P's texel
    float z = lom_depth(t, layer, 0);
    return z >= 0.0 && z < z_p - margin ? 1.0 : 0.0;
  }
  PcssMap map = pcss_map(k, i);
  vec2 half_light = light_half_extent(k, map.perspective);
  float d_r = pcss_distance(map, z_p);
  ivec2 cell = fixed_texel(k, i, t, size);
  uvec3 h = pcg3d(uvec3(uvec2(cell), uint(layer)));
  // 1. The nearest occluder (peel 0 holds the depth nearest the light at each texel), over a
  //    disc of taps turned per stored point, plus P's own texel.
  float search = clamp(pcss_radius(map, l, d_r, map.perspective ? map.near : 0.0), 1.0,
                       PCSS_MAX_RADIUS);
  int taps = int(u_shadow_views[k].soft.z);
  float angle = float(h.x >> 8u) * (6.28318531 / 16777216.0);
  float z_min = z_p;
  for (int s = 0; s <= taps; ++s) {
    vec2 o = s == taps ? vec2(0.0) : disc_tap(s, taps, angle) * (search / size);
    float z = texture(u_lom_depth, vec3(c + o, float(lom_slice(layer, 0)))).r;
    if (z >= 0.0 && z < z_p + dot(g, o) - margin) z_min = min(z_min, z);
  }
  if (z_min >= z_p) return 0.0;  // nothing casts on P
  // 2. The kernel (eqs. (1), (2) above), one texel wider for the micro-occluders' extent: at
  //    most 2 LOM_HALF + 1 cells a side (coarser cells past that), fewer for a narrow one.
  float radius = clamp(pcss_radius(map, l, d_r, pcss_distance(map, z_min)) + 1.0, 1.0, search);
  float step = max(1.0, ceil(radius / float(LOM_HALF)));
  int half_cells = min(LOM_HALF, int(ceil(radius / step)));
  // 3. Back-project the micro-occluders onto the light's cells.
  uvec2 blocked = uvec2(0u);
  for (int y = -half_cells; y <= half_cells; ++y) {
    for (int x = -half_cells; x <= half_cells; ++x) {
      vec2 offset = vec2(float(x), float(y)) * step;  // texels from P
      ivec2 s = t + ivec2(offset);
      if (any(lessThan(s, ivec2(0))) || any(greaterThanEqual(s, ivec2(int(size))))) continue;
      // In front of P's plane by the margin, and by a quarter of the plane's depth change
      // there: the plane is estimated from differences of one texel, which a curved surface
      // (a sphere near its silhouette as the light sees it) bends away from; without this
      // the surface's own points in front of the estimate shadowed it.
      float z_plane = z_p + dot(g, offset / size) - margin -
                      0.25 * dot(abs(g), abs(offset)) / size;
      for (int m = 0; m < layers; ++m) {
        float z = lom_depth(s, layer, m);
        if (abs(z) >= z_plane) break;  // this peel and the deeper ones are behind P
        if (z < 0.0) continue;         // stored to be shaded, casts nothing
        blocked |= micro_occluder(map, s, layer, m, z, offset, step, d_r, half_light, size);
      }
    }
    if (blocked == uvec2(0xffffffffu)) break;  // the whole light is hidden
  }
  return float(bitCount(blocked.x) + bitCount(blocked.y)) / 64.0;
}

void main() {
  int k = u_lom_target.x, i = u_lom_target.y, j = u_lom_target.z;
  int layer = view_first_layer(k) + i;
  ivec2 t = ivec2(gl_FragCoord.xy);
  if (u_lom_target.w != 0 && abs(lom_depth(t, layer, lom_layers())) < 1.0)
    atomicCounterIncrement(u_overflow_texels);
  float z_p = lom_depth(t, layer, j);
  // No surface stored: the virtual far layer (factor 1), which pass 2 reads where a sample has
  // no surface behind the receiver.
  o_factor = abs(z_p) >= 1.0 ? 1.0 : occlusion_factor(k, i, layer, t, abs(z_p));
}
