// The renderer's passes, in the order Renderer::render() runs them (renderer.h):
//   ShadowMapPass      the depth layers of every shadow view (S0, S4)
//   LomPass            S1's layered occlusion map (technique lom)
//   MomentsPass        the blurred, mipmapped moments of vsm/evsm
//   ProbeCapturePass   reflection probe faces, mips and sphere maps (S3)
//   ForwardPass        colour and AOVs of the main view
// Each pass has prepare() (what it checks and decides before any draw: storage, which layers or
// faces are drawn) and record() (the GL commands), and says what is true after it. Draws go
// through DrawState, which switches programs and materials only when they change.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/assets/image_io.h"
#include "runtime/result/result.h"
#include "runtime/gpu/gl_handles.h"
#include "runtime/render/draw_list.h"
#include "runtime/render/frame_input.h"
#include "runtime/render/frame_uniforms.h"
#include "runtime/render/gpu_cache.h"
#include "runtime/features/shader_interface.h"
#include "runtime/render/shader_library.h"

namespace kaskad::render {

struct FrameStats;

/// Program and material state while draws are recorded: glUseProgram and the material's
/// uniforms and textures only when they change (draws are sorted so they rarely do), counted in
/// the frame's stats.
class DrawState {
 public:
  DrawState(ShaderLibrary& shaders, GpuCache& cache, FrameStats& stats);
  /// Uses the program of (pass, key); errors are shader build failures.
  Status use_program(Pass pass, VariantKey key);
  /// The program in use.
  gpu::ProgramRef program() const { return program_; }
  /// The material of draw `d` on the current program; `key`: the key that program was compiled
  /// for (its material features say which optional uniforms exist).
  void bind_material(const DrawItem& d, VariantKey key);
  /// Whether a draw with `key` reads its material in the depth pass: alpha-masked draws do, and
  /// every draw when the library's programs select material features by uniform (the test
  /// oracle's über-programs).
  bool depth_reads_material(VariantKey key) const;
  /// Programs select material features by a uniform, not by compilation (ShaderLibrary).
  bool features_by_uniform() const { return features_by_uniform_; }
  /// After GL calls outside this class changed the program or texture units (the probes'
  /// fullscreen passes): the next use_program() and bind_material() bind again.
  void forget() {
    program_ = gpu::ProgramRef();
    material_ = nullptr;
  }

 private:
  ShaderLibrary& shaders_;
  GpuCache& cache_;
  FrameStats& stats_;
  bool features_by_uniform_;
  gpu::ProgramRef program_;
  const Material* material_ = nullptr;  // bound on program_, with material_key_
  VariantKey material_key_;
};

class ShadowMapPass {
 public:
  /// Sizes the depth texture array for the frame's views (a size the driver refuses is an error
  /// before anything is drawn) and decides which layers to draw: a layer whose inputs (matrix,
  /// bias, culling, pass mode, casters with their meshes, matrices and depth programs) hash as
  /// when it was last drawn keeps its depth. `shader_reloads` counts the shader library's
  /// reloads: a shader edited on disk redraws every layer. After it: stats hold the layers,
  /// casters per layer and the layers to be drawn (shadow_layers_rendered).
  Status prepare(const FrameInput& frame, const DrawList& list, const AssetStore& assets,
                 bool layered, bool features_by_uniform, int shader_reloads, FrameStats& stats);
  /// Draws those layers. After it: every layer of every view holds the depth of its casters.
  Status record(const FrameInput& frame, const DrawList& list, GpuCache& cache, DrawState& state,
                FrameStats& stats);

  /// The depth texture array (a 64^2 single layer before the first shadowed frame, so the
  /// sampler is always complete).
  gpu::TextureRef texture();
  /// Binds the map for the lookups: to UNIT_SHADOW with its depth compare, and to
  /// UNIT_SHADOW_DEPTH through a sampler without compare (nearest, border depth 1), which
  /// reads raw depths (PCSS's blocker search), and to UNIT_SHADOW_LINEAR compared with linear
  /// filtering (the disc kernels' taps).
  void bind();
  /// The lookups' matrices of the layers that scrolled: `block`'s (packed from `frame`) get
  /// their layer's origin added to the translation, so a lookup at map coordinates uv reads
  /// texture coordinates uv + origin / size, wrapping (GL_REPEAT while any origin is not 0).
  void offset_lookups(const FrameInput& frame, FrameBlock& block) const;
  /// Depth of every layer, stacked top to bottom (layer 0 first), rows top to bottom; a
  /// scrolled layer as its matrix sees it (texel (0, 0) the map's corner, not the texture's).
  Image read() const;
  /// This frame's hash of what layer `layer` is drawn from (after prepare()).
  std::uint64_t layer_inputs(int layer) const { return inputs_[std::size_t(layer)]; }

