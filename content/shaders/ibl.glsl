// Image-based lighting: the formulas of components/ibl.h (the CPU twin, with their sources; the
// tests compare the two). Light from the surroundings is the irradiance over pi (9 SH
// coefficients, or the ambient radiance) and the radiance prefiltered by roughness (a cube's mip
// chain, or the ambient radiance), combined with the split-sum table (UNIT_DFG) and
// Fdez-Aguera's multiple-scattering correction.
#ifndef KASKAD_IBL_GLSL
#define KASKAD_IBL_GLSL

// (A, B) of the split sum at (N.V, roughness): dfg_table() in components/ibl.h, uploaded once.
layout(binding = UNIT_DFG) uniform sampler2D u_dfg;
// Rows of 9 SH coefficients (rgb) of radiance, one per probe prefiltered for the pbr reflection
// model (IblMaps in runtime/render/ibl_maps.h). The environment map's are in the frame block
// (u_environment_sh: nine texture fetches per pixel cost llvmpipe much more;
// docs/design/shading.md, "The model").
layout(binding = UNIT_SH) uniform sampler2D u_sh;

// sh9_irradiance_over_pi() of components/ibl.h: E(n) / pi from coefficients c[0..8].
vec3 sh9_irradiance_over_pi(vec3 c[9], vec3 n) {
  vec3 e = c[0] * 0.282095;
  e += (2.0 / 3.0) * 0.488603 * (c[1] * n.y + c[2] * n.z + c[3] * n.x);
  e += 0.25 * (c[4] * (1.092548 * n.x * n.y) + c[5] * (1.092548 * n.y * n.z) +
               c[6] * (0.315392 * (3.0 * n.z * n.z - 1.0)) + c[7] * (1.092548 * n.x * n.z) +
               c[8] * (0.546274 * (n.x * n.x - n.y * n.y)));
  return max(e, vec3(0.0));
}

// The same from SH row `row` (a pbr probe's).
vec3 sh9_irradiance_over_pi(int row, vec3 n) {
  vec3 c[9];
  for (int i = 0; i < 9; ++i) c[i] = texelFetch(u_sh, ivec2(i, row), 0).rgb;
  return sh9_irradiance_over_pi(c, n);
}

vec2 dfg_lookup(float n_dot_v, float roughness) {
  return texture(u_dfg, vec2(clamp(n_dot_v, 0.0, 1.0), clamp(roughness, 0.0, 1.0))).rg;
}

// ibl_combine() of components/ibl.h.
vec3 ibl_combine(vec3 base, float metallic, float roughness, float n_dot_v, vec2 dfg,
                 vec3 irradiance, vec3 specular) {
  metallic = clamp(metallic, 0.0, 1.0);
  roughness = clamp(roughness, BRDF_MIN_ROUGHNESS, 1.0);
  vec3 c_diff = mix(base, vec3(0.0), metallic);
  vec3 f0 = mix(vec3(BRDF_DIELECTRIC_F0), base, metallic);
  float m = 1.0 - clamp(n_dot_v, 0.0, 1.0);
  vec3 k_s = f0 + (max(vec3(1.0 - roughness), f0) - f0) * (m * m * m * m * m);
  vec3 fss_ess = k_s * dfg.x + dfg.y;
  float ems = 1.0 - (dfg.x + dfg.y);
  vec3 f_avg = f0 + (vec3(1.0) - f0) * (1.0 / 21.0);
  vec3 fms_ems = ems * fss_ess * f_avg / (vec3(1.0) - f_avg * ems);
  vec3 k_d = c_diff * max(vec3(1.0) - fss_ess - fms_ems, vec3(0.0));
  return fss_ess * specular + (fms_ems + k_d) * irradiance;
}

#endif
