// The basic shadow map's light projection: maths only, no GL.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/gtc/quaternion.hpp>

#include "systems/shadow_map_system.h"

namespace kaskad {
namespace {

void expect_encloses(const LightProjection& lp, const Aabb& b) {
  const glm::mat4 m = lp.view_proj();
  for (float v : {m[0][0], m[1][1], m[2][2], m[3][0], m[3][1], m[3][2]}) ASSERT_TRUE(std::isfinite(v));
  ASSERT_GT(std::abs(glm::determinant(m)), 0.0f);
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 c{(i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y,
                      (i & 4) ? b.max.z : b.min.z};
    const glm::vec4 clip = m * glm::vec4(c, 1.0f);
    EXPECT_LE(std::abs(clip.x / clip.w), 1.0f + 1e-4f) << "corner " << i;
    EXPECT_LE(std::abs(clip.y / clip.w), 1.0f + 1e-4f) << "corner " << i;
    EXPECT_LE(std::abs(clip.z / clip.w), 1.0f + 1e-4f) << "corner " << i;
  }
}

TEST(BasicShadow, FitEnclosesTheBoundsTightly) {
  const Aabb b = Aabb::from_corners({-20, 0, -20}, {20, 3, 20});
  const LightProjection lp = fit_ortho_light_to_bounds(glm::normalize(glm::vec3(-0.45f, -0.65f, -0.6f)), b);
  expect_encloses(lp, b);
  // Tight: some corner touches the x and y borders.
  float max_x = 0, max_y = 0;
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 c{(i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y, (i & 4) ? b.max.z : b.min.z};
    const glm::vec4 clip = lp.view_proj() * glm::vec4(c, 1.0f);
    max_x = std::max(max_x, std::abs(clip.x));
    max_y = std::max(max_y, std::abs(clip.y));
  }
  EXPECT_NEAR(max_x, 1.0f, 1e-4f);
  EXPECT_NEAR(max_y, 1.0f, 1e-4f);
}

TEST(BasicShadow, DegenerateDirectionsGiveValidMatrices) {
  const Aabb b = Aabb::from_corners({-5, 0, -5}, {5, 2, 5});
  for (glm::vec3 d : {glm::vec3(0, -1, 0), glm::vec3(0, 1, 0), glm::vec3(1, 0, 0), glm::vec3(0, 0, -1),
                      glm::vec3(1e-7f, -1, 0)})
    expect_encloses(fit_ortho_light_to_bounds(d, b), b);
}

TEST(BasicShadow, FlatBoundsStayInvertible) {
  const Aabb plane = Aabb::from_corners({-5, 0, -5}, {5, 0, 5});
  expect_encloses(fit_ortho_light_to_bounds(glm::vec3(0, -1, 0), plane), plane);
  expect_encloses(fit_ortho_light_to_bounds(glm::vec3(1, 0, 0), plane), plane);  // edge-on
}

TEST(BasicShadow, LightDirectionIsMinusZOfTheEntity) {
  const glm::mat4 m = glm::mat4_cast(glm::angleAxis(glm::radians(-90.0f), glm::vec3(1, 0, 0)));
  const glm::vec3 d = light_direction(m);
  EXPECT_NEAR(d.y, -1.0f, 1e-6f);
}

}  // namespace
}  // namespace kaskad
