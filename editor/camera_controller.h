// The editor's fly camera: a position and a heading that the user moves (keys, mouse, F, orbit)
// and the editor writes into the scene's active camera (camera_controller.cpp).
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

namespace kaskad::editor {

// The fly camera: a position and a heading, written into the scene's active camera when moved.
struct FlyCamera {
  glm::vec3 position{0.0f};
  float yaw = 0.0f;    ///< radians about +Y; 0 looks down -Z
  float pitch = 0.0f;  ///< radians above the horizon
  bool moved = false;  ///< the user moved it since load (then it is kept over undo and redo)

  glm::vec3 forward() const {
    return {std::sin(yaw) * std::cos(pitch), std::sin(pitch), -std::cos(yaw) * std::cos(pitch)};
  }
  void look_along(const glm::vec3& d) {
    const glm::vec3 n = glm::normalize(d);
    pitch = std::asin(std::clamp(n.y, -1.0f, 1.0f));
    yaw = std::atan2(n.x, -n.z);
  }
};

}  // namespace kaskad::editor
