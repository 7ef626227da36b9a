// Variance shadow maps (techniques vsm and evsm, shadow_filter.glsl): the moments MomentsPass
// stores, their warp (shared with vsm_moments.frag) and the lookup.
#ifdef SHADOW_MOMENTS
// The moments of every layer (MomentsPass): blurred, mipmapped, read trilinear.
layout(binding = UNIT_VSM_MOMENTS) uniform sampler2DArray u_vsm_moments;

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
// pixel (docs/design/soft_shadows.md, vsm).
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

#ifdef SHADOW_MOMENTS
float wide_taps(int k, int i, vec3 c, vec3 q, vec3 n, float texel) {
  int layer = view_first_layer(k) + i;
  return vsm(k, i, layer, c, q, n);
}
#endif
