#include "runtime/math/sphere_map_math.h"

#include <algorithm>
#include <cmath>

namespace kaskad {

glm::vec3 cube_direction(CubeFace face, float s, float t) {
  // Table 8.19 solved for the direction on the unit cube: sc = 2s - 1, tc = 2t - 1.
  const float sc = 2.0f * s - 1.0f;
  const float tc = 2.0f * t - 1.0f;
  glm::vec3 d{0.0f};
  switch (face) {
    case CubeFace::pos_x:
      d = {1.0f, -tc, -sc};
      break;
    case CubeFace::neg_x:
      d = {-1.0f, -tc, sc};
      break;
    case CubeFace::pos_y:
      d = {sc, 1.0f, tc};
      break;
    case CubeFace::neg_y:
      d = {sc, -1.0f, -tc};
      break;
    case CubeFace::pos_z:
      d = {sc, -tc, 1.0f};
      break;
    case CubeFace::neg_z:
      d = {-sc, -tc, -1.0f};
      break;
  }
  return glm::normalize(d);
}

CubeCoord cube_coord(const glm::vec3& d) {
  const float ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
  if (!std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.z) || (ax == 0.0f && ay == 0.0f && az == 0.0f)) return {CubeFace::pos_z, 0.5f, 0.5f};
  CubeFace face;
  float sc, tc, ma;
  if (ax >= ay && ax >= az) {
    ma = ax;
    face = d.x > 0.0f ? CubeFace::pos_x : CubeFace::neg_x;
    sc = d.x > 0.0f ? -d.z : d.z;
    tc = -d.y;
  } else if (ay >= az) {
    ma = ay;
    face = d.y > 0.0f ? CubeFace::pos_y : CubeFace::neg_y;
    sc = d.x;
    tc = d.y > 0.0f ? d.z : -d.z;
  } else {
    ma = az;
    face = d.z > 0.0f ? CubeFace::pos_z : CubeFace::neg_z;
    sc = d.z > 0.0f ? d.x : -d.x;
    tc = -d.y;
  }
  // S3: e.g. +X: s = -z / (2|x|) + 1/2, t = -y / (2|x|) + 1/2.
  return {face, 0.5f * (sc / ma + 1.0f), 0.5f * (tc / ma + 1.0f)};
}

glm::vec3 sphere_map_direction(int i, int j, int size) {
  // S3 eq. (2) at the texel centre; t counts upwards, rows downwards (env_map.h, SphereMap).
  const float s = 2.0f * (float(i) + 0.5f) / float(size) - 1.0f;
  const float t = 1.0f - 2.0f * (float(j) + 0.5f) / float(size);
  const float r2 = s * s + t * t;
  if (r2 >= 1.0f) return {0.0f, 0.0f, -1.0f};
  const float az = std::sqrt(1.0f - r2);
  return {2.0f * az * s, 2.0f * az * t, 2.0f * az * az - 1.0f};
}

glm::vec2 sphere_map_uv(const glm::vec3& reflected_view) {
  const float len = glm::length(reflected_view);
  if (!(len > 0.0f) || !std::isfinite(len)) return {0.5f, 0.5f};
  const glm::vec3 r = reflected_view / len;
  // S3 eq. (4); at R = (0, 0, -1) A_z = 0 and every rim point is the answer: pick (1, 0.5).
  const float az = std::sqrt(std::max(0.0f, (r.z + 1.0f) * 0.5f));
  if (az < 1e-6f) return {1.0f, 0.5f};
  const float s = r.x / (2.0f * az);
  const float t = r.y / (2.0f * az);
  return {(s + 1.0f) * 0.5f, (t + 1.0f) * 0.5f};  // eq. (5)
}

glm::vec3 m_rot(const glm::vec3& v) {
  return {v.x, -v.z, v.y};
}

}  // namespace kaskad
