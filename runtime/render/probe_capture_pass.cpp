#include "runtime/render/probe_capture_pass.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <vector>

#include "runtime/render/forward_pass.h"

namespace kaskad::render {

void ProbeCapturePass::prepare(const FrameInput& frame, const AssetStore& assets, GpuCache& cache) {
  std::vector<ProbeHandle> live;
  for (const ProbeJob& job : frame.probes) live.push_back(job.handle);
  std::sort(live.begin(), live.end());
  cache.probes().retain(live);  // maps of reflectors that no longer exist are dropped
  for (const ProbeJob& job : frame.probes)
    if (job.env_map != kNoProbe && job.env_map < assets.env_maps.size())
      cache.probes().upload(job.handle, job.visible, assets.env_maps[job.env_map]);
}

Status ProbeCapturePass::record(const FrameInput& frame, const DrawList& list,
                                const FrameBlock& main, const gpu::Buffer& ubo, GpuCache& cache,
                                DrawState& state, FrameStats& stats) {
  // The environment map, prefiltered once per map; its SH, the split-sum table and its cube are
  // bound for every forward draw (captures included).
  const int prefiltered_before = cache.probes().prefilter_faces;
  cache.probes().ibl().set_environment(frame.environment, frame.environment_key);
  cache.probes().ibl().bind();
  if (frame.probes.empty()) {
    state.forget();  // prefiltering uses its own programs and unit 0
    return {};
  }
  // The pbr model's prefiltering, time-sliced like the captures: faces_per_frame faces a frame
  // of the cube that was complete before this frame's captures (what their round 1 reads; they
  // may swap buffers), so a capture completing every 6 / faces_per_frame frames never starves it.
  for (const ProbeJob& job : frame.probes)
    if (job.prefilter &&
        cache.probes().prefilter(job.handle, probe_read_buffer(job, 1), job.faces_per_frame))
      ++stats.probe_prefilters;
  state.forget();
  glDisable(GL_FRAMEBUFFER_SRGB);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  Status status;
  // Every cube captured this frame exists before the first face is drawn, so that a probe read
  // before its first capture is a black cube, not an empty texture unit.
  int rounds = 1;
  for (const ProbeJob& job : frame.probes)
    if (job.env_map == kNoProbe && job.faces != 0) {
      cache.probes().cube(job.handle, job.target, job.resolution);
      rounds = std::max(rounds, job.rounds);
    }
  // Round k draws every probe due in it into capture_buffer(job, k), its reflective draws
  // reading the other probes' maps of round k - 1 (probe_read_buffer()).
  for (int round = 1; round <= rounds && status; ++round) {
    for (const ProbeJob& job : frame.probes) {
      if (job.env_map != kNoProbe || job.faces == 0 || round > job.rounds) continue;
      const int buffer = capture_buffer(job, round);
      for (int f = 0; f < 6 && status; ++f) {
        if (!(job.faces & (1u << f))) continue;
        const FrameBlock face = probe_face_block(main, job, f);
        glNamedBufferSubData(ubo.id(), 0, sizeof face, &face);
        cache.probes().begin_face(job.handle, buffer, f, frame.clear_color);
        const int before = stats.draw_calls, mesh_draws_before = stats.mesh_draws,
                  instances_before = stats.instances;
        const std::size_t triangles_before = stats.triangles;
        status = draw_forward(frame, list.capture_order, list.capture_keys, &job, round,
                              face.view_proj, cache, state, stats);
        // Then the blended draws, back to front for this face's camera.
        if (status)
          status = draw_transparent(frame, list, list.capture_keys, &job, round, face.view_proj,
                                    clip_depth_plane(face.view_proj), 1, cache, state, stats);
        // Draws into faces are counted apart from the main view's.
        stats.probe_draw_calls += stats.draw_calls - before;
        stats.probe_instances += stats.instances - instances_before;
        stats.draw_calls = before;
        stats.mesh_draws = mesh_draws_before;
        stats.instances = instances_before;
        stats.triangles = triangles_before;
        ++stats.probe_faces;
      }
      if (!status) break;
      // Complete (a round's cube, or the target that is now the visible buffer): rebuild its
      // mip chain before anything samples it.
      if (job.target == job.visible) cache.probes().finish_cube(job.handle, buffer);
    }
    // A sphere-mapped probe is read through its sphere map: the next round's reads need this
    // round's.
    if (round < rounds && status) {
      for (const ProbeJob& job : frame.probes)
        if (job.sphere && job.rounds > round)
          cache.probes().update_sphere(job.handle, capture_buffer(job, round),
                                       glm::mat3(frame.camera.view));
      // A pbr probe's round is prefiltered whole before the next round reads it.
      for (const ProbeJob& job : frame.probes)
        if (job.prefilter && job.rounds > round)
          cache.probes().prefilter(job.handle, capture_buffer(job, round), 6);
      state.forget();  // update_sphere() and prefiltering used their own programs and unit 0
    }
  }
  glNamedBufferSubData(ubo.id(), 0, sizeof main, &main);  // the main view's block again
  if (!status) return status;
  // A probe's first map (or one uploaded from a file; after several rounds, the last round's) is
  // prefiltered whole at once, so a pbr reflector never waits without one.
  for (const ProbeJob& job : frame.probes)
    if (job.prefilter && (!cache.probes().has_specular(job.handle) || job.rounds > 1) &&
        cache.probes().prefilter(job.handle, job.visible, 6))
      ++stats.probe_prefilters;
  cache.probes().ibl().bind();
  for (const ProbeJob& job : frame.probes)
    if (job.sphere && cache.probes().existing_cube(job.handle, job.visible))
      cache.probes().update_sphere(job.handle, job.visible, glm::mat3(frame.camera.view));
  state.forget();  // the fullscreen passes above used their own programs and unit 0
  stats.probe_prefilter_faces = cache.probes().prefilter_faces - prefiltered_before;
  return {};
}

}  // namespace kaskad::render
