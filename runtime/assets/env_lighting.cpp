#include "runtime/assets/env_lighting.h"

#include <cmath>

namespace kaskad {

Sh9 project_sh9(const CubeMap& cube) {
  Sh9 sh{};
  if (cube.size <= 0) return sh;
  float total = 0.0f;
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < cube.size; ++y)
      for (int x = 0; x < cube.size; ++x) {
        const float s = (float(x) + 0.5f) / float(cube.size);
        const float t = (float(y) + 0.5f) / float(cube.size);
        const float sc = 2.0f * s - 1.0f, tc = 2.0f * t - 1.0f;
        // A texel's solid angle is (4 / size^2) (1 + sc^2 + tc^2)^(-3/2); the constant factor
        // cancels in the normalisation.
        const float r2 = 1.0f + sc * sc + tc * tc;
        const float solid_angle = 1.0f / (r2 * std::sqrt(r2));
        const std::array<float, 9> y9 = sh9_basis(cube_direction(CubeFace(f), s, t));
        const glm::vec3 radiance(cube.at(CubeFace(f), x, y));
        for (std::size_t i = 0; i < 9; ++i) sh[i] += radiance * (y9[i] * solid_angle);
        total += solid_angle;
      }
  for (glm::vec3& c : sh) c *= 4.0f * kPi / total;
  return sh;
}

glm::vec3 prefiltered_radiance(const CubeMap& cube, const glm::vec3& r, float roughness,
                               std::uint32_t samples) {
  if (cube.size <= 0 || samples == 0) return glm::vec3(0.0f);
  const glm::vec3 n = glm::normalize(r);
  const float alpha = std::pow(std::clamp(roughness, kMinRoughness, 1.0f), 2.0f);
  const glm::vec3 up = std::abs(n.y) < 0.999f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  const glm::vec3 tx = glm::normalize(glm::cross(up, n));
  const glm::vec3 ty = glm::cross(n, tx);
  glm::vec3 sum(0.0f);
  float weight = 0.0f;
  for (std::uint32_t i = 0; i < samples; ++i) {
    const glm::vec3 hl = ggx_sample_half_vector(hammersley(i, samples), alpha);
    const glm::vec3 h = tx * hl.x + ty * hl.y + n * hl.z;
    const glm::vec3 l = 2.0f * glm::dot(n, h) * h - n;
    const float n_dot_l = glm::dot(n, l);
    if (n_dot_l <= 0.0f) continue;
    sum += glm::vec3(sample_cube(cube, l)) * n_dot_l;
    weight += n_dot_l;
  }
  return weight > 0.0f ? sum / weight : glm::vec3(0.0f);
}

}  // namespace kaskad
