// How a shadow-map layer is filtered at map coordinates c (included by shadow.glsl, which picks
// the layer). The plain lookups (filter none, bilinear, pcf3x3 with technique pcf) are
// shadow_taps() below. Every other lookup is "wide": it is defined by its technique family's file
// as wide_taps(k, i, c, q, n, texel), the lookup of layer i of view k for the receiver q (the
// normal-offset point) with normal n, texel metres per texel at q. Exactly one family defines
// it in each variant:
//   shadow_pcf.glsl      technique pcf with kernels past 3x3 (boxes, the Poisson disc), and the
//                        helpers every wide lookup shares (receiver plane, rotated discs)
//   shadow_pcss.glsl     pcss and backprojection: blocker searches sized by the light
//   shadow_lom.glsl      lom: S1's layered occlusion map
//   shadow_moments.glsl  vsm and evsm: variance shadow maps
// The families' switches come from the technique table (components/shadow_technique.h):
// TECHNIQUE_NEEDS_LIGHT_SIZE and TECHNIQUE_MOMENT_CHANNELS.
#if VARIANT_HAS_SHADOW
// The wide lookups: PCF kernels past 3x3 and every technique but pcf. They compare each tap
// against the receiver plane (receiver_slope()) and rotate their discs per point
// (stable_angle()).
#if VARIANT_SHADOW_TECHNIQUE != VARIANT_SHADOW_TECHNIQUE_PCF || \
    (VARIANT_SHADOW_FILTER == VARIANT_SHADOW_FILTER_PCF3X3 && \
     VARIANT_SHADOW_KERNEL != VARIANT_SHADOW_KERNEL_3X3)
#define SHADOW_WIDE 1
// The same map compared with linear filtering: each disc tap is a hardware 2x2 PCF, so few taps
// still give smooth ramps.
layout(binding = UNIT_SHADOW_LINEAR) uniform sampler2DArrayShadow u_shadow_linear;
#endif
#if TECHNIQUE_NEEDS_LIGHT_SIZE
#define SHADOW_SIZED 1  // lookups that use the light's size (PcssMap, shadow_pcss.glsl)
#endif
#if TECHNIQUE_MOMENT_CHANNELS != 0
#define SHADOW_MOMENTS 1  // variance shadow maps (MomentsPass, shadow_moments.glsl)
#endif
#if defined(SHADOW_SIZED) || defined(SHADOW_MOMENTS)
// The same map without compare: raw depths for PCSS's blocker search and backprojection, and
// for the moments pass.
layout(binding = UNIT_SHADOW_DEPTH) uniform sampler2DArray u_shadow_depth;
#endif

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
#include "shadow_pcf.glsl"
#include "shadow_pcss.glsl"
#include "shadow_lom.glsl"
#include "shadow_moments.glsl"
#endif
#endif
