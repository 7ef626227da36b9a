// Axis-aligned bounds. LocalBounds comes from the mesh; WorldBounds is derived by the
// TransformSystem (the 8 transformed corners of the local box).
#pragma once

#include <algorithm>
#include <limits>

#include <glm/glm.hpp>

namespace kaskad {

struct Aabb {
  glm::vec3 min{std::numeric_limits<float>::max()};
  glm::vec3 max{-std::numeric_limits<float>::max()};

  /// The box spanned by two opposite corners (in any order).
  static Aabb from_corners(const glm::vec3& a, const glm::vec3& b) {
    Aabb box;
    box.expand(a);
    box.expand(b);
    return box;
  }

  bool empty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
  glm::vec3 center() const { return 0.5f * (min + max); }
  glm::vec3 extent() const { return max - min; }
  void expand(const glm::vec3& p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
  void expand(const Aabb& b) {
    if (b.empty()) return;
    expand(b.min);
    expand(b.max);
  }
  /// Corner i of 8: bit 0 picks max.x, bit 1 max.y, bit 2 max.z.
  glm::vec3 corner(int i) const {
    return {(i & 1) ? max.x : min.x, (i & 2) ? max.y : min.y, (i & 4) ? max.z : min.z};
  }
  /// The box of the 8 corners of this box transformed by m (empty stays empty).
  Aabb transformed(const glm::mat4& m) const {
    Aabb out;
    if (empty()) return out;
    for (int i = 0; i < 8; ++i) out.expand(glm::vec3(m * glm::vec4(corner(i), 1.0f)));
    return out;
  }
};

/// Whether `box` lies entirely outside the clip volume of `view_proj` (-w <= x, y, z <= w): all 8
/// corners beyond one of the six clip planes. Conservative (a box near a frustum corner may be
/// kept) and exact for corners behind the eye, since each plane test is linear in homogeneous
/// coordinates. An empty box is never outside (nothing known: draw it).
inline bool outside_clip_volume(const glm::mat4& view_proj, const Aabb& box) {
  if (box.empty()) return false;
  int out[6] = {0, 0, 0, 0, 0, 0};
  for (int i = 0; i < 8; ++i) {
    const glm::vec4 c = view_proj * glm::vec4(box.corner(i), 1.0f);
    out[0] += c.x < -c.w;
    out[1] += c.x > c.w;
    out[2] += c.y < -c.w;
    out[3] += c.y > c.w;
    out[4] += c.z < -c.w;
    out[5] += c.z > c.w;
  }
  for (int n : out)
    if (n == 8) return true;
  return false;
}

/// Derived: world-space bounds of an entity's mesh.
struct WorldBounds {
  Aabb box;
};

}  // namespace kaskad
