// The glTF 2.0 metallic-roughness BRDF (glTF 2.0 specification, Appendix B), on the CPU: the
// formulas content/shaders/brdf.glsl evaluates on the GPU (the render test
// BrdfTest.GlslMatchesTheCpuEvaluationOfAppendixB fails when the two part), also used by the
// reflection reference (shade_point). Plain maths.
//
//   c_diff = lerp(base.rgb, black, metallic)        f0 = lerp(0.04, base.rgb, metallic)
//   alpha  = roughness^2
//   F = f0 + (1 - f0) (1 - |V.H|)^5                  Schlick
//   D = alpha^2 / (pi ((N.H)^2 (alpha^2 - 1) + 1)^2)  GGX / Trowbridge-Reitz (0 where N.H <= 0)
//   V = 0.5 / (N.L sqrt((N.V)^2 (1 - a2) + a2) + N.V sqrt((N.L)^2 (1 - a2) + a2)), a2 = alpha^2
//       Smith height-correlated visibility G2 / (4 N.L N.V), G2 = 1 / (1 + Lambda(V) +
//       Lambda(L)) (Heitz 2014, "Understanding the Masking-Shadowing Function in
//       Microfacet-Based BRDFs"; the Khronos sample viewer's V_GGX)
//   f_diffuse  = (1 - F) (1 / pi) c_diff             Lambert
//   f_specular = F D V
//   f = f_diffuse + f_specular                       (per steradian: a BRDF)
//
// Radiometry (Kaskad's convention, docs/design/shading.md, "The model"): a light's colour * intensity is the
// illuminance E it delivers to a surface facing it (KHR_lights_punctual: lux for directional
// lights; candela / d^2 for spot and point lights), so the radiance leaving a surface is
// f * E * N.L. A white Lambert surface facing a light of colour c shows c / pi.
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

namespace kaskad {

inline constexpr float kPi = 3.14159265358979323846f;
/// Roughness is clamped to at least this before alpha = roughness^2: at 0 D is a Dirac delta,
/// which a point light cannot hit (and fp32 cannot hold). Kaskad's clamp since Blinn-Phong.
inline constexpr float kMinRoughness = 0.03f;
/// glTF's dielectric f0 (an index of refraction of 1.5).
inline constexpr float kDielectricF0 = 0.04f;

/// The inputs of the BRDF a surface point has.
struct BrdfInputs {
  glm::vec3 base{1.0f};    ///< linear base colour (factor * texture)
  float metallic = 0.0f;   ///< [0, 1]
  float roughness = 0.5f;  ///< perceptual roughness, [0, 1]; clamped to kMinRoughness
};

/// Schlick's Fresnel: f0 + (1 - f0) (1 - v_dot_h)^5, v_dot_h = |V.H|.
inline glm::vec3 brdf_fresnel_schlick(const glm::vec3& f0, float v_dot_h) {
  const float m = std::clamp(1.0f - v_dot_h, 0.0f, 1.0f);
  const float m2 = m * m;
  return f0 + (glm::vec3(1.0f) - f0) * (m2 * m2 * m);
}

/// GGX / Trowbridge-Reitz normal distribution for unit n and h, alpha = roughness^2; 0 where
/// N.H <= 0. The denominator (N.H)^2 (alpha^2 - 1) + 1 is computed as |N x H|^2 + (N.H)^2 alpha^2
/// (the same value: 1 - (N.H)^2 = |N x H|^2): near the peak 1 - (N.H)^2 cancels to fp32 noise
/// as large as alpha^2 at low roughness (Filament's D_GGX does the same).
inline float brdf_distribution_ggx(const glm::vec3& n, const glm::vec3& h, float alpha) {
  const float n_dot_h = glm::dot(n, h);
  if (n_dot_h <= 0.0f) return 0.0f;
  const glm::vec3 nxh = glm::cross(n, h);
  const float a2 = alpha * alpha;
  const float d = glm::dot(nxh, nxh) + n_dot_h * n_dot_h * a2;
  return a2 / (kPi * d * d);
}

/// Smith height-correlated visibility V = G2 / (4 N.L N.V); n_dot_l > 0, n_dot_v >= 0.
inline float brdf_visibility_smith_correlated(float n_dot_l, float n_dot_v, float alpha) {
  const float a2 = alpha * alpha;
  const float ggx_v = n_dot_l * std::sqrt(n_dot_v * n_dot_v * (1.0f - a2) + a2);
  const float ggx_l = n_dot_v * std::sqrt(n_dot_l * n_dot_l * (1.0f - a2) + a2);
  const float sum = ggx_v + ggx_l;
  return sum > 0.0f ? 0.5f / sum : 0.0f;
}

/// f(l, v) of Appendix B for unit vectors n (shading normal), v (to the eye), l (to the light);
/// 0 where N.L <= 0 (the light is below the surface). N.V is clamped to 0: a smooth or mapped
/// normal may face slightly away from the eye at a silhouette, and the diffuse term does not
/// depend on it. Multiply by E * N.L for the radiance a light of illuminance E reflects.
inline glm::vec3 brdf_evaluate(const BrdfInputs& in, const glm::vec3& n, const glm::vec3& v,
                               const glm::vec3& l) {
  const float n_dot_l = glm::dot(n, l);
  const float n_dot_v = std::max(glm::dot(n, v), 0.0f);
  if (n_dot_l <= 0.0f) return glm::vec3(0.0f);
  const float metallic = std::clamp(in.metallic, 0.0f, 1.0f);
  const float roughness = std::clamp(in.roughness, kMinRoughness, 1.0f);
  const float alpha = roughness * roughness;
  const glm::vec3 c_diff = glm::mix(in.base, glm::vec3(0.0f), metallic);
  const glm::vec3 f0 = glm::mix(glm::vec3(kDielectricF0), in.base, metallic);
  const glm::vec3 h = glm::normalize(l + v);
  const glm::vec3 f = brdf_fresnel_schlick(f0, std::abs(glm::dot(v, h)));
  const float d = brdf_distribution_ggx(n, h, alpha);
  const float vis = brdf_visibility_smith_correlated(n_dot_l, n_dot_v, alpha);
  const glm::vec3 f_diffuse = (glm::vec3(1.0f) - f) * (1.0f / kPi) * c_diff;
  const glm::vec3 f_specular = f * d * vis;
  return f_diffuse + f_specular;
}

}  // namespace kaskad