 private:
  void ensure_storage(int size, int layers, DepthFormat format, ShadowFilter filter);
  int size_ = 0, layers_ = 0;
  DepthFormat format_ = DepthFormat::d24;
  ShadowFilter filter_ = ShadowFilter::none;
  gpu::Framebuffer fbo_;
  gpu::Texture map_;
  gpu::Sampler raw_depth_;       ///< compare off: UNIT_SHADOW_DEPTH
  gpu::Sampler linear_compare_;  ///< compare, linear: UNIT_SHADOW_LINEAR
  bool layered_ = false;
  /// Per layer: a hash of what its depth was last drawn from (0 = nothing valid) and the texels
  /// it was drawn in (x0, y0, x1, y1; ends exclusive): outside them the layer holds stale depth
  /// no lookup reads.
  std::vector<std::uint64_t> drawn_from_;
  std::vector<glm::ivec4> drawn_rect_;
  std::vector<std::uint64_t> inputs_;  // this frame's hashes
  std::vector<glm::ivec4> rects_;      // this frame's texels lookups read per layer
  std::uint32_t redraw_ = 0;           // bit l: layer l is drawn (in part or whole) this frame
  /// Scrolling (render.shadow_scroll). A stable cascade whose matrix moved by whole texels, and
  /// nothing else changed, keeps the depth it holds and draws only the texels that came into
  /// view. Its texture is a torus: map texel x lies at texel (x + origin) mod size, so nothing
  /// is copied. Per layer: the origin, and the matrix and hash of everything but the
  /// translation it was last drawn with. The drawn rectangle (drawn_rect_) is in map texels.
  std::vector<glm::ivec2> origin_;
  std::vector<glm::mat4> drawn_matrix_;
  std::vector<std::uint64_t> drawn_fixed_;
  std::vector<std::vector<std::uint64_t>> drawn_casters_;  // sorted caster hashes drawn
  /// A part of a layer drawn this frame: texels `texture` (x0, y0, x1, y1 of the texture,
  /// within one wrap) drawn through a viewport at `viewport` (map texel x lands on x + it).
  struct Piece {
    glm::ivec4 texture;
    glm::ivec2 viewport;
  };
  std::vector<std::vector<Piece>> pieces_;  // this frame's, per layer
  std::vector<std::uint64_t> fixed_;        // this frame's hashes of all but the translation
  std::vector<std::vector<std::uint64_t>> casters_;  // this frame's casters per layer, sorted
  bool wrapped_ = false;                    // the texture's wrap is GL_REPEAT
};

/// S1's layered occlusion map (ShadowTechnique::lom), pass 1, after the shadow maps: for every
/// layer of every perspective or ortho shadow view,
///  a. lom_layers depth peels from the light (one scene render each, plus an overflow peel that
///     finds what did not fit), casters and the receivers in the layer's frustum;
///  b. the occlusion factor of every stored point (content/shaders/lom_occlusion.frag).
/// Pass 2 is the lookup in shadow.glsl's lom(). A layer is recomputed when the shadow pass redraws
/// it or when what else it depends on changed (receivers that cast nothing, light size, layers).
class LomPass {
 public:
  /// Sizes the peel and occlusion arrays (an error, before drawing, when the driver refuses
  /// them) and decides which layers to recompute. No-op unless the technique is lom.
  Status prepare(const FrameInput& frame, const DrawList& list, const ShadowMapPass& shadow,
                 FrameStats& stats);
  /// Peels and computes those layers. After it: the occlusion map holds every stored point's
  /// factor; stats.lom_overflow_texels the texels where the layers ran out.
  Status record(const FrameInput& frame, const DrawList& list, GpuCache& cache, DrawState& state,
                FrameStats& stats);
  /// Binds the peels (UNIT_LOM_DEPTH) and occlusion factors (UNIT_LOM_OCCLUSION) for lookups.
  void bind();
  /// The signed depths of every peel slice, stacked as ShadowMapPass::read() (tests).
  Image read_depths() const;
  /// The occlusion factors, stacked the same way (tests).
  Image read_factors() const;
  /// The occlusion factors of each shadow-map layer's first peel (the surfaces nearest the
  /// light), stacked as read_factors() with one slice per layer: what a debug view shows.
  Image read_first_factors() const;

