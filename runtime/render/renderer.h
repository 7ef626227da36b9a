// The forward renderer: a depth-only shadow pass over the shadow views (one layer of a depth
// texture array per cascade, face or hemisphere), probe captures, then one forward pass that
// writes colour and the AOVs (world position + mask, facing normal + view depth, shadow
// visibility + cascade) into an offscreen framebuffer. Headless and windowed use the same passes;
// a window only adds present().
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/assets/asset_store.h"
#include "runtime/assets/env_map.h"
#include "runtime/assets/image_io.h"
#include "runtime/result/result.h"
#include "runtime/gpu/gl_handles.h"
#include "runtime/render/shader_library.h"
#include "runtime/render/draw_list.h"
#include "runtime/render/frame_input.h"
#include "runtime/render/frame_stats.h"
#include "runtime/features/variant_key.h"

namespace kaskad::render {

struct RendererOptions {
  std::filesystem::path shader_cache_dir;  ///< empty: no binary cache
  bool uber_oracle = false;  ///< tests only: one über-program per pass, features by uniform
};

class Renderer {
 public:
  /// Needs a current GL 4.5 context. `shader_dir` holds the GLSL files (content/shaders).
  static Result<std::unique_ptr<Renderer>> create(const std::filesystem::path& shader_dir,
                                                  const RendererOptions& options = {});

  /// Compiles (or loads from the binary cache) every program `frame` needs, before the first
  /// frame, and with `shadow_points` the points pass's (shadow_at_points()). Programs built later
  /// count as runtime compiles in stats().shaders.
  Status prewarm(const FrameInput& frame, bool shadow_points = false);
  ShaderLibrary& shaders();
  ~Renderer();

  /// Checks before the first frame that render targets of `width` x `height` can be made: the
  /// GL limits (GL_MAX_TEXTURE_SIZE, GL_MAX_RENDERBUFFER_SIZE, GL_MAX_VIEWPORT_DIMS), the driver's
  /// answer for each target format (proxy textures: llvmpipe refuses textures over 1 GiB) and an
  /// estimate of the memory the targets and read-backs take against the memory available.
  /// With `msaa` > 1 (render.msaa), the multisampled colour and depth targets count too.
  /// The error names the size and what refused it.
  Status check_target_size(int width, int height, bool read_aovs, int msaa = 1) const;

  /// Records and submits the shadow and forward passes. Meshes and textures are uploaded from
  /// `assets` on first use. Errors: shader compile/link failures (content errors).
  Status render(const FrameInput& frame, const AssetStore& assets);

  /// Blocks until the GPU is done (for honest frame timing and read-back).
  void finish();

  /// sRGB-encoded colour of the last frame, RGBA in [0,1], rows top to bottom.
  Image read_color() const;
  /// AOVs of the last frame: P.X P.Y P.Z N.X N.Y N.Z Z visibility mask cascade reflection.R
  /// reflection.G reflection.B reflector (docs/guide/cli.md, "AOV contract").
  /// Precondition: the last frame was rendered with write_aovs.
  Image read_aovs() const;
  /// A probe's cube buffer (0 or 1; level 0) or its sphere map (row 0 at the top) as last
  /// rendered; empty when the probe has none. Tests and `kaskad render --probe-maps`.
  CubeMap read_probe_cube(ProbeHandle handle, int buffer) const;
  SphereMap read_probe_sphere(ProbeHandle handle) const;
  /// Image-based lighting as last made (tests): level `level` of the environment map's
  /// prefiltered cube (empty without one), and SH row `row` (9 rgb coefficients; row 0 the
  /// environment's, a pbr probe's row from probe_sh_row()).
  CubeMap read_environment_level(int level) const;
  std::vector<glm::vec3> read_sh_row(int row) const;
  int probe_sh_row(ProbeHandle handle) const;
  /// Depth of the shadow map of the last frame (one channel, [0,1]), rows top to bottom; with
  /// cascades the layers are stacked top to bottom (cascade 0 first), map_size rows each.
  Image read_shadow_map() const;
  /// The positions mesh `id` holds on the GPU now (a posed mesh: the deform pass's last pose);
  /// empty when it was never uploaded. For tests that compare the GPU pose with the CPU's.
  std::vector<glm::vec3> read_mesh_positions(MeshId id) const;
  /// Technique lom: the signed depths of every depth peel and the occlusion factors, stacked as
  /// read_shadow_map() (lom_layers + 1 slices per shadow-map layer; empty before the first).
  Image read_lom_depths() const;
  Image read_lom_factors() const;
  /// The soft-shadow technique's own maps of the last frame, one slice per shadow-map layer
  /// stacked as read_shadow_map(): lom the occlusion factors of each layer's first peel, vsm
  /// and evsm the first moment (evsm: the positive warp). Empty for techniques without maps of
  /// their own (pcf, pcss, backprojection) and before the first frame.
  Image read_soft_shadow_maps() const;

  /// The visibility of the shadow view the AOV shows (FrameInput::aov_shadow_view) at fixed world
  /// points
  /// with unit normals (one per point),
  /// evaluated by the forward pass's own shadow lookup (content/shaders/shadow.glsl) against the
  /// shadow maps, camera and frame features of the last render(). One (visibility,
  /// cascade) pair per point, as the forward pass would shade a surface there: (1, -1) without a
  /// shadow pass. For stability metrics: the points stay put while the camera moves.
  /// Errors: sizes differ, or the pass's program fails to build.
  /// With `blend_weights`, also the weight of the next cascade the lookup blended in at each
  /// point (0 where it did not blend; blend_weight() in shadow.glsl), for tests.
  Result<std::vector<glm::vec2>> shadow_at_points(std::span<const glm::vec3> points,
                                                  std::span<const glm::vec3> normals,
                                                  std::vector<float>* blend_weights = nullptr);

  /// Pixels of the last frame's AOV per cascade index (FrameStats::cascade_receiver_pixels).
  /// Precondition: the last frame was rendered with write_aovs.
  std::array<std::size_t, kMaxCascades> cascade_pixel_counts() const;

  /// Copies the colour target to the default framebuffer (windowed mode).
  void present(int window_width, int window_height) const;

  const FrameStats& stats() const { return stats_; }

 private:
  Renderer() = default;
  void read_timers();  // the previous frame's GPU pass times into stats_
  struct Impl;
  std::unique_ptr<Impl> impl_;
  FrameStats stats_;
};

}  // namespace kaskad::render
