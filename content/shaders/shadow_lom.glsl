// S1's layered occlusion map (technique lom, shadow_filter.glsl): the peels and occlusion
// factors LomPass stores, and pass 2, the lookup. lom_occlusion.frag (pass 1) reads the peels
// through the same functions.
#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_LOM
// S1's layered occlusion map (LomPass, runtime/render/lom_pass.h): per shadow-map layer, lom_layers
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

#if VARIANT_SHADOW_TECHNIQUE == VARIANT_SHADOW_TECHNIQUE_LOM
float wide_taps(int k, int i, vec3 c, vec3 q, vec3 n, float texel) {
  int layer = view_first_layer(k) + i;
  vec2 g = receiver_slope(k, i, q, n, c, texel);
  // At the receiver itself, not the normal-offset point q: pass 1 already kept each stored
  // point's own surface out of its occluders, and the offset would move the four samples
  // sideways off a surface the light grazes (a sphere's rim), onto what lies beside it.
  vec3 p = map_coords(k, i, q - n * (u_shadow_views[k].params.x * texel));
  if (any(lessThan(p.xy, vec2(0.0))) || any(greaterThan(p.xy, vec2(1.0)))) return 1.0;  // border
  return lom(layer, p, g);
}
#endif
