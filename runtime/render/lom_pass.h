// S1's layered occlusion map (technique lom), after the shadow maps.
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

/// S1's layered occlusion map (ShadowTechnique::lom), pass 1, after the shadow maps: for every
/// layer of every perspective or ortho shadow view,
///  a. lom_layers depth peels from the light (one scene render each, plus an overflow peel that
///     finds what did not fit), casters and the receivers in the layer's frustum;
///  b. the occlusion factor of every stored point (content/shaders/lom_occlusion.frag).
/// Pass 2 is the lookup in shadow_lom.glsl's lom(). A layer is recomputed when the shadow pass
/// redraws it or when what else it depends on changed (receivers that cast nothing, light size,
/// layers).
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
  std::vector<DrawnLayer> drawn_;  // per shadow-map layer, as ShadowMapPass
  std::vector<std::uint64_t> inputs_;
  std::uint32_t redraw_ = 0;
  std::vector<std::int64_t> layer_overflow_;  // per layer, as of its last computation
};

}  // namespace kaskad::render
