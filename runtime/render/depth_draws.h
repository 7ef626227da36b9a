// Casters of a shadow view as instanced depth draws, shared by the shadow pass and LOM's depth
// peels: which draws go to which layers, grouped into runs and batches, and the depth state.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/render/draw_state.h"
#include "runtime/result/result.h"

namespace kaskad::render {

/// The instance record of a depth draw: shadow_depth.vert reads the model matrix and the layer
/// (the layered pass's) only, so no normal matrix is computed (one per caster and layer).
InstanceRecord depth_instance_of(const glm::mat4& model, std::uint32_t layer);

/// The layers of view `v` that draw `d` (bit c: layer first_layer + c).
std::uint32_t caster_mask(const ShadowView& v, const DrawItem& d);

/// Casters of one shadow view drawn by one instanced draw: draw list entry `draw` gives the
/// mesh, program and material; records first .. first + count - 1 the instances. Consecutive
/// runs with the same program, material (where it reads one), winding and face culling
/// (caster_cull(): double-sided materials cast from both faces) are one batch (one multi-draw).
struct CasterRun {
  std::uint32_t draw;
  std::size_t first, count;
  bool mirrored;      ///< the casters' transforms mirror (negative determinant): reversed winding
  bool starts_batch;  ///< its program, material, winding or culling differs from the run before's
};

/// The depth program's key of draw i in view `view`; `peel`: a LomPass depth peel (one layer per
/// pass, never the layered program).
VariantKey depth_program_key(const DrawList& list, std::size_t view, std::uint32_t i, bool peel);

/// Draws of view `view` as instanced runs that share a draw (same mesh and depth program, and
/// the same material where the depth program reads it), in depth order, marked where a batch
/// starts. `mask_of(i)`: the layers of the view (bit c) draw i goes to; `record_of(i, c)`: its
/// instance record in layer c. The records go to `records`, one per draw and layer.
template <typename MaskOf, typename RecordOf>
std::vector<CasterRun> depth_runs(const FrameInput& frame, const DrawList& list, GpuCache& cache,
                                  const DrawState& state, std::size_t view, bool peel,
                                  MaskOf mask_of, RecordOf record_of,
                                  std::vector<InstanceRecord>& records) {
  const ShadowView& v = frame.shadow_views[view];
  auto same_batch = [&](std::uint32_t i, std::uint32_t j) {
    const DrawItem& a = frame.draws[i];
    const DrawItem& b = frame.draws[j];
    if (mirrors(a.model) != mirrors(b.model) ||
        caster_cull(v.cull, a.material.double_sided) !=
            caster_cull(v.cull, b.material.double_sided) ||
        depth_program_key(list, view, i, peel).filtered_for(Pass::depth) !=
            depth_program_key(list, view, j, peel).filtered_for(Pass::depth))
      return false;
    return !state.depth_reads_material(list.keys[i]) ||
           (a.material == b.material && list.keys[i].material() == list.keys[j].material());
  };
  records.clear();
  std::vector<CasterRun> runs;
  std::uint32_t previous = 0;
  for (std::uint32_t i : list.depth_order) {
    const std::uint32_t mask = mask_of(i);
    if (mask == 0 || cache.mesh(frame.draws[i].mesh).index_count == 0) continue;
    const bool starts_batch = runs.empty() || !same_batch(previous, i);
    if (starts_batch || frame.draws[previous].mesh != frame.draws[i].mesh)
      runs.push_back({i, records.size(), 0, mirrors(frame.draws[i].model), starts_batch});
    previous = i;
    for (int c = 0; c < v.layer_count; ++c)
      if (mask & (1u << c)) records.push_back(record_of(i, c));
    runs.back().count = records.size() - runs.back().first;
  }
  return runs;
}

/// The casters of view `view` in `layers` (bit c: layer c of the view; a caster goes to the
/// layers of its mask in `layers`), their instance records carrying the layer when `per_layer`
/// (the layered pass). With `rect` (one layer drawn over part of it, ortho: x0, y0, x1, y1 in NDC
/// through `light_vp`), casters whose box lies outside it are left out (counted in
/// `rect_culled`): they would write only texels no lookup reads, and on a software rasteriser
/// each costs its vertices and set-up.
std::vector<CasterRun> caster_runs(const FrameInput& frame, const DrawList& list, GpuCache& cache,
                                   const DrawState& state, std::size_t view, std::uint32_t layers,
                                   bool per_layer, std::vector<InstanceRecord>& records,
                                   const glm::mat4* light_vp = nullptr,
                                   const glm::vec4* rect = nullptr, int* rect_culled = nullptr);

/// Culling (the view's; draw_runs() sets each batch's caster_cull()), polygon offset and
/// clipping of view `v`'s depth pass.
void set_depth_state(const ShadowView& v);

/// Records instanced depth draws of `runs` of view `view` (their records uploaded first);
/// light_vp: the one layer's matrix, null for the layered pass.
Status draw_runs(const FrameInput& frame, const DrawList& list, GpuCache& cache, DrawState& state,
                 FrameStats& stats, std::size_t view, std::span<const CasterRun> runs,
                 std::span<const InstanceRecord> records, const glm::mat4* light_vp,
                 bool peel = false);

}  // namespace kaskad::render
