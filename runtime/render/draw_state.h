// Program and material state while the passes record draws, and the batched draw call they
// share (shadow, LOM and forward passes).
#pragma once

#include <span>

#include "runtime/gpu/gl_handles.h"
#include "runtime/render/draw_list.h"
#include "runtime/render/frame_input.h"
#include "runtime/render/frame_stats.h"
#include "runtime/render/gpu_cache.h"
#include "runtime/render/shader_library.h"

namespace kaskad::render {

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
  /// Whether a draw with `key` reads its material in the depth pass: alpha-masked and blended
  /// draws do, and
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

/// Draws `batch` (draws of one program, material and winding) as one multi-draw, or with
/// render.multi_draw off one call per mesh, counting both.
void draw_batch(const FrameInput& frame, GpuCache& cache, std::span<const MeshDraw> batch,
                int& calls, int& mesh_draws);

}  // namespace kaskad::render
