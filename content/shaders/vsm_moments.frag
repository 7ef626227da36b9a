// The moments of variance shadow maps (MomentsPass; shadow_moments.glsl's vsm()): one layer of the
// shadow map array into its moments, blurred by a separable Gaussian of vsm_blur texels. Two
// fullscreen draws per layer:
//  step 0: the moments vsm_warp(vsm_depth(z)) of each depth texel, blurred along x, into a 2D
//          scratch texture, drawn inside the layer's read rectangle only (scissor);
//  step 1: those blurred along y, into the layer; outside the rectangle, where the depth is
//          stale, the moments of depth 1 (nothing there: lit), so the mipmaps made next never
//          average stale texels in.
// The step is a uniform of one draw (the same for every fragment), not a feature: both steps
// are the same filter over different inputs.
// Taps outside the rectangle are clamped to its edge; a lookup reads no texel closer to the edge
// than the blur's reach (filter_reach_texels() is part of the rectangle's margin).
#include "common.glsl"
#include "features.glsl"
#include "shadow.glsl"

// x shadow view k, y its layer i, z step (0 along x from the depth, 1 along y), w blur side.
layout(location = LOC_VSM_TARGET) uniform ivec4 u_vsm_target;
// The layer's texels with valid depth: x0, y0, x1, y1, ends exclusive (empty: x0 >= x1).
layout(location = LOC_VSM_RECT) uniform ivec4 u_vsm_rect;
// Step 1's input: step 0's output.
layout(binding = UNIT_VSM_SOURCE) uniform sampler2D u_vsm_source;

layout(location = 0) out vec4 o_moments;

void main() {
  int k = u_vsm_target.x;
  ivec2 t = ivec2(gl_FragCoord.xy);
  bool inside = all(greaterThanEqual(t, u_vsm_rect.xy)) && all(lessThan(t, u_vsm_rect.zw));
  if (!inside) {
    o_moments = vsm_warp(vsm_depth(k, 1.0));
    return;
  }
  // Gaussian weights over the side s = 2 h + 1 taps, sigma = s / 4 (the kernel ends at two
  // sigmas); s = 1 copies.
  int h = u_vsm_target.w / 2;
  float sigma = max(float(u_vsm_target.w) * 0.25, 1e-3);
  int layer = view_first_layer(k) + u_vsm_target.y;
  ivec2 axis = u_vsm_target.z == 0 ? ivec2(1, 0) : ivec2(0, 1);
  vec4 sum = vec4(0.0);
  float total = 0.0;
  for (int o = -h; o <= h; ++o) {
    ivec2 s = clamp(t + o * axis, u_vsm_rect.xy, u_vsm_rect.zw - 1);
    vec4 m = u_vsm_target.z == 0
                 ? vsm_warp(vsm_depth(k, texelFetch(u_shadow_depth, ivec3(s, layer), 0).r))
                 : texelFetch(u_vsm_source, s, 0);
    float w = exp(-0.5 * float(o * o) / (sigma * sigma));
    sum += w * m;
    total += w;
  }
  o_moments = sum / total;
}
