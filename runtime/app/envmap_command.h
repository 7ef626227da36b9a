// CLI pieces for environment maps and the ray-traced references (README "Environment maps",
// "Soft shadows"): `kaskad envmap`, `kaskad render --reflection-reference` and
// `--shadow-reference`.
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "runtime/assets/image_io.h"
#include "runtime/assets/scene.h"
#include "runtime/result/result.h"

namespace kaskad {

/// `kaskad envmap IN [options]`: loads an environment map in any layout, prints what it found
/// and how long loading took, and writes faces / a sphere map. argv[1] is "envmap". Returns the
/// exit status: 0 success, 1 content error, 2 usage error.
int run_envmap_command(int argc, char** argv);

/// Traces the reflection reference of an AOV image (Renderer::read_aovs()) rendered from `eye`
/// and writes it as EXR to `out` (channels reflection.R/G/B, reflection.hit, mask). `environment`
/// (may be empty) is loaded with load_cube_map(auto) and returned on misses, else the scene's
/// clear colour. Prints rays and speed.
Status write_reflection_reference(const Scene& scene, const Image& aov, const glm::vec3& eye,
                                  const std::string& environment, const std::string& out);

/// Traces the visibility of `light` (area lights sampled, reference::reference_light()) at the
/// surfaces of an AOV image and writes, as EXR to `out`, the channels reference, visibility (the
/// AOV's), error (visibility - reference on receivers, else 0) and receiver. Prints RMSE and MAE
/// over the receivers (reference::compare_shadows()).
Status write_shadow_reference(const Scene& scene, const Image& aov, ecs::Entity light,
                              const std::string& out);

}  // namespace kaskad
