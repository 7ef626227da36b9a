// The cube and sphere-map direction maths alone (kaskad::math): each mapping inverts the other.
// The maps built on them (sampling, loaders, S3's tables) are tested in assets_test.
#include <gtest/gtest.h>

#include <cmath>

#include "runtime/math/sphere_map_math.h"

namespace kaskad {
namespace {

TEST(SphereMapMath, CubeCoordInvertsCubeDirectionOnEveryFace) {
  for (int f = 0; f < 6; ++f)
    for (float s : {0.05f, 0.3f, 0.5f, 0.77f, 0.95f})
      for (float t : {0.05f, 0.4f, 0.5f, 0.81f, 0.95f}) {
        const glm::vec3 d = cube_direction(CubeFace(f), s, t);
        EXPECT_NEAR(glm::length(d), 1.0f, 1e-6f);
        const CubeCoord c = cube_coord(d * 3.0f);  // need not be unit
        EXPECT_EQ(int(c.face), f);
        EXPECT_NEAR(c.s, s, 1e-5f);
        EXPECT_NEAR(c.t, t, 1e-5f);
      }
  const CubeCoord zero = cube_coord(glm::vec3(0.0f));
  EXPECT_EQ(zero.face, CubeFace::pos_z);
  EXPECT_EQ(cube_coord(glm::vec3(NAN, 1, 0)).s, 0.5f);
}

TEST(SphereMapMath, SphereMapUvFindsTheTexelWhoseDirectionItIs) {
  const int size = 64;
  for (int j = 0; j < size; j += 7)
    for (int i = 0; i < size; i += 5) {
      const glm::vec3 r = sphere_map_direction(i, j, size);
      const float s = 2.0f * (float(i) + 0.5f) / float(size) - 1.0f;
      const float t = 1.0f - 2.0f * (float(j) + 0.5f) / float(size);
      if (s * s + t * t >= 1.0f) {
        EXPECT_EQ(r, glm::vec3(0, 0, -1));  // outside the circle: the rim value
        continue;
      }
      EXPECT_NEAR(glm::length(r), 1.0f, 1e-5f);
      const glm::vec2 uv = sphere_map_uv(r);
      EXPECT_NEAR(uv.x * float(size) - 0.5f, float(i), 1e-3f);
      EXPECT_NEAR((1.0f - uv.y) * float(size) - 0.5f, float(j), 1e-3f);  // rows from the top
    }
  EXPECT_EQ(sphere_map_uv(glm::vec3(0, 0, -1)), glm::vec2(1.0f, 0.5f));
}

TEST(SphereMapMath, MRotTurnsYUpIntoZUp) {
  EXPECT_EQ(m_rot(glm::vec3(0, 1, 0)), glm::vec3(0, 0, 1));
  EXPECT_EQ(m_rot(glm::vec3(0, 0, 1)), glm::vec3(0, -1, 0));
  EXPECT_EQ(m_rot(glm::vec3(1, 0, 0)), glm::vec3(1, 0, 0));
}

}  // namespace
}  // namespace kaskad
