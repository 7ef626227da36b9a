// Image-based lighting on the CPU: the formulas content/shaders/ibl.glsl evaluates on the GPU,
// also used by the reflection reference (shade_point) and the tests. Plain maths.
//
// Light from the surroundings (an environment map, a reflection probe, or the uniform ambient
// radiance when there is neither) reaches the glTF BRDF (components/brdf.h) in two parts:
//   - diffuse: the irradiance E(n) over pi, from 9 spherical-harmonic coefficients of the
//     radiance (Ramamoorthi and Hanrahan 2001, "An Efficient Representation for Irradiance
//     Environment Maps": E(n) = sum_lm A_l L_lm Y_lm(n), A_0 = pi, A_1 = 2 pi / 3, A_2 = pi / 4);
//   - specular: the split-sum approximation (Karis 2013, "Real Shading in Unreal Engine 4"): the
//     radiance prefiltered with the GGX lobe of the surface's roughness (assuming N = V = R),
//     times the BRDF's directional albedo f0 A + B read from a table of (N.V, roughness).
// The two are combined with Fdez-Aguera's multiple-scattering correction (2019, "A
// Multiple-Scattering Microfacet Model for Real-Time Image-based Lighting"): single scattering
// f0 A + B (with a roughness-dependent Fresnel), the energy it misses (1 - A - B) added back
// as multiple scattering, and the diffuse lobe given only what the specular lobes leave. In a
// uniform environment of radiance L a white non-metal and a white metal both reflect exactly L
// (the white furnace), whatever their roughness.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "components/brdf.h"

