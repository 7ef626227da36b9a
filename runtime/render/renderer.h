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
#include "runtime/features/variant_key.h"

namespace kaskad::render {

/// Draw calls are GL draw calls: draws that share program, material and winding are one call, a
/// multi-draw of one instanced draw per mesh among them (mesh draws; a call of one mesh is a plain
/// instanced draw). Instances are the objects those calls draw.
struct FrameStats {
  /// Forward pass of the main view; with render.msaa > 1 and AOVs, its multisampled colour
  /// and single-sample AOV draws together (each object twice).
  int draw_calls = 0;
  int mesh_draws = 0;                 ///< the instanced draws within them (one per mesh)
  int instances = 0;                  ///< objects drawn by them
  int frustum_culled = 0;             ///< draws outside the main view's frustum, not drawn
  std::size_t triangles = 0;          ///< submitted in the forward pass (both, as draw_calls)
  /// Shadow pass draw calls recorded this frame (0 when every layer kept its depth).
  int shadow_draw_calls = 0;
  int shadow_mesh_draws = 0;  ///< the instanced draws within them (one per mesh)
  /// Caster instances in the shadow map's layers (one per caster and layer) and their
  /// triangles, whether drawn this frame or kept from an earlier one (shadow_layers_rendered
  /// says which layers were drawn).
  int shadow_instances = 0;
  std::size_t shadow_triangles = 0;
  int shadow_layers = 0;  ///< layers of the shadow map this frame (all shadow views)
  /// Bit l: texture-array layer l was cleared and re-rendered this frame. The others kept their
  /// depth: same matrix, casters, caster matrices, bias and pass mode as when last drawn.
  std::uint32_t shadow_layers_rendered = 0;
  /// Caster instances left out of layers drawn this frame over part of their texels
  /// (shadow.scissor_to_receivers) because their boxes miss those texels.
  int shadow_rect_culled = 0;
  /// Bit l: layer l scrolled this frame (render.shadow_scroll): its matrix moved by whole texels
  /// (or not at all, its read rectangle having grown) and it kept the depth it held, drawing
  /// only the texels it did not hold (if any, its bit in shadow_layers_rendered is set too).
  std::uint32_t shadow_layers_scrolled = 0;
  /// Texels cleared and drawn this frame over all layers (each layer's size^2 when redrawn whole).
  std::int64_t shadow_texels_drawn = 0;
  /// Per layer of the shadow map array (all shadow views; view k's layers start at its
  /// first_layer): the casters it holds, their triangles, and metres per texel (spot and point
  /// layers: at 1 m from the light).
  std::array<int, kMaxShadowLayers> layer_casters{};
  std::array<std::size_t, kMaxShadowLayers> layer_triangles{};
  std::array<float, kMaxShadowLayers> layer_texel_size{};
  /// The texels of each layer that lookups read this frame, (x0, y0, x1, y1) with exclusive
  /// ends: its read rectangle (ShadowView::read_rect), the whole layer when a pass that reads
  /// anywhere runs. The depth pass clears and draws only these when it redraws the layer;
  /// outside them a layer may hold stale depth. Empty (x0 >= x1) when nothing reads it.
  std::array<glm::ivec4, kMaxShadowLayers> layer_rect{};
  /// Receiver pixels per cascade: pixels of the frame's AOV whose `cascade` channel is i (visible
  /// shadow-receiving surfaces shaded from cascade i; the first one where blending). Counted by
  /// cascade_pixel_counts(), which render_frames() calls after its last frame when AOVs are
  /// written; 0 otherwise.
  std::array<std::size_t, kMaxCascades> cascade_receiver_pixels{};
  /// ShadowTechnique::lom: shadow-map layers whose peels and occlusion factors were recomputed
  /// this frame (bit l, as shadow_layers_rendered), and texels, over all layers, where the
  /// depth peels found more light-facing surfaces than lom_layers (a point under all of them
  /// reads as umbra; shadow.glsl's lom()).
  std::uint32_t lom_layers_computed = 0;
  std::int64_t lom_overflow_texels = 0;
  /// ShadowTechnique::vsm/evsm: shadow-map layers whose moments were recomputed this frame (bit
  /// l, as shadow_layers_rendered; MomentsPass).
  std::uint32_t vsm_layers_computed = 0;
  /// render.visibility_cache: the forward pass read each pixel's shadow visibility back from
  /// the frame before instead of looking the shadow maps up (nothing it depends on changed).
  bool visibility_reused = false;
  /// render.visibility_cache: the forward pass stored each pixel's visibility for the next frame
  /// (a frame that sees what the frame before saw and does not read back).
  bool visibility_stored = false;
  /// GPU times are the previous frame's (queries are read a frame late); 0 until frame 3.
  /// GPU time (GL_TIMESTAMP pairs, GpuTimers) of the shadow pass with LOM and moments, the
  /// forward pass and the probe captures (previous frame).
  double shadow_gpu_ms = 0.0;
  double forward_gpu_ms = 0.0;
  double probe_gpu_ms = 0.0;
  /// Parts of the above (previous frame): LomPass and MomentsPass (in shadow_gpu_ms), and pbr
  /// prefiltering with SH projection of probes and the environment map (in probe_gpu_ms).
  double lom_gpu_ms = 0.0, moments_gpu_ms = 0.0, prefilter_gpu_ms = 0.0;
  int probe_faces_timed = 0;          ///< faces that probe_gpu_ms covers (previous frame's)
  int probe_faces = 0;                ///< reflection probe cube faces rendered this frame
  int probe_prefilters = 0;           ///< probe cubes whose pbr prefiltering completed this frame
  int probe_prefilter_faces = 0;      ///< cube faces prefiltered this frame (time-sliced)
  int probe_draw_calls = 0;           ///< draw calls into those faces (not in draw_calls)
  int probe_instances = 0;            ///< objects they draw
  int probe_culled = 0;               ///< draws outside a captured face's frustum, not drawn
  /// Colour samples per pixel of the main view (render.msaa as the driver offers it; 1: none).
  int msaa_samples = 1;
  int program_switches = 0;           ///< glUseProgram calls in the frame (draws are sorted)
  int material_switches = 0;          ///< material uniform/texture updates in the frame
  ShaderStats shaders;                ///< compiles, cache hits, compile ms (since creation)
};


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
  /// reflection.G reflection.B reflector (see README).
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
