// The depth layers of every shadow view (S0, S4): the first pass of a frame with shadows.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/assets/image_io.h"
#include "runtime/gpu/gl_handles.h"
#include "runtime/render/draw_state.h"
#include "runtime/render/frame_uniforms.h"
#include "runtime/render/layer_cache.h"
#include "runtime/result/result.h"

namespace kaskad::render {

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
  /// Per layer: what its depth was last drawn from and the texels drawn (layer_cache.h).
  std::vector<DrawnLayer> drawn_;
  std::vector<std::uint64_t> inputs_;  // this frame's hashes
  std::vector<glm::ivec4> rects_;      // this frame's texels lookups read per layer
  std::uint32_t redraw_ = 0;           // bit l: layer l is drawn (in part or whole) this frame
  /// Scrolling (render.shadow_scroll). A stable cascade whose matrix moved by whole texels, and
  /// nothing else changed, keeps the depth it holds and draws only the texels that came into
  /// view. Its texture is a torus: map texel x lies at texel (x + origin) mod size, so nothing
  /// is copied. Per layer: the origin, and the matrix and hash of everything but the
  /// translation it was last drawn with. The drawn rectangle (drawn_[l].rect) is in map texels.
  std::vector<glm::ivec2> origin_;
  std::vector<glm::mat4> drawn_matrix_;
  std::vector<std::uint64_t> drawn_fixed_;
  std::vector<std::vector<std::uint64_t>> drawn_casters_;  // sorted caster hashes drawn
  /// Moved casters (a still camera): per layer, the hash of the pass and matrix without the
  /// casters it was last drawn with, and the world box of each caster drawn (drawn_casters_'s
  /// order). A layer whose casters alone changed redraws only the texels of the boxes of those
  /// that left and those that came (moved_caster_rects()).
  std::vector<std::uint64_t> drawn_pass_;
  std::vector<std::vector<Aabb>> drawn_boxes_;
  std::vector<std::vector<LayerPiece>> pieces_;  // this frame's parts drawn, per layer
  std::vector<std::uint64_t> fixed_;        // this frame's hashes of all but the translation
  std::vector<std::vector<std::uint64_t>> casters_;  // this frame's casters per layer, sorted
  std::vector<std::vector<Aabb>> boxes_;            // and their world boxes, in that order
  std::vector<std::uint64_t> pass_;                 // this frame's hashes of pass and matrix
  bool wrapped_ = false;                    // the texture's wrap is GL_REPEAT
};

}  // namespace kaskad::render
