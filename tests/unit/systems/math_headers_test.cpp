// Every components/ header and every systems/*_math.h compiled in a target that links kaskad::math
// alone (math_test): the plain data and the maths need GLM, ecs::Entity and result.h, nothing of
// the GL, asset or render layers. (cmake/check_layers.cmake checks the include lines themselves.)
#include "components/bounds.h"
#include "components/brdf.h"
#include "components/camera.h"
#include "components/ibl.h"
#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/name.h"
#include "components/probe_state.h"
#include "components/reflector.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "systems/cascade_math.h"
#include "systems/local_light_math.h"
#include "systems/sphere_map_math.h"

#include <gtest/gtest.h>

namespace kaskad {
namespace {

TEST(MathHeaders, ComponentsAndMathHeadersCompileAgainstKaskadMathAlone) {
  // The includes above are the test; this only makes the binary list it.
  SUCCEED();
}

}  // namespace
}  // namespace kaskad
