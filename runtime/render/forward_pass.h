// The main view's colour and AOVs, and the forward drawing it shares with probe captures.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/gpu/gl_handles.h"
#include "runtime/render/draw_state.h"
#include "runtime/result/result.h"

namespace kaskad::render {

/// The main view. With one sample: one draw of every visible draw into colour and, when asked
/// for, the AOVs. With `samples` > 1 (render.msaa): the colour is drawn into multisampled colour
/// and depth targets with DrawList::msaa_keys (alpha-masked draws through alpha to coverage) and
/// resolved into the single-sample colour target by a blit; the AOVs, when asked for, are drawn
/// by a second, single-sample pass with DrawList::keys whose colour output goes nowhere, so they
/// are those of a frame without MSAA, bit for bit. Each sample is tone mapped by forward.frag
/// before the resolve averages them (in linear space: GL_FRAMEBUFFER_SRGB is on for the blit),
/// so a bright background does not darken the edges in front of it. Blended draws follow the
/// opaque ones in each colour pass (draw_transparent()); the AOVs show the opaque surface behind
/// them (docs/guide/materials.md, "Transparency").
class ForwardPass {
 public:
  /// The colour, AOV and depth targets at the frame's size, and with `samples` > 1 the
  /// multisampled colour and depth targets (made when the size or sample count changes).
  void prepare(const FrameInput& frame, int samples);
  /// Draws the main view's visible draws into colour (and the AOVs when asked for). After it:
  /// colour holds the frame (resolved), the AOVs its surfaces when write_aovs. `keys` are the
  /// single-sample pass's (the list's, or with kReuseLoad the loading ones). `reuse` is the
  /// frame's VariantKey::kShadowReuse: with kReuseStore the pass also stores each pixel's
  /// shadow visibility per view; with kReuseLoad the programs read the stored values back (the
  /// caller's promise: nothing they depend on changed since they were stored); with
  /// kReuseReproject they read the values stored last under another camera (the frame block's
  /// previous_* members; the caller's promise: only the camera changed) and store their own.
  Status record(const FrameInput& frame, const DrawList& list,
                const std::vector<VariantKey>& keys, std::uint32_t reuse, GpuCache& cache,
                DrawState& state, FrameStats& stats);

  struct Target {
    const char* name;
    GLenum internal_format, format, type;
    int bytes_per_pixel;
  };
  /// The targets, in attachment order (colour 0..4, then depth): what prepare() makes and what
  /// Renderer::check_target_size() asks the driver about.
  static std::span<const Target> targets();
  /// The stored-visibility target for `views` shadow views: one 32-bit float channel each, and
  /// one for the distance from the camera when there are fewer than four.
  static Target visibility_target(int views);

  int width() const { return width_; }
  int height() const { return height_; }
  /// Colour samples of the last prepare() (1: no multisampled targets).
  int samples() const { return samples_; }
  bool aovs_written() const { return aovs_written_; }
  /// Whether a storing frame left stored visibility at the current size.
  bool holds_visibility() const { return bool(visibility_[current_]); }
  gpu::FramebufferRef framebuffer() const { return fbo_; }
  /// Attachment i of targets().
  gpu::TextureRef texture(int i) const { return textures_[std::size_t(i)]; }

 private:
  int width_ = 0, height_ = 0, samples_ = 1;
  bool aovs_written_ = false;
  gpu::Framebuffer fbo_;
  std::array<gpu::Texture, 6> textures_;
  gpu::Framebuffer msaa_fbo_;                 ///< samples_ > 1: colour and depth, multisampled
  std::array<gpu::Texture, 2> msaa_textures_;  ///< targets() 0 and 5 with samples_ samples
  /// visibility_target(visibility_views_), made by storing frames: [current_] holds the last
  /// stored, and the next storing frame writes the other (a reprojecting one reads [current_]).
  std::array<gpu::Texture, 2> visibility_;
  int current_ = 0;
  int visibility_views_ = 0;
};

/// The forward path of the main view and of probe faces: draws `order` with `keys` as seen by
/// `view_proj` (culled per draw), binding reflection maps; `capture` names the probe face being
/// drawn in capture round `round` (its reflector is left out, and reflections read
/// probe_read_buffer(job, round)); the main view passes none and round 0.
Status draw_forward(const FrameInput& frame, std::span<const std::uint32_t> order,
                    const std::vector<VariantKey>& keys, const ProbeJob* capture, int round,
                    const glm::mat4& view_proj, GpuCache& cache, DrawState& state,
                    FrameStats& stats);

/// The transparent phase of a view, after its opaque draws: DrawList::blend_draws sorted by
/// back_to_front() for `depth_plane`, drawn by draw_forward() with the depth test on and depth
/// writes off, blended premultiplied over (GL_ONE, GL_ONE_MINUS_SRC_ALPHA) into draw buffer 0;
/// draw buffers 1 .. draw_buffers - 1 (the AOVs, the stored visibility) are masked off, so
/// they keep the opaque surface behind. A double-sided blended draw draws its back faces, then
/// its front faces. Leaves blending off and depth writes on.
Status draw_transparent(const FrameInput& frame, const DrawList& list,
                        const std::vector<VariantKey>& keys, const ProbeJob* capture, int round,
                        const glm::mat4& view_proj, const glm::vec4& depth_plane,
                        int draw_buffers, GpuCache& cache, DrawState& state, FrameStats& stats);

}  // namespace kaskad::render
