// The frame, in order. This is the one place the phases are listed (STYLE.md 3).
//
//   1. Transforms  after it: every Transform has a current WorldTransform and every MeshRenderer
//                  a current WorldBounds.
//   2. Camera      after it: the active camera's view/projection for this frame's aspect.
//   3. Cascades    after it: every shadowed light (the first of any type, up to 3 more
//                  directional ones) has current splits or faces, one light matrix per layer
//                  and the casters drawn into each (ShadowData).
//   4. Probes      after it: every Reflector has a ProbeState and this frame's probe job (faces
//                  to capture, buffer to show); counters are current (ProbeData).
//   5. DrawList    after it: the renderer's FrameInput holds every drawable, light, probe and
//                  setting.
//   6. Render      after it: shadow, probe capture and forward passes are submitted (not
//                  necessarily finished).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "runtime/assets/scene.h"
#include "runtime/core/result.h"
#include "runtime/render/renderer.h"
#include "systems/camera_system.h"
#include "systems/environment_probe_system.h"
#include "systems/shadow_cascade_system.h"

namespace kaskad {

struct FrameContext {
  int width = 1280;
  int height = 720;
  std::uint64_t index = 0;  ///< frame number since the scene was loaded
  bool write_aovs = true;   ///< render the AOV targets too (see render::FrameInput)
};

/// What a frame did, for stats output and tests. CPU times in milliseconds.
struct FrameReport {
  double transforms_ms = 0, camera_ms = 0, shadows_ms = 0, probes_ms = 0, draw_list_ms = 0,
         render_ms = 0;
  CameraState camera;
  ShadowData shadow;                      ///< the first shadowed light
  std::vector<ShadowData> extra_shadows;  ///< further shadowed directional lights
  ProbeData probes;
  render::FrameStats stats;
  /// Carried from frame to frame when the caller reuses its report (the player does).
  ShadowCascadeState shadow_state;
};

/// Runs phases 1-6. Errors: no camera in the scene, shader build failures.
Status run_frame(Scene& scene, render::Renderer& renderer, const FrameContext& ctx,
                 FrameReport& report);

/// Phases 1-5 without GL: the renderer input a frame of this scene would get (probe states are
/// planned, not advanced).
render::FrameInput plan_frame(Scene& scene, const FrameContext& ctx);
/// The same, also returning the frame's ShadowData (tests).
render::FrameInput plan_frame(Scene& scene, const FrameContext& ctx, ShadowData& shadow);

/// Phases 1-5, then compiles every program the frame will use (scene load: no compiles later).
Status prewarm_frame(Scene& scene, render::Renderer& renderer, const FrameContext& ctx,
                     bool shadow_points = false);

/// Phase 5 on its own (pure: no GL), exposed for tests. Draws of entities with a Reflector whose
/// map is ready get the reflection_cube or reflection_sphere material feature. `extra` are the
/// further shadowed directional lights (update_shadows() after its first element).
render::FrameInput build_frame_input(const Scene& scene, const FrameContext& ctx,
                                     const CameraState& camera, const ShadowData& shadow,
                                     const ProbeData& probes = {},
                                     std::span<const ShadowData> extra = {});

}  // namespace kaskad
