// The lookups sized by the light (shadow_filter.glsl): PCSS's blocker search and filter, and
// backprojection, which sums the part of the light each blocker found covers.
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
  // edge gave penumbrae too narrow; docs/design/soft_shadows.md, pcss).
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

#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_PCSS || \
    VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_BACKPROJECTION
float wide_taps(int k, int i, vec3 c, vec3 q, vec3 n, float texel) {
  int layer = view_first_layer(k) + i;
  vec2 g = receiver_slope(k, i, q, n, c, texel);
#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_PCSS
  return pcss(k, i, layer, c, g, stable_angle(k, i, q, c));
#else
  return backprojection(k, i, layer, c, g, stable_angle(k, i, q, c));
#endif
}
#endif
