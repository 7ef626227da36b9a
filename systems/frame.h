// The frame, in order. This is the one place the phases are listed (STYLE.md 3).
//
//   0. Animation   after it: every playing clip's nodes hold its pose (Transform, MorphWeights)
//                  and its clock has moved on by the frame's dt.
//   1. Transforms  after it: every Transform has a current WorldTransform and every MeshRenderer
//                  a current WorldBounds; then deformed meshes are posed (skin matrices, morph
//                  weights) and their WorldBounds hold the pose.
//   2. Camera      after it: the active camera's view/projection for this frame's aspect.
//   3. Cascades    after it: every shadowed light has its shadow view (ShadowData): current
//                  splits or faces, one light matrix per layer, its layers of the shared
//                  shadow map and the casters drawn into each.
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
#include "runtime/result/result.h"
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
  /// Seconds the animation clock moves on after this frame (a frame shows clips at their time
  /// now). 0: still (a single render, or a re-render of the same moment).
  double dt = 0.0;
};

/// What the systems carry from one frame of a scene to the next. Whoever runs the frames of a
/// scene keeps one (the player, a playback run, a stability run) and passes it to every frame.
/// A state used with another scene starts afresh (history of one scene says nothing of another).
struct SystemState {
  std::uint64_t scene = 0;  ///< AssetStore::uid of the scene it belongs to; 0: none yet
  ShadowCascadeState shadows;
};

/// What a frame did, for stats output and tests. CPU times in milliseconds.
struct FrameReport {
  double animation_ms = 0, transforms_ms = 0, camera_ms = 0, shadows_ms = 0, probes_ms = 0, draw_list_ms = 0,
         render_ms = 0;
  CameraState camera;
  std::vector<ShadowData> shadows;  ///< one per shadow view (update_shadows())
  ProbeData probes;
  render::FrameStats stats;

  /// Shadow view k, or an empty one (light null) when there are not that many.
  const ShadowData& shadow(std::size_t k = 0) const;
};

/// Runs phases 1-6 and advances `state`. Errors: no camera in the scene, shader build failures,
/// a frame the renderer refuses.
Status run_frame(Scene& scene, render::Renderer& renderer, const FrameContext& ctx,
                 SystemState& state, FrameReport& report);

/// Phases 1-5 without GL, as run_frame() would run them next with `state` (which is not
/// advanced; probe states are planned, not advanced): the renderer input and, in `report`, what
/// the systems published.
render::FrameInput plan_frame(Scene& scene, const FrameContext& ctx,
                              const SystemState& state = {}, FrameReport* report = nullptr);

/// Phases 1-5 as plan_frame(), then compiles every program the frame will use (scene load: no
/// compiles later), and with `shadow_points` the points pass's.
Status prewarm_frame(Scene& scene, render::Renderer& renderer, const FrameContext& ctx,
                     const SystemState& state = {}, bool shadow_points = false);

/// The index of the shadow view the AOV shows: render.aov_shadow_light counts the shadowed
/// lights in order; past the last one it is the first. 0 when there are none.
int aov_shadow_index(const Scene& scene, std::size_t views);

/// Phase 5 on its own (pure: no GL), exposed for tests. Draws of entities with a Reflector whose
/// map is ready get the reflection_cube or reflection_sphere material feature. `shadows` are
/// update_shadows()'s views.
render::FrameInput build_frame_input(const Scene& scene, const FrameContext& ctx,
                                     const CameraState& camera,
                                     std::span<const ShadowData> shadows,
                                     const ProbeData& probes = {});

}  // namespace kaskad
