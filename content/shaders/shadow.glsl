// The shadow lookup, shared by every pass that shades with shadows: the forward pass and the
// stability probe pass (shadow_points.*), so that both evaluate visibility with the same code.
// Needs common.glsl and features.glsl first. This file decides which map a point reads: its
// view, cascade, cube face or hemisphere, and the blend between cascades. How a layer is
// filtered there is shadow_filter.glsl's, one file per technique family below it.
#if VARIANT_HAS_SHADOW
layout(binding = UNIT_SHADOW) uniform sampler2DArrayShadow u_shadow_map;  // one layer per cascade
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
// a loop whose uniform bound is 0 still runs its body once with every lane masked off
// (docs/design/shadow_cost.md).
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

#include "shadow_filter.glsl"

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
// another trip, so only vectors that touch the band pay (measured on llvmpipe:
// docs/design/shadow_cost.md, "Where a shadowed frame's time went"). A GPU branches either way.
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
