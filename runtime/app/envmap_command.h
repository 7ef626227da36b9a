// CLI pieces for environment maps and the ray-traced references (docs/guide/envmaps.md; the
// reference outputs in docs/guide/cli.md, "What `kaskad render` prints and writes"):
// `kaskad envmap`, `kaskad render --reflection-reference` and `--shadow-reference`.
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "runtime/assets/env_map.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/scene.h"
#include "runtime/result/result.h"

namespace kaskad {

/// What `kaskad envmap` was asked for (runtime/cli/ reads it from the command line).
struct EnvmapOptions {
  std::string input;      ///< a file, a face pattern sky_*.png or a folder of faces
  EnvLoadOptions load;    ///< the layout (auto: detected) and the 3ds Max conversion
  std::string faces_out;  ///< empty: no faces written; else a pattern with * or a folder
  std::string sphere_out;  ///< empty: no sphere map written
  int sphere_size = 0;     ///< pixels; 0: twice the cube's face size
};

/// `kaskad envmap`: loads an environment map in any layout, prints what it found and how long
/// loading took, and writes faces / a sphere map. Outputs are checked before any work. Returns
/// the exit status: 0 success, 1 content error.
int run_envmap(const EnvmapOptions& options);

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