 private:
  void ensure_storage(int size, int slices);
  int size_ = 0, slices_ = 0, peels_ = 0;  // peels_: lom_layers + 1 per shadow-map layer
  gpu::Texture depth_;        ///< R32F array: signed peel depths
  gpu::Texture occlusion_;    ///< R8 array: occlusion factors
  gpu::Texture test_depth_;   ///< D32F 2D: the depth test of one peel
  gpu::Texture previous_;     ///< R32F 2D: the peel before the one drawn
  gpu::Framebuffer peel_fbo_, factor_fbo_;
  gpu::Sampler nearest_;      ///< nearest, border depth 1
  gpu::Buffer counter_;       ///< the overflow texel count (atomic counter)
  gpu::Query any_samples_;    ///< whether a peel found anything
  gpu::VertexArray empty_vao_;
  std::vector<std::uint64_t> drawn_from_;  // per shadow-map layer, as ShadowMapPass
  std::vector<glm::ivec4> drawn_rect_;
  std::vector<std::uint64_t> inputs_;
  std::uint32_t redraw_ = 0;
  std::vector<std::int64_t> layer_overflow_;  // per layer, as of its last computation
};

/// The moments of variance shadow maps (ShadowTechnique vsm: Donnelly, Lauritzen 2006; evsm:
/// Lauritzen, McCool 2008), after the shadow maps: for every layer of every perspective or
/// ortho shadow view that the shadow pass redrew, the moments of each texel's linear depth
/// (shadow.glsl's vsm_warp()), blurred by a separable Gaussian of vsm_blur texels (one draw
/// along x from the depth, one along y into the layer), then mipmaps for every layer. The
/// lookup is shadow.glsl's vsm(). Format: RGBA32F for evsm (four moments; e^(2 * 40) of the
/// positive warp's second moment is far past half floats' 65504), RG32F for vsm (two moments;
/// half floats' 11-bit mantissa cannot hold E[z^2] - E[z]^2 of depths that differ by less than
/// about 1e-3, so the variance of a flat receiver would be noise).
class MomentsPass {
 public:
  /// Sizes the moments array and decides which layers to recompute (the ones the shadow pass
  /// redrew, or whose blur changed). No-op unless the technique is vsm or evsm.
  Status prepare(const FrameInput& frame, const ShadowMapPass& shadow, FrameStats& stats);
  /// Computes those layers: inside each layer's read rectangle the blurred moments, outside it
  /// the moments of depth 1 (lit; the depth there is stale), then the mipmaps. After it: every
  /// layer's moments match its depth.
  Status record(const FrameInput& frame, const DrawList& list, ShadowMapPass& shadow,
                DrawState& state);
  /// Binds the moments (UNIT_VSM_MOMENTS: trilinear).
  void bind();
  /// Level 0 of every layer, stacked as ShadowMapPass::read(), channels as stored (tests).
  Image read() const;

 private:
  void ensure_storage(int size, int layers, bool four);
  int size_ = 0, layers_ = 0;
  bool four_ = false;            ///< four moments (evsm): RGBA32F, else RG32F
  gpu::Texture moments_;         ///< 2D array, mipmapped
  gpu::Texture along_x_;         ///< 2D: one layer's moments blurred along x
  gpu::Framebuffer fbo_;
  gpu::Sampler filtered_;  ///< trilinear, clamp to edge
  gpu::VertexArray empty_vao_;
  std::vector<std::uint64_t> drawn_from_;  // per shadow-map layer, as LomPass
  std::vector<glm::ivec4> drawn_rect_;
  std::vector<std::uint64_t> inputs_;
  std::vector<glm::ivec4> rects_;  // this frame's read rectangles per layer (texels)
  std::uint32_t redraw_ = 0;
};

class ProbeCapturePass {
 public:
  /// Drops the maps of reflectors that no longer exist and uploads static maps due this frame.
  void prepare(const FrameInput& frame, const AssetStore& assets, GpuCache& cache);
  /// Each scheduled face of a probe's back cube is drawn by a 90° camera at the probe centre
  /// through the forward path (shadows included, no AOVs, no exposure: cubes hold linear
  /// radiance, with cascades selected by map bounds), then mips and sphere maps. `ubo` holds
  /// `main`, the main view's block, before and after. After it: every probe's visible buffer
  /// is the map draws shade with this frame.
  Status record(const FrameInput& frame, const DrawList& list, const FrameBlock& main,
                const gpu::Buffer& ubo, GpuCache& cache, DrawState& state, FrameStats& stats);
};

/// The main view. With one sample: one draw of every visible draw into colour and, when asked
/// for, the AOVs. With `samples` > 1 (render.msaa): the colour is drawn into multisampled colour
/// and depth targets with DrawList::msaa_keys (alpha-masked draws through alpha to coverage) and
/// resolved into the single-sample colour target by a blit; the AOVs, when asked for, are drawn
/// by a second, single-sample pass with DrawList::keys whose colour output goes nowhere, so they
/// are those of a frame without MSAA, bit for bit. Each sample is tone mapped by forward.frag
/// before the resolve averages them (in linear space: GL_FRAMEBUFFER_SRGB is on for the blit),
/// so a bright background does not darken the edges in front of it.
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
  /// caller's promise: nothing they depend on changed since they were stored).
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
  /// The stored-visibility target for `views` shadow views: one 32-bit float channel each.
  static Target visibility_target(int views);

  int width() const { return width_; }
  int height() const { return height_; }
  /// Colour samples of the last prepare() (1: no multisampled targets).
  int samples() const { return samples_; }
  bool aovs_written() const { return aovs_written_; }
  /// Whether a storing frame left stored visibility at the current size.
  bool holds_visibility() const { return bool(visibility_); }
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
  gpu::Texture visibility_;  ///< visibility_target(visibility_views_), made by a storing frame
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

}  // namespace kaskad::render