namespace kaskad {

/// Levels of a cube prefiltered for the specular lobe from a cube of `size` texels a side:
/// level k holds roughness k / (levels - 1), down to 4 x 4 texels a face, at most 6 levels.
inline int ibl_specular_levels(int size) {
  int mips = 0;
  for (int s = std::max(1, size); s > 0; s >>= 1) ++mips;
  return std::clamp(mips - 2, 1, 6);
}

/// Nine spherical-harmonic coefficients (bands 0-2) of an RGB radiance function.
using Sh9 = std::array<glm::vec3, 9>;

/// The real SH basis Y_0^0 .. Y_2^2 at a unit direction d, in the order
/// (0,0) (1,-1) (1,0) (1,1) (2,-2) (2,-1) (2,0) (2,1) (2,2) with y, z, x for m = -1, 0, 1.
inline std::array<float, 9> sh9_basis(const glm::vec3& d) {
  return {0.282095f,
          0.488603f * d.y,
          0.488603f * d.z,
          0.488603f * d.x,
          1.092548f * d.x * d.y,
          1.092548f * d.y * d.z,
          0.315392f * (3.0f * d.z * d.z - 1.0f),
          1.092548f * d.x * d.z,
          0.546274f * (d.x * d.x - d.y * d.y)};
}

/// The radiance a white Lambert surface with normal n reflects, E(n) / pi, from the SH of the
/// radiance around it (band weights A_l / pi = 1, 2/3, 1/4). Clamped at 0 (the band-limited
/// function can ring below 0 behind a bright, small source).
inline glm::vec3 sh9_irradiance_over_pi(const Sh9& sh, const glm::vec3& n) {
  const std::array<float, 9> y = sh9_basis(n);
  constexpr float band[9] = {1.0f, 2.0f / 3.0f, 2.0f / 3.0f, 2.0f / 3.0f, 0.25f,
                             0.25f, 0.25f, 0.25f, 0.25f};
  glm::vec3 e(0.0f);
  for (int i = 0; i < 9; ++i) e += sh[std::size_t(i)] * (band[i] * y[std::size_t(i)]);
  return glm::max(e, glm::vec3(0.0f));
}

/// The SH of a uniform radiance L: only the constant band (L / Y_0^0 = L sqrt(4 pi)).
inline Sh9 sh9_uniform(const glm::vec3& radiance) {
  Sh9 sh{};
  sh[0] = radiance * (1.0f / 0.282095f);
  return sh;
}

/// Point i of n of the Hammersley set in [0, 1)^2 (van der Corput radical inverse in base 2).
inline glm::vec2 hammersley(std::uint32_t i, std::uint32_t n) {
  std::uint32_t b = i;
  b = (b << 16u) | (b >> 16u);
  b = ((b & 0x55555555u) << 1u) | ((b & 0xAAAAAAAAu) >> 1u);
  b = ((b & 0x33333333u) << 2u) | ((b & 0xCCCCCCCCu) >> 2u);
  b = ((b & 0x0F0F0F0Fu) << 4u) | ((b & 0xF0F0F0F0u) >> 4u);
  b = ((b & 0x00FF00FFu) << 8u) | ((b & 0xFF00FF00u) >> 8u);
  return {float(i) / float(n), float(b) * 2.3283064365386963e-10f};
}

/// A half vector drawn from the GGX distribution D(h) (N.H) around +Z for alpha = roughness^2:
/// cos(theta) = sqrt((1 - u.y) / (1 + (alpha^2 - 1) u.y)), phi = 2 pi u.x.
inline glm::vec3 ggx_sample_half_vector(const glm::vec2& u, float alpha) {
  const float a2 = alpha * alpha;
  const float cos_t = std::sqrt((1.0f - u.y) / (1.0f + (a2 - 1.0f) * u.y));
  const float sin_t = std::sqrt(std::max(0.0f, 1.0f - cos_t * cos_t));
  const float phi = 2.0f * kPi * u.x;
  return {sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t};
}

/// The split sum's second factor: the directional albedo of the specular lobe is f0 A + B,
/// A = int (1 - Fc) f_s/F N.L dl, B = int Fc f_s/F N.L dl with Fc = (1 - V.H)^5, for the
/// BRDF of components/brdf.h (GGX D, height-correlated Smith V), by GGX importance sampling.
/// roughness is clamped to kMinRoughness like brdf_evaluate()'s.
inline glm::vec2 dfg_integrate(float n_dot_v, float roughness, std::uint32_t samples) {
  n_dot_v = std::clamp(n_dot_v, 1e-4f, 1.0f);
  const float alpha = std::pow(std::clamp(roughness, kMinRoughness, 1.0f), 2.0f);
  const glm::vec3 v(std::sqrt(1.0f - n_dot_v * n_dot_v), 0.0f, n_dot_v);
  glm::vec2 ab(0.0f);
  for (std::uint32_t i = 0; i < samples; ++i) {
    const glm::vec3 h = ggx_sample_half_vector(hammersley(i, samples), alpha);
    const float v_dot_h = glm::dot(v, h);
    const glm::vec3 l = 2.0f * v_dot_h * h - v;
    if (l.z <= 0.0f || v_dot_h <= 0.0f) continue;
    // f_s N.L / pdf(l) with pdf(l) = D N.H / (4 V.H): D cancels.
    const float w = 4.0f * brdf_visibility_smith_correlated(l.z, n_dot_v, alpha) * l.z *
                    v_dot_h / h.z;
    const float m = 1.0f - v_dot_h;
    const float fc = m * m * m * m * m;
    ab += glm::vec2((1.0f - fc) * w, fc * w);
  }
  return ab / float(samples);
}

/// The split-sum table: kDfgTableSize^2 texels of (A, B), texel (i, j) at N.V = (i + 0.5) / size
/// and roughness = (j + 0.5) / size (row j, as the GL texture's row j), lookups with linear
/// filtering and clamping to the edge texels.
inline constexpr int kDfgTableSize = 32;
inline constexpr std::uint32_t kDfgTableSamples = 512;

inline const std::vector<glm::vec2>& dfg_table() {
  static const std::vector<glm::vec2> table = [] {
    std::vector<glm::vec2> t(std::size_t(kDfgTableSize) * kDfgTableSize);
    for (int j = 0; j < kDfgTableSize; ++j)
      for (int i = 0; i < kDfgTableSize; ++i)
        t[std::size_t(j) * kDfgTableSize + std::size_t(i)] =
            dfg_integrate((float(i) + 0.5f) / kDfgTableSize, (float(j) + 0.5f) / kDfgTableSize,
                          kDfgTableSamples);
    return t;
  }();
  return table;
}

/// dfg_table() read as the GPU reads it: bilinear, clamped to the edge texels.
inline glm::vec2 dfg_lookup(float n_dot_v, float roughness) {
  const std::vector<glm::vec2>& t = dfg_table();
  const int n = kDfgTableSize;
  const float x = std::clamp(n_dot_v, 0.0f, 1.0f) * float(n) - 0.5f;
  const float y = std::clamp(roughness, 0.0f, 1.0f) * float(n) - 0.5f;
  const float x0f = std::floor(x), y0f = std::floor(y);
  const float ax = x - x0f, ay = y - y0f;
  auto at = [&](int i, int j) {
    return t[std::size_t(std::clamp(j, 0, n - 1)) * std::size_t(n) + std::size_t(std::clamp(i, 0, n - 1))];
  };
  const int x0 = int(x0f), y0 = int(y0f);
  return glm::mix(glm::mix(at(x0, y0), at(x0 + 1, y0), ax),
                  glm::mix(at(x0, y0 + 1), at(x0 + 1, y0 + 1), ax), ay);
}

/// The light a surface reflects from its surroundings (see the top of this file):
/// `irradiance` is E(n) / pi (sh9_irradiance_over_pi, or the ambient radiance), `specular` the
/// prefiltered radiance along the reflected view direction for this roughness, `dfg` the
/// table's (A, B) at (N.V, roughness). roughness is the clamped perceptual roughness.
inline glm::vec3 ibl_combine(const BrdfInputs& in, float n_dot_v, const glm::vec2& dfg,
                             const glm::vec3& irradiance, const glm::vec3& specular) {
  const float metallic = std::clamp(in.metallic, 0.0f, 1.0f);
  const float roughness = std::clamp(in.roughness, kMinRoughness, 1.0f);
  const glm::vec3 c_diff = glm::mix(in.base, glm::vec3(0.0f), metallic);
  const glm::vec3 f0 = glm::mix(glm::vec3(kDielectricF0), in.base, metallic);
  const float m = 1.0f - std::clamp(n_dot_v, 0.0f, 1.0f);
  const glm::vec3 fr = glm::max(glm::vec3(1.0f - roughness), f0) - f0;
  const glm::vec3 k_s = f0 + fr * (m * m * m * m * m);
  const glm::vec3 fss_ess = k_s * dfg.x + dfg.y;
  const float ems = 1.0f - (dfg.x + dfg.y);
  const glm::vec3 f_avg = f0 + (glm::vec3(1.0f) - f0) * (1.0f / 21.0f);
  const glm::vec3 fms_ems = ems * fss_ess * f_avg / (glm::vec3(1.0f) - f_avg * ems);
  const glm::vec3 k_d = c_diff * glm::max(glm::vec3(1.0f) - fss_ess - fms_ems, glm::vec3(0.0f));
  return fss_ess * specular + (fms_ems + k_d) * irradiance;
}

}  // namespace kaskad
