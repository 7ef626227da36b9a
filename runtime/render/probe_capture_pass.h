// Reflection probe faces, their mips and sphere maps (S3), drawn through the forward path.
#pragma once

#include "runtime/gpu/gl_handles.h"
#include "runtime/render/draw_state.h"
#include "runtime/render/frame_uniforms.h"
#include "runtime/result/result.h"

namespace kaskad::render {

class ProbeCapturePass {
 public:
  /// Drops the maps of reflectors that no longer exist and uploads static maps due this frame.
  void prepare(const FrameInput& frame, const AssetStore& assets, GpuCache& cache);
  /// Each scheduled face of a probe's back cube is drawn by a 90° camera at the probe centre
  /// through the forward path (shadows included, no AOVs, no exposure: cubes hold linear
  /// radiance, with cascades selected by map bounds), its blended draws after its opaque ones,
  /// back to front for the face's camera (draw_transparent()), then mips and sphere maps. `ubo` holds
  /// `main`, the main view's block, before and after. After it: every probe's visible buffer
  /// is the map draws shade with this frame.
  Status record(const FrameInput& frame, const DrawList& list, const FrameBlock& main,
                const gpu::Buffer& ubo, GpuCache& cache, DrawState& state, FrameStats& stats);
};

}  // namespace kaskad::render
