// Every components/ header and every runtime/math/ header compiled in an object library that links
// kaskad::math alone (math_headers_check, built with the tests): the plain data and the maths need
// GLM, ecs::Entity and result.h, nothing of the GL, asset or render layers; a header that needs more
// fails the build. (cmake/check_layers.cmake checks the include lines themselves.)
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
#include "runtime/math/cascade_math.h"
#include "runtime/math/local_light_math.h"
#include "runtime/math/sphere_map_math.h"
