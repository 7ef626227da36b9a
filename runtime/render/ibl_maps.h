// GL resources of image-based lighting (components/ibl.h has the formulas): the split-sum table,
// the rows of SH coefficients (row 0 the environment map's, one row per prefiltered probe), the
// environment map's prefiltered cube, and the two fullscreen passes that make them from any cube
// with a mip chain: GGX prefiltering into a cube's levels (content/shaders/ibl_prefilter.frag)
// and SH projection into a row (sh_project.frag). ProbeMaps owns one and prefilters the probes
// of the pbr reflection model through it after each completed capture.
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

#include "runtime/assets/env_map.h"
#include "runtime/result/result.h"
#include "runtime/gpu/gl_handles.h"

namespace kaskad::render {

class GpuTimers;

// Cube textures as IblMaps and ProbeMaps make and read them (RGBA16F, trilinear, clamped).
/// Levels of a full mip chain for `size` texels a side.
int cube_mip_levels(int size);
/// Trilinear filtering and clamp to edge on every axis.
void set_cube_sampling(const gpu::Texture& cube);
/// Level `level` of a cube texture as floats (+X -X +Y -Y +Z -Z).
CubeMap read_cube_level(const gpu::Texture& cube, int level);
/// The program of a fullscreen pass: fullscreen.vert and `fragment` from `shader_dir`.
Result<gpu::Program> fullscreen_program(const std::filesystem::path& shader_dir,
                                        const char* fragment);

class IblMaps {
 public:
  /// Builds both programs from `shader_dir` and uploads the split-sum table. Needs a current GL
  /// 4.5 context.
  static Result<std::unique_ptr<IblMaps>> create(const std::filesystem::path& shader_dir);

  /// GGX samples per texel of prefiltered level k >= 1 (level 0 is the source's level 0):
  /// 16 << (k - 1), at most 64. The narrow lobes of the large levels read fine source mips
  /// already (filtered importance sampling), and those levels hold most of the texels.
  static int prefilter_samples(int level) { return std::min(64, 16 << std::max(0, level - 1)); }

  /// Prefilters cube `source` (`size` texels a side, full mip chain) into `target` (made here
  /// when empty or of another size; ibl_specular_levels(size) levels) and writes the source's SH
  /// into row `row` (grown as needed). Leaves the framebuffer and program bindings changed.
  void prefilter(const gpu::Texture& source, int size, gpu::Texture& target, int row);
  /// The two halves of prefilter(), for time slicing: faces [first, first + count) of every
  /// level, and the SH row.
  void prefilter_faces(const gpu::Texture& source, int size, gpu::Texture& target, int first,
                       int count);
  void project_sh(const gpu::Texture& source, int size, int row);

  /// The environment map (render.environment): uploaded, mipmapped and prefiltered (SH into
  /// row 0) when `cube` is another map than last time (by `key`); null: none.
  void set_environment(const CubeMap* cube, std::uint64_t key);
  /// The environment's prefiltered cube (none without one) and its ibl_specular_levels().
  gpu::TextureRef environment() const { return environment_specular_; }
  int environment_levels() const { return environment_levels_; }

  /// A free SH row for a probe (rows >= 1), and giving one back.
  int acquire_row();
  void release_row(int row);

  /// Binds the split-sum table and the SH rows to UNIT_DFG and UNIT_SH, and the environment's
  /// prefiltered cube (or a black one) to UNIT_ENVIRONMENT.
  void bind() const;

  /// Where prefiltering and SH projection are timed (TimedPart::probe_prefilter); none: not.
  void set_timers(GpuTimers* timers) { timers_ = timers; }

  /// Read-back for tests: SH row `row` (9 rgb coefficients); level `level` of the
  /// environment's prefiltered cube.
  std::vector<glm::vec3> read_sh_row(int row) const;
  CubeMap read_environment_level(int level) const;


 private:
  IblMaps() = default;
  void ensure_rows(int rows);
  /// The state of both fullscreen passes: no depth, culling, blending or sRGB writes, `source`
  /// on unit 0, the pass framebuffer bound; and undoing what the rest of the frame relies on.
  void begin_fullscreen(const gpu::Texture& source);
  void end_fullscreen();
  GpuTimers* timers_ = nullptr;
  gpu::Program prefilter_program_, sh_program_;
  gpu::VertexArray empty_vao_;
  gpu::Framebuffer fbo_;
  gpu::Texture dfg_, sh_, black_cube_;
  int sh_rows_ = 0;
  std::vector<bool> row_used_;
  gpu::Texture environment_specular_;
  int environment_levels_ = 0;
  std::uint64_t environment_key_ = 0;
};

}  // namespace kaskad::render
