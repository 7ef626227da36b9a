#include "runtime/math/local_light_math.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <string>

#include "runtime/result/result.h"

namespace kaskad {

NearFar local_light_near_far(const glm::vec3& position, std::span<const Aabb> boxes, float range) {
  NearFar out;
  float near = 3.4e38f, far = 0.0f;
  for (const Aabb& b : boxes) {
    if (b.empty()) continue;
    // Nearest point of the box: the position clamped to it; farthest: the opposite corner on
    // each axis.
    const glm::vec3 nearest = glm::clamp(position, b.min, b.max);
    const float dmin = glm::length(nearest - position);
    if (range > 0.0f && dmin > range) continue;
    glm::vec3 farthest;
    for (int a = 0; a < 3; ++a)
      farthest[a] =
          std::abs(b.min[a] - position[a]) > std::abs(b.max[a] - position[a]) ? b.min[a] : b.max[a];
    near = std::min(near, dmin);
    far = std::max(far, glm::length(farthest - position));
  }
  if (!(far > 0.0f)) return out;
  if (range > 0.0f) far = std::min(far, range);
  out.near = std::min(near, far);
  out.far = far;
  out.empty = false;
  return out;
}

float local_light_near(const NearFar& range, float tan_half) {
  const float corner = std::sqrt(1.0f + 2.0f * tan_half * tan_half);
  return std::max(0.9f * range.near / corner, 1e-3f * range.far);
}

float widen_tan_half_fov(float tan_half, int map_size, float border_texels) {
  KASKAD_CHECK(tan_half > 0.0f && float(map_size) > 2.0f * border_texels && border_texels >= 0.0f,
               "widen_tan_half_fov: needs tan_half > 0 and map_size > 2 * border, was " +
                   std::to_string(tan_half) + ", " + std::to_string(map_size) + ", " +
                   std::to_string(border_texels));
  // The cone spans map_size - 2 * border texels of the map's map_size.
  return tan_half * float(map_size) / (float(map_size) - 2.0f * border_texels);
}

namespace {

PerspectiveShadow perspective_shadow(const glm::vec3& position, const glm::vec3& direction,
                                     const glm::vec3& up, float tan_half, float near, float far,
                                     int map_size) {
  PerspectiveShadow out;
  out.view = glm::lookAt(position, position + direction, up);
  out.proj = glm::perspective(2.0f * std::atan(tan_half), 1.0f, near, far);
  out.texel_at_unit_distance = 2.0f * tan_half / float(map_size);
  return out;
}

}  // namespace

float spot_tan_half_fov(float outer_cone_deg, int map_size, float border_texels) {
  constexpr float kMaxHalfDeg = 89.0f;
  const float cone = std::clamp(outer_cone_deg, 0.5f, kMaxHalfDeg);
  return std::min(widen_tan_half_fov(std::tan(glm::radians(cone)), map_size, border_texels),
                  std::tan(glm::radians(kMaxHalfDeg)));
}

PerspectiveShadow fit_spot_shadow(const glm::vec3& position, const glm::vec3& direction,
                                  float tan_half, float near, float far, int map_size,
                                  const glm::vec3& up) {
  KASKAD_CHECK(glm::length(direction) > 0.0f && tan_half > 0.0f && near > 0.0f && far > near,
               "fit_spot_shadow: needs a direction, tan_half > 0 and 0 < near < far, was near " +
                   std::to_string(near) + ", far " + std::to_string(far));
  const glm::vec3 dir = glm::normalize(direction);
  // The given up unless it is (nearly) parallel to the direction or not finite.
  const glm::vec3 side = glm::cross(dir, up);
  const bool finite_up = std::isfinite(up.x) && std::isfinite(up.y) && std::isfinite(up.z);
  const bool usable = finite_up && glm::dot(side, side) > 1e-6f * glm::dot(up, up);
  return perspective_shadow(position, dir, usable ? up : light_up_vector(dir), tan_half, near, far,
                            map_size);
}

int cube_face_of(const glm::vec3& d) {
  const glm::vec3 a = glm::abs(d);
  if (a.x >= a.y && a.x >= a.z) return d.x >= 0.0f ? 0 : 1;
  if (a.y >= a.z) return d.y >= 0.0f ? 2 : 3;
  return d.z >= 0.0f ? 4 : 5;
}

PerspectiveShadow cube_face_shadow(const glm::vec3& position, int face, float tan_half, float near,
                                   float far, int map_size) {
  KASKAD_CHECK(face >= 0 && face < kCubeFaces,
               "cube_face_shadow: face must be in [0, 6), was " + std::to_string(face));
  // GL's cube-map face axes (forward, up); any up would do, these make the dumped layers read
  // like a cube map's.
  static const glm::vec3 kForward[kCubeFaces] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                                 {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  static const glm::vec3 kUp[kCubeFaces] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1},
                                            {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
  return perspective_shadow(position, kForward[face], kUp[face], tan_half, near, far, map_size);
}

std::array<glm::mat4, 2> paraboloid_views(const glm::vec3& position, const glm::vec3& direction) {
  const glm::vec3 dir = glm::normalize(direction);
  const glm::mat4 front = glm::lookAt(position, position + dir, light_up_vector(dir));
  // 180 degrees about y: (x, y, z) -> (-x, y, -z).
  const glm::mat4 turn = glm::rotate(glm::mat4(1.0f), glm::pi<float>(), glm::vec3(0, 1, 0));
  return {front, turn * front};
}

float paraboloid_margin(int map_size, float border_texels) {
  return std::min(2.0f * border_texels / float(map_size), 0.25f);
}

glm::vec3 paraboloid_project(const glm::vec3& v, float near, float far, float margin) {
  const float d = glm::length(v);
  const glm::vec3 u = d > 0.0f ? v / d : glm::vec3(0.0f, 0.0f, -1.0f);
  const glm::vec2 xy = glm::vec2(u) / ((1.0f - u.z) * (1.0f + margin));
  return {xy, 2.0f * (d - near) / (far - near) - 1.0f};
}

float paraboloid_texel_at_unit_distance(int map_size, float margin) {
  // A texel is 2 / map_size of map units; map units per radian are (1/2) / (1 + margin) at the
  // centre.
  return 4.0f * (1.0f + margin) / float(map_size);
}

}  // namespace kaskad
