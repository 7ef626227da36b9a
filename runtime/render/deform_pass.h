// The deform pass: skinned and morphed meshes posed on the GPU before any other pass draws
// (FrameInput::deforms). One compute dispatch a deformed mesh, its program chosen by the variant
// system (Pass::deform, the skin and morph features of draw_list.h's deform_variant()), writing
// the mesh's posed copy in the GPU cache's shared vertex buffer; every other pass then draws
// the copy like any stored mesh. Posing once a frame, not in each pass's vertex shader, keeps a
// character's skinning out of every cascade, probe face and depth peel it is drawn into.
#pragma once

#include <cstdint>
#include <unordered_map>

#include "runtime/gpu/gl_handles.h"
#include "runtime/render/frame_input.h"
#include "runtime/render/frame_stats.h"
#include "runtime/render/gpu_cache.h"
#include "runtime/render/shader_library.h"
#include "runtime/result/result.h"

namespace kaskad::render {

class DeformPass {
 public:
  /// After it: every posed mesh of `frame.deforms` holds this frame's pose. A posed mesh whose
  /// pose hash (DrawItem::pose) is the one it was last posed with is not dispatched again.
  Status record(const FrameInput& frame, std::uint64_t assets_uid, GpuCache& cache,
                ShaderLibrary& shaders, FrameStats& stats);

 private:
  gpu::Buffer matrices_, weights_;
  std::size_t matrices_capacity_ = 0, weights_capacity_ = 0;  // bytes
  std::uint64_t assets_uid_ = 0;
  std::unordered_map<std::uint32_t, std::uint64_t> posed_with_;  // posed mesh -> pose hash
};

}  // namespace kaskad::render
