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
  /// The box of the 8 corners of this box transformed by m (empty stays empty).
  Aabb transformed(const glm::mat4& m) const {
    Aabb out;
    if (empty()) return out;
    for (int i = 0; i < 8; ++i) {
      glm::vec3 c{(i & 1) ? max.x : min.x, (i & 2) ? max.y : min.y, (i & 4) ? max.z : min.z};
      out.expand(glm::vec3(m * glm::vec4(c, 1.0f)));
    }
    return out;
  }
};

/// Derived: world-space bounds of an entity's mesh.
struct WorldBounds {
  Aabb box;
};

}  // namespace kaskad
