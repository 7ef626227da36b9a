#include "runtime/render/depth_draws.h"

#include <epoxy/gl.h>

#include "runtime/features/shader_interface.h"
#include "runtime/render/layer_cache.h"

namespace kaskad::render {

InstanceRecord depth_instance_of(const glm::mat4& model, std::uint32_t layer) {
  InstanceRecord r;
  r.model = model;
  r.layer = glm::uvec4(layer, 0, 0, 0);
  return r;
}

std::uint32_t caster_mask(const ShadowView& v, const DrawItem& d) {
  if (!d.cast_shadows) return 0;
  return (d.shadow_layers >> v.first_layer) & (~0u >> (32 - v.layer_count));
}

VariantKey depth_program_key(const DrawList& list, std::size_t view, std::uint32_t i, bool peel) {
  VariantKey k = list.depth_key(view, i);
  if (peel) k.set(VariantKey::kShadowPeel, 1).set(VariantKey::kShadowLayered, 0);
  return k;
}

std::vector<CasterRun> caster_runs(const FrameInput& frame, const DrawList& list, GpuCache& cache,
                                   const DrawState& state, std::size_t view, std::uint32_t layers,
                                   bool per_layer, std::vector<InstanceRecord>& records,
                                   const glm::mat4* light_vp, const glm::vec4* rect,
                                   int* rect_culled) {
  const ShadowView& v = frame.shadow_views[view];
  auto outside_rect = [&](const DrawItem& d) {
    if (!rect || d.bounds.empty()) return false;
    const bool out = box_misses(d.bounds, *light_vp, *rect);
    if (out && rect_culled) ++*rect_culled;
    return out;
  };
  return depth_runs(
      frame, list, cache, state, view, false,
      [&](std::uint32_t i) {
        const std::uint32_t mask = layers & caster_mask(v, frame.draws[i]);
        return mask != 0 && outside_rect(frame.draws[i]) ? 0u : mask;
      },
      [&](std::uint32_t i, int c) {
        return depth_instance_of(frame.draws[i].model, per_layer ? std::uint32_t(c) : 0u);
      },
      records);
}

namespace {

// GL's face culling for `cull`: the faces caster_face_blocks() says do not block are not drawn.
// GL's front faces are the counter-clockwise ones in the map (glFrontFace per batch turns that
// round for mirroring transforms), which are the faces that face the light: every view looks
// from the light through a right-handed look-at and a projection that keeps x and y the right
// way round (cascades, spot maps, cube faces and the paraboloid hemispheres, whose second view
// is a rotation: local_light_math.h).
void set_cull(CullMode cull) {
  if (cull == CullMode::none) {
    glDisable(GL_CULL_FACE);
  } else {
    glEnable(GL_CULL_FACE);
    glCullFace(cull == CullMode::front ? GL_FRONT : GL_BACK);
  }
}

}  // namespace

void set_depth_state(const ShadowView& v) {
  set_cull(v.cull);
  glPolygonOffset(v.slope_bias, v.constant_bias);
  // Paraboloid hemispheres end at a clip distance (shadow_depth.vert).
  if (v.projection == ShadowProjection::dual_paraboloid) {
    glEnable(GL_CLIP_DISTANCE0);
  } else {
    glDisable(GL_CLIP_DISTANCE0);
  }
}

Status draw_runs(const FrameInput& frame, const DrawList& list, GpuCache& cache, DrawState& state,
                 FrameStats& stats, std::size_t view, std::span<const CasterRun> runs,
                 std::span<const InstanceRecord> records, const glm::mat4* light_vp,
                 bool peel) {
  const std::uint32_t base = cache.upload(records);
  const ShadowView& v = frame.shadow_views[view];
  std::vector<MeshDraw> batch;
  for (std::size_t first = 0; first < runs.size();) {
    const CasterRun& run = runs[first];
    const DrawItem& d = frame.draws[run.draw];
    std::size_t end = first + 1;
    while (end < runs.size() && !runs[end].starts_batch) ++end;
    batch.clear();
    for (std::size_t r = first; r < end; ++r)
      batch.push_back({cache.mesh(frame.draws[runs[r].draw].mesh),
                       base + std::uint32_t(runs[r].first), std::uint32_t(runs[r].count)});
    KASKAD_TRY(state.use_program(Pass::depth, depth_program_key(list, view, run.draw, peel)));
    const GLuint prog = state.program().id();
    // The material as the depth program sees it: uniforms of features it lacks (occlusion, ...)
    // must not be set, their locations may belong to other uniforms there.
    const VariantKey depth_material = list.keys[run.draw].filtered_for(Pass::depth);
    if (state.depth_reads_material(depth_material)) state.bind_material(d, depth_material);
    if (light_vp) {  // one layer
      glProgramUniformMatrix4fv(prog, kLocLightViewProj, 1, GL_FALSE, &(*light_vp)[0][0]);
    } else {  // layered: every layer of the view, the instance says which
      glProgramUniform1i(prog, kLocLayerBase, v.first_layer);
      glProgramUniformMatrix4fv(prog, kLocLayerViewProj, v.layer_count, GL_FALSE,
                                &v.view_proj[0][0][0]);
    }
    glFrontFace(run.mirrored ? GL_CW : GL_CCW);
    set_cull(caster_cull(v.cull, d.material.double_sided));  // a batch shares it (depth_runs())
    draw_batch(frame, cache, batch, stats.shadow_draw_calls, stats.shadow_mesh_draws);
    first = end;
  }
  glFrontFace(GL_CCW);
  set_cull(v.cull);
  return {};
}

}  // namespace kaskad::render
