// View-frustum culling of draws (outside_clip_volume in components/bounds.h): boxes in front of,
// beside, behind and around a perspective camera, and the six faces of a probe cube.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "components/bounds.h"

namespace kaskad {
namespace {

Aabb unit_box_at(glm::vec3 c) { return Aabb::from_corners(c - 0.5f, c + 0.5f); }

TEST(FrustumCulling, BoxesOutsideAPerspectiveViewAreCulled) {
  // Eye at the origin looking down -Z, 90 degrees vertical, square, near 0.1, far 100.
  const glm::mat4 vp = glm::perspective(glm::radians(90.0f), 1.0f, 0.1f, 100.0f) *
                       glm::lookAt(glm::vec3(0), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0));
  EXPECT_FALSE(outside_clip_volume(vp, unit_box_at({0, 0, -10})));    // straight ahead
  EXPECT_FALSE(outside_clip_volume(vp, unit_box_at({9.9f, 0, -10})));  // at the right edge
  EXPECT_TRUE(outside_clip_volume(vp, unit_box_at({12, 0, -10})));    // right of the view
  EXPECT_TRUE(outside_clip_volume(vp, unit_box_at({0, -12, -10})));   // below
  EXPECT_TRUE(outside_clip_volume(vp, unit_box_at({0, 0, 10})));      // behind the eye
  EXPECT_TRUE(outside_clip_volume(vp, unit_box_at({0, 0, -200})));    // beyond far
  EXPECT_FALSE(outside_clip_volume(vp, unit_box_at({0, 0, 0})));      // around the eye
  // A large box enclosing the whole frustum has all corners outside, but not beyond one plane.
  EXPECT_FALSE(outside_clip_volume(vp, Aabb::from_corners(glm::vec3(-500), glm::vec3(500))));
  EXPECT_FALSE(outside_clip_volume(vp, Aabb{}));  // empty: unknown, drawn
}

TEST(FrustumCulling, EachProbeFaceKeepsOnlyWhatItSees) {
  // 90 degree faces at the origin: a box on +X is seen by the +X face only.
  const glm::mat4 proj = glm::perspective(glm::radians(90.0f), 1.0f, 0.05f, 50.0f);
  const glm::vec3 dirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const glm::vec3 ups[6] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
  for (int box_face = 0; box_face < 6; ++box_face) {
    const Aabb box = unit_box_at(5.0f * dirs[box_face]);
    for (int f = 0; f < 6; ++f) {
      const glm::mat4 vp = proj * glm::lookAt(glm::vec3(0), dirs[f], ups[f]);
      EXPECT_EQ(outside_clip_volume(vp, box), f != box_face) << "box " << box_face << " face " << f;
    }
  }
}

}  // namespace
}  // namespace kaskad
