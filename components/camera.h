// A camera looking along the entity's local -Z axis with +Y up (glTF convention).
#pragma once

namespace kaskad {

enum class Projection { perspective, orthographic };

struct Camera {
  Projection projection = Projection::perspective;
  float fov_y_deg = 50.0f;   ///< perspective: full vertical field of view, degrees
  float ortho_height = 10.0f;///< orthographic: full view height, metres
  float near = 0.1f;         ///< metres, > 0
  float far = 200.0f;        ///< metres, > near
  float aspect = 0.0f;       ///< width / height; 0 = take it from the output image
  bool active = false;       ///< the first active camera renders; else the first camera found
  bool auto_frame = false;   ///< on load, back the camera off along its view axis to frame the scene
};

}  // namespace kaskad
