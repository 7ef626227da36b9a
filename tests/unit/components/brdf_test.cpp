// components/brdf.h, the CPU glTF BRDF, checked against properties the formulas must have:
// GGX's D is a normalised distribution of projected microfacet area; the height-correlated V
// equals Heitz's G2 = 1 / (1 + Lambda(v) + Lambda(l)) over 4 N.L N.V; Schlick's F runs from f0
// to 1; f is reciprocal; metals have no diffuse lobe; a dielectric's diffuse part is
// (1 - F) c / pi whatever the roughness.
#include "components/brdf.h"

#include <gtest/gtest.h>

#include <cmath>

namespace kaskad {
namespace {

glm::vec3 direction(float theta, float phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

TEST(Brdf, GgxDistributionIsNormalised) {
  // Integral over the hemisphere of D(h) (N.h) dw = 1 (midpoint rule in cos theta).
  for (float alpha : {0.1f, 0.3f, 0.6f, 1.0f}) {
    const int steps = 200000;
    double sum = 0.0;
    for (int i = 0; i < steps; ++i) {
      const double mu = (i + 0.5) / steps;
      const glm::vec3 h(float(std::sqrt(1.0 - mu * mu)), 0.0f, float(mu));
      sum += double(brdf_distribution_ggx(glm::vec3(0, 0, 1), h, alpha)) * mu *
             (2.0 * 3.14159265358979 / steps);
    }
    EXPECT_NEAR(sum, 1.0, 2e-3) << "alpha " << alpha;
  }
}

TEST(Brdf, HeightCorrelatedVisibilityIsHeitzG2) {
  auto lambda = [](float cosine, float alpha) {  // Heitz 2014 eq. 72 for GGX
    const float tan2 = (1.0f - cosine * cosine) / (cosine * cosine);
    return 0.5f * (-1.0f + std::sqrt(1.0f + alpha * alpha * tan2));
  };
  for (float alpha : {0.01f, 0.2f, 0.5f, 1.0f})
    for (float nl : {0.05f, 0.3f, 0.7f, 1.0f})
      for (float nv : {0.02f, 0.4f, 0.9f, 1.0f}) {
        const float g2 = 1.0f / (1.0f + lambda(nl, alpha) + lambda(nv, alpha));
        const float want = g2 / (4.0f * nl * nv);
        EXPECT_NEAR(brdf_visibility_smith_correlated(nl, nv, alpha), want, 1e-4f * want)
            << alpha << " " << nl << " " << nv;
      }
}

TEST(Brdf, SchlickRunsFromF0ToOne) {
  const glm::vec3 f0(0.04f, 0.5f, 0.9f);
  EXPECT_EQ(brdf_fresnel_schlick(f0, 1.0f), f0);
  EXPECT_EQ(brdf_fresnel_schlick(f0, 0.0f), glm::vec3(1.0f));
  EXPECT_NEAR(brdf_fresnel_schlick(f0, 0.5f).x, 0.04f + 0.96f / 32.0f, 1e-6f);
}

TEST(Brdf, ReciprocalMetalsHaveNoDiffuseDielectricDiffuseIsLambert) {
  const glm::vec3 n(0.0f, 0.0f, 1.0f);
  for (float roughness : {0.1f, 0.5f, 1.0f})
    for (float tv : {0.1f, 0.8f, 1.4f})
      for (float tl : {0.0f, 0.6f, 1.3f}) {
        const glm::vec3 v = direction(tv, 0.3f), l = direction(tl, 2.5f);
        BrdfInputs in{glm::vec3(0.9f, 0.5f, 0.2f), 0.3f, roughness};
        const glm::vec3 a = brdf_evaluate(in, n, v, l), b = brdf_evaluate(in, n, l, v);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-5f * std::max(1.0f, a[c]));
        // Metal: f = F D V alone.
        in.metallic = 1.0f;
        const glm::vec3 h = glm::normalize(l + v);
        const float alpha = roughness * roughness;
        const glm::vec3 spec = brdf_fresnel_schlick(in.base, glm::dot(v, h)) *
                               brdf_distribution_ggx(n, h, alpha) *
                               brdf_visibility_smith_correlated(l.z, v.z, alpha);
        const glm::vec3 metal = brdf_evaluate(in, n, v, l);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(metal[c], spec[c], 1e-5f * std::max(1.0f, spec[c]));
        // Dielectric: f - F D V = (1 - F) c / pi with F of f0 0.04.
        in.metallic = 0.0f;
        const glm::vec3 f = brdf_fresnel_schlick(glm::vec3(0.04f), glm::dot(v, h));
        const glm::vec3 diffuse =
            brdf_evaluate(in, n, v, l) - f * brdf_distribution_ggx(n, h, alpha) *
                                             brdf_visibility_smith_correlated(l.z, v.z, alpha);
        const glm::vec3 lambert = (glm::vec3(1.0f) - f) * in.base / kPi;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(diffuse[c], lambert[c], 1e-5f);
      }
  // Light below the surface: nothing.
  EXPECT_EQ(brdf_evaluate({}, n, n, -n), glm::vec3(0.0f));
}

}  // namespace
}  // namespace kaskad
