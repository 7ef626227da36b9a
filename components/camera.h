// A camera looking along the entity's local -Z axis with +Y up (glTF convention).
#pragma once

#include <array>
#include <string_view>
#include <tuple>

#include "components/limits.h"
#include "runtime/fields/fields.h"

namespace kaskad {

enum class Projection { perspective, orthographic };
constexpr std::array<std::string_view, 2> enum_names(Projection) {
  return {"perspective", "orthographic"};
}
static_assert(enum_names(Projection{}).size() == std::size_t(Projection::orthographic) + 1);

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

/// The fields of Camera, once (runtime/fields/fields.h); far > near is the scene reader's rule.
constexpr auto field_table(fields::Of<Camera>) {
  using C = Camera;
  using namespace fields;
  return std::tuple{
      choice("projection", &C::projection, "Perspective or orthographic"),
      number("fov_y_deg", &C::fov_y_deg, 0.01, 179, "Perspective: full vertical field of view, degrees"),
      number("ortho_height", &C::ortho_height, 1e-6, kMaxCoordinate,
             "Orthographic: full view height, metres"),
      number("near", &C::near, 1e-7, kMaxCoordinate, "Near plane, metres"),
      number("far", &C::far, 1e-6, 1e12, "Far plane, metres; greater than near"),
      number("aspect", &C::aspect, 0, 1000, "Width / height; 0 takes it from the output image"),
      flag("active", &C::active, "The first active camera renders; else the first camera found"),
      flag("auto_frame", &C::auto_frame, "On load, backs off along the view axis to frame the scene"),
  };
}

}  // namespace kaskad
