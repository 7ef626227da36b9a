// components/ibl.h, image-based lighting's formulas on the CPU, checked against independent
// evaluations: the split-sum table against brute-force integration of components/brdf.h's
// BRDF over the hemisphere, the SH irradiance against direct integration of a cube map, and the
// white furnace (a white surface in a uniform environment reflects exactly that radiance).
#include "components/ibl.h"

#include <gtest/gtest.h>

#include <cmath>

#include "runtime/assets/env_lighting.h"

namespace kaskad {
namespace {

// The directional albedo of the specular lobe, int f_s(l, v) N.L dl over the hemisphere, by a
// midpoint rule in (cos theta, phi): brdf_evaluate() of a metal of base colour f0 has no diffuse
// lobe, so it is f_s with F's f0.
float specular_albedo(float n_dot_v, float roughness, float f0) {
  const glm::vec3 n(0, 0, 1), v(std::sqrt(1.0f - n_dot_v * n_dot_v), 0.0f, n_dot_v);
  const BrdfInputs in{glm::vec3(f0), 1.0f, roughness};
  const int steps_mu = 2000, steps_phi = 400;
  double sum = 0.0;
  for (int i = 0; i < steps_mu; ++i) {
    const float mu = (float(i) + 0.5f) / steps_mu;
    const float s = std::sqrt(1.0f - mu * mu);
    for (int j = 0; j < steps_phi; ++j) {
      const float phi = 2.0f * kPi * (float(j) + 0.5f) / steps_phi;
      const glm::vec3 l(s * std::cos(phi), s * std::sin(phi), mu);
      sum += double(brdf_evaluate(in, n, v, l).x) * mu;
    }
  }
  return float(sum * (2.0 * 3.14159265358979 / (double(steps_mu) * steps_phi)));
}

TEST(Ibl, SplitSumTableIsTheBrdfsDirectionalAlbedo) {
  // f0 = 0 gives B, f0 = 1 gives A + B. Rough lobes only: the midpoint rule cannot resolve a
  // narrow peak, and the table's samples are exact there anyway (the lobe is a reflection).
  for (float roughness : {0.35f, 0.6f, 1.0f})
    for (float n_dot_v : {0.15f, 0.5f, 0.9f}) {
      const glm::vec2 ab = dfg_integrate(n_dot_v, roughness, 4096);
      EXPECT_NEAR(ab.y, specular_albedo(n_dot_v, roughness, 0.0f), 4e-3f)
          << "roughness " << roughness << ", N.V " << n_dot_v;
      EXPECT_NEAR(ab.x + ab.y, specular_albedo(n_dot_v, roughness, 1.0f), 1e-2f)
          << "roughness " << roughness << ", N.V " << n_dot_v;
      // The table, looked up bilinearly between its texel centres, stays close.
      const glm::vec2 t = dfg_lookup(n_dot_v, roughness);
      EXPECT_NEAR(t.x, ab.x, 2e-2f);
      EXPECT_NEAR(t.y, ab.y, 1e-2f);
    }
  // A smooth surface seen head-on reflects all of a white metal's energy.
  const glm::vec2 mirror = dfg_integrate(1.0f, 0.0f, 512);
  EXPECT_NEAR(mirror.x + mirror.y, 1.0f, 2e-3f);
}

TEST(Ibl, WhiteFurnaceReflectsTheEnvironment) {
  // A white surface, metal or not, of any roughness, seen from any angle, in a uniform
  // environment of radiance L: single scattering plus the multiple-scattering term plus what
  // diffuse gets of the rest add up to L.
  const glm::vec3 l(0.7f, 0.5f, 0.25f);
  for (float metallic : {0.0f, 1.0f})
    for (float roughness : {0.0f, 0.3f, 0.7f, 1.0f})
      for (float n_dot_v : {0.05f, 0.4f, 1.0f}) {
        const BrdfInputs in{glm::vec3(1.0f), metallic, roughness};
        const glm::vec3 out = ibl_combine(
            in, n_dot_v, dfg_lookup(n_dot_v, std::max(roughness, kMinRoughness)), l, l);
        EXPECT_NEAR(out.x, l.x, 1e-5f) << metallic << " " << roughness << " " << n_dot_v;
        EXPECT_NEAR(out.z, l.z, 1e-5f) << metallic << " " << roughness << " " << n_dot_v;
      }
  // A black dielectric keeps only its specular reflection: far below L, above 0.
  const BrdfInputs black{glm::vec3(0.0f), 0.0f, 0.5f};
  const glm::vec3 out = ibl_combine(black, 0.8f, dfg_lookup(0.8f, 0.5f), l, l);
  EXPECT_GT(out.x, 0.02f * l.x);
  EXPECT_LT(out.x, 0.1f * l.x);
}

CubeMap sky(int size) {
  // Brighter above, coloured by direction: smooth, so SH and prefiltering are well behaved.
  return make_cube_map(size, [](const glm::vec3& d) {
    return glm::vec4(0.5f + 0.5f * d.y, 0.3f + 0.2f * d.x, 0.2f + 0.1f * d.z * d.z, 1.0f);
  });
}

// E(n) / pi by summing the cube's texels: (1 / pi) sum L max(n.d, 0) dw.
glm::vec3 irradiance_over_pi(const CubeMap& cube, const glm::vec3& n) {
  glm::vec3 sum(0.0f);
  float total = 0.0f;
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < cube.size; ++y)
      for (int x = 0; x < cube.size; ++x) {
        const float s = (x + 0.5f) / cube.size, t = (y + 0.5f) / cube.size;
        const float sc = 2 * s - 1, tc = 2 * t - 1, r2 = 1 + sc * sc + tc * tc;
        const float w = 1.0f / (r2 * std::sqrt(r2));
        const glm::vec3 d = cube_direction(CubeFace(f), s, t);
        sum += glm::vec3(cube.at(CubeFace(f), x, y)) * (w * std::max(glm::dot(n, d), 0.0f));
        total += w;
      }
  return sum * (4.0f / total);  // (4 pi / total) / pi
}

TEST(Ibl, ShIrradianceMatchesIntegratingTheCube) {
  const CubeMap cube = sky(32);
  const Sh9 sh = project_sh9(cube);
  // A linear-plus-quadratic environment lies in SH bands 0-2, so nine coefficients hold it and
  // the irradiance is exact up to the cube's sampling.
  for (const glm::vec3& n : {glm::vec3(0, 1, 0), glm::vec3(0, -1, 0), glm::vec3(1, 0, 0),
                             glm::normalize(glm::vec3(1, 1, -1)), glm::vec3(0, 0, -1)}) {
    const glm::vec3 want = irradiance_over_pi(cube, n), got = sh9_irradiance_over_pi(sh, n);
    EXPECT_NEAR(got.x, want.x, 5e-3f);
    EXPECT_NEAR(got.y, want.y, 5e-3f);
    EXPECT_NEAR(got.z, want.z, 5e-3f);
  }
  // A uniform environment: its radiance, whatever the normal; sh9_uniform() agrees.
  const glm::vec3 l(0.3f, 0.6f, 0.9f);
  const Sh9 flat = project_sh9(make_cube_map(8, [&](const glm::vec3&) { return glm::vec4(l, 1); }));
  const Sh9 uniform = sh9_uniform(l);
  for (const glm::vec3& n : {glm::vec3(0, 1, 0), glm::normalize(glm::vec3(-1, 2, 3))}) {
    EXPECT_NEAR(sh9_irradiance_over_pi(flat, n).y, l.y, 1e-4f);
    EXPECT_NEAR(sh9_irradiance_over_pi(uniform, n).z, l.z, 1e-4f);
  }
}

TEST(Ibl, PrefilteringKeepsAUniformEnvironmentAndBlursALobe) {
  const glm::vec3 l(0.25f, 0.5f, 1.0f);
  const CubeMap flat = make_cube_map(8, [&](const glm::vec3&) { return glm::vec4(l, 1); });
  for (float r : {0.1f, 0.5f, 1.0f}) {
    const glm::vec3 p = prefiltered_radiance(flat, glm::vec3(0.3f, 0.9f, 0.1f), r, 128);
    EXPECT_NEAR(p.z, l.z, 1e-4f);
  }
  // Half bright, half dark (y > 0 lit): 45 degrees above the horizon a smooth lobe sees only
  // the bright half; a rough lobe reaches below the horizon and darkens; along the horizon,
  // about half. (Straight up even the roughest lobe stays bright: it keeps N.L > 0.)
  const CubeMap half = make_cube_map(32, [](const glm::vec3& d) {
    return glm::vec4(d.y > 0.0f ? 1.0f : 0.0f, 0, 0, 1);
  });
  const glm::vec3 up45 = glm::normalize(glm::vec3(1, 1, 0));
  EXPECT_NEAR(prefiltered_radiance(half, up45, 0.05f, 512).x, 1.0f, 1e-3f);
  EXPECT_NEAR(prefiltered_radiance(half, glm::vec3(0, 1, 0), 1.0f, 512).x, 1.0f, 1e-3f);
  const float rough = prefiltered_radiance(half, up45, 1.0f, 2048).x;
  EXPECT_LT(rough, 0.99f);
  EXPECT_GT(rough, 0.7f);
  EXPECT_NEAR(prefiltered_radiance(half, glm::vec3(1, 0, 0), 0.8f, 4096).x, 0.5f, 0.05f);
}

}  // namespace
}  // namespace kaskad
