// The moments of variance shadow maps (techniques vsm and evsm), after the shadow maps.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/assets/image_io.h"
#include "runtime/gpu/gl_handles.h"
#include "runtime/render/draw_state.h"
#include "runtime/render/layer_cache.h"
#include "runtime/render/shadow_map_pass.h"
#include "runtime/result/result.h"

namespace kaskad::render {

/// The moments of variance shadow maps (ShadowTechnique vsm: Donnelly, Lauritzen 2006; evsm:
/// Lauritzen, McCool 2008), after the shadow maps: for every layer of every perspective or
/// ortho shadow view that the shadow pass redrew, the moments of each texel's linear depth
/// (shadow_moments.glsl's vsm_warp()), blurred by a separable Gaussian of vsm_blur texels (one draw
/// along x from the depth, one along y into the layer), then mipmaps for every layer. The
/// lookup is shadow_moments.glsl's vsm(). Format: RGBA32F for evsm (four moments; e^(2 * 40) of the
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
  std::vector<DrawnLayer> drawn_;  // per shadow-map layer, as ShadowMapPass
  std::vector<std::uint64_t> inputs_;
  std::vector<glm::ivec4> rects_;  // this frame's read rectangles per layer (texels)
  std::uint32_t redraw_ = 0;
};

}  // namespace kaskad::render
