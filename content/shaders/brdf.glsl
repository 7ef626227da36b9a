// The glTF 2.0 metallic-roughness BRDF (specification, Appendix B): Lambert diffuse, GGX /
// Trowbridge-Reitz distribution, Smith height-correlated visibility, Schlick Fresnel. The same
// formulas, with their derivation notes and the radiometric convention (a light's colour is the
// illuminance E it delivers; outgoing radiance = f * E * N.L), are in components/brdf.h (change
// together; tests/render/brdf_test compares the two at sampled angles, roughness and metalness).
#ifndef KASKAD_BRDF_GLSL
#define KASKAD_BRDF_GLSL

#define BRDF_PI 3.14159265358979323846
#define BRDF_MIN_ROUGHNESS 0.03  // kMinRoughness
#define BRDF_DIELECTRIC_F0 0.04  // kDielectricF0

vec3 brdf_fresnel_schlick(vec3 f0, float v_dot_h) {
  float m = clamp(1.0 - v_dot_h, 0.0, 1.0);
  float m2 = m * m;
  return f0 + (vec3(1.0) - f0) * (m2 * m2 * m);
}

// (N.H)^2 (alpha^2 - 1) + 1 as |N x H|^2 + (N.H)^2 alpha^2: no cancellation near the peak.
float brdf_distribution_ggx(vec3 n, vec3 h, float alpha) {
  float n_dot_h = dot(n, h);
  if (n_dot_h <= 0.0) return 0.0;
  vec3 nxh = cross(n, h);
  float a2 = alpha * alpha;
  float d = dot(nxh, nxh) + n_dot_h * n_dot_h * a2;
  return a2 / (BRDF_PI * d * d);
}

float brdf_visibility_smith_correlated(float n_dot_l, float n_dot_v, float alpha) {
  float a2 = alpha * alpha;
  float ggx_v = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
  float ggx_l = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
  float sum = ggx_v + ggx_l;
  return sum > 0.0 ? 0.5 / sum : 0.0;
}

// f(l, v) for unit n, v (to the eye), l (to the light); 0 where N.L <= 0; N.V clamped to 0.
vec3 brdf_evaluate(vec3 base, float metallic, float roughness, vec3 n, vec3 v, vec3 l) {
  float n_dot_l = dot(n, l);
  float n_dot_v = max(dot(n, v), 0.0);
  if (n_dot_l <= 0.0) return vec3(0.0);
  metallic = clamp(metallic, 0.0, 1.0);
  roughness = clamp(roughness, BRDF_MIN_ROUGHNESS, 1.0);
  float alpha = roughness * roughness;
  vec3 c_diff = mix(base, vec3(0.0), metallic);
  vec3 f0 = mix(vec3(BRDF_DIELECTRIC_F0), base, metallic);
  vec3 h = normalize(l + v);
  vec3 f = brdf_fresnel_schlick(f0, abs(dot(v, h)));
  float d = brdf_distribution_ggx(n, h, alpha);
  float vis = brdf_visibility_smith_correlated(n_dot_l, n_dot_v, alpha);
  vec3 f_diffuse = (vec3(1.0) - f) * (1.0 / BRDF_PI) * c_diff;
  vec3 f_specular = f * d * vis;
  return f_diffuse + f_specular;
}

#endif
