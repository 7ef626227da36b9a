#include "runtime/render/lom_pass.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <string>

#include "components/shadow_technique.h"
#include "runtime/core/log.h"
#include "runtime/features/shader_interface.h"
#include "runtime/render/depth_draws.h"
#include "runtime/core/hash.h"
#include "runtime/render/texture_storage.h"

namespace kaskad::render {

namespace {

// Whether a view gets a layered occlusion map: cascades, spot maps and cube faces (the
// paraboloid's projection is not a matrix, and its lookup is the plain one).
bool lom_view(const ShadowView& v) { return v.projection != ShadowProjection::dual_paraboloid; }

// A layer's peel region: its read rectangle grown by the widest reach of the occlusion pass's
// search (the factors at the rectangle's edge read peels that far out).
glm::ivec4 peel_rect(const glm::ivec4& r, int size) {
  if (empty_rect(r)) return r;
  const int m = kPcssMaxRadiusTexels + 2;
  return {std::max(r.x - m, 0), std::max(r.y - m, 0), std::min(r.z + m, size),
          std::min(r.w + m, size)};
}

}  // namespace

void LomPass::ensure_storage(int size, int slices) {
  if (depth_ && size == size_ && slices == slices_) return;
  size_ = size;
  slices_ = slices;
  depth_ = gpu::make_texture(GL_TEXTURE_2D_ARRAY);
  glTextureStorage3D(depth_.id(), 1, GL_R32F, size, size, slices);
  occlusion_ = gpu::make_texture(GL_TEXTURE_2D_ARRAY);
  glTextureStorage3D(occlusion_.id(), 1, GL_R8, size, size, slices);
  test_depth_ = gpu::make_texture(GL_TEXTURE_2D);
  glTextureStorage2D(test_depth_.id(), 1, GL_DEPTH_COMPONENT32F, size, size);
  previous_ = gpu::make_texture(GL_TEXTURE_2D);
  glTextureStorage2D(previous_.id(), 1, GL_R32F, size, size);
  for (GLuint t : {depth_.id(), occlusion_.id(), previous_.id()}) {
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  }
  peel_fbo_ = gpu::make_framebuffer();
  glNamedFramebufferTexture(peel_fbo_.id(), GL_DEPTH_ATTACHMENT, test_depth_.id(), 0);
  glNamedFramebufferDrawBuffer(peel_fbo_.id(), GL_COLOR_ATTACHMENT0);
  factor_fbo_ = gpu::make_framebuffer();
  glNamedFramebufferDrawBuffer(factor_fbo_.id(), GL_COLOR_ATTACHMENT0);
  if (!nearest_) {
    nearest_ = border_sampler(false, GL_NEAREST);  // outside the map: nothing stored
    any_samples_ = gpu::make_query(GL_ANY_SAMPLES_PASSED);
    counter_ = gpu::make_buffer();
    glNamedBufferStorage(counter_.id(), sizeof(GLuint), nullptr, GL_DYNAMIC_STORAGE_BIT);
    empty_vao_ = gpu::make_vertex_array();
  }
  const int layers = slices / std::max(peels_, 1);
  drawn_.assign(std::size_t(layers), {});
  layer_overflow_.assign(std::size_t(layers), 0);
}

Status LomPass::prepare(const FrameInput& frame, const DrawList& list, const ShadowMapPass& shadow,
                        FrameStats& stats) {
  stats.lom_layers_computed = 0;
  stats.lom_overflow_texels = 0;
  redraw_ = 0;
  const std::vector<ShadowView>& views = frame.shadow_views;
  if (views.empty() ||
      traits(frame.shadow_settings.technique).extra_pass != ShadowExtraPass::lom_peeling)
    return {};
  const int size = frame.shadow_settings.map_size;
  const int total = views.back().first_layer + views.back().layer_count;
  const int peels = frame.shadow_settings.lom_layers + 1;
  const int slices = total * peels;
  if (!depth_ || size != size_ || slices != slices_ || peels != peels_) {
    const double mib = double(size) * size * slices * 5.0 / double(1 << 20);
    const std::string what = std::to_string(slices) + " slices of " + std::to_string(size) +
                             "^2 (" + std::to_string(int(mib)) + " MiB)";
    // The R32F peels; the R8 factors are no larger.
    const TextureCheck check = check_array_texture(GL_R32F, GL_RED, size, slices);
    if (check.fit == TextureCheck::over_limits)
      return Error{"", "shadow.lom_layers", "the layered occlusion map needs " + what +
                                                ", more than this driver's limits (" +
                                                check.limits() + ")"};
    if (check.fit == TextureCheck::refused)
      return Error{"", "shadow.lom_layers",
                   "the OpenGL driver refuses the layered occlusion map's " + what +
                       "; use a smaller map_size, fewer lom_layers or fewer cascades"};
    peels_ = peels;
    depth_ = {};
    ensure_storage(size, slices);
    // Pass 1 works per map texel and layer: past S1's one 1024^2 map, a software rasteriser
    // is slow whenever the maps are redrawn (the first frame, a moving camera or light;
    // measured: docs/design/soft_shadows.md, lom).
    if (double(size) * size * total > 2.0 * 1024.0 * 1024.0)
      log::warn_once("shadow.technique lom: %d map layers of %d^2 with %d depth peels each; its "
                     "pass 1 runs per map texel and layer, so every frame that redraws the maps "
                     "pays for all of them (S1's set-up is one 1024^2 map; a smaller "
                     "shadow.map_size or a smaller shadow.cascade_count cuts it)",
                     total, size, peels - 1);
  }
  // A layer's inputs beyond its casters: the receivers that cast nothing (stored, so that they
  // are shaded; hashed once for every layer), the light's size and the layer count.
  Hash receivers;
  for (std::uint32_t i : list.depth_order) {
    const DrawItem& d = frame.draws[i];
    if (d.receive_shadows && !d.cast_shadows) receivers.add(d.mesh).add(d.model).add(d.pose);
  }
  inputs_.assign(std::size_t(total), 0);
  for (const ShadowView& v : views)
    for (int c = 0; c < v.layer_count; ++c) {
      const int layer = v.first_layer + c;
      Hash h;
      h.add(shadow.layer_inputs(layer)).add(v.light_size).add(peels).add(v.cull);
      h.add(receivers.value());
      inputs_[std::size_t(layer)] = h.value();
      if (!lom_view(v) || v.skipped[std::size_t(c)]) continue;
      if (!keeps_layer(frame.shadow_cache, drawn_[std::size_t(layer)], inputs_[std::size_t(layer)],
                       stats.layer_rect[std::size_t(layer)], ((v.held >> c) & 1u) != 0))
        redraw_ |= 1u << layer;
    }
  stats.lom_layers_computed = redraw_;
  return {};
}

Status LomPass::record(const FrameInput& frame, const DrawList& list, GpuCache& cache,
                       DrawState& state, FrameStats& stats) {
  if (frame.shadow_views.empty() ||
      traits(frame.shadow_settings.technique).extra_pass != ShadowExtraPass::lom_peeling)
    return {};
  const int peels = peels_;
  Status status;
  std::vector<InstanceRecord> records;
  for (std::size_t view = 0; view < frame.shadow_views.size() && status; ++view) {
    const ShadowView& v = frame.shadow_views[view];
    for (int c = 0; c < v.layer_count && status; ++c) {
      const int layer = v.first_layer + c;
      if (!((redraw_ >> layer) & 1u)) continue;
      const glm::ivec4 read = stats.layer_rect[std::size_t(layer)];
      const glm::ivec4 r = peel_rect(read, size_);
      if (empty_rect(r)) continue;
      // a. Peels 0 .. lom_layers (the last one only to count what did not fit): casters of
      //    the layer, and receivers in its frustum (flagged when they cast nothing).
      const glm::mat4& vp = v.view_proj[std::size_t(c)];
      const std::uint32_t bit = 1u << c;
      auto mask_of = [&](std::uint32_t i) -> std::uint32_t {
        const DrawItem& d = frame.draws[i];
        if (caster_mask(v, d) & bit) return bit;
        return d.receive_shadows && !outside_clip_volume(vp, d.bounds) ? bit : 0u;
      };
      auto record_of = [&](std::uint32_t i, int) {
        const DrawItem& d = frame.draws[i];
        return depth_instance_of(d.model, d.cast_shadows ? 0u : 1u);
      };
      const auto runs =
          depth_runs(frame, list, cache, state, view, true, mask_of, record_of, records);
      glBindFramebuffer(GL_FRAMEBUFFER, peel_fbo_.id());
      glViewport(0, 0, size_, size_);
      glEnable(GL_SCISSOR_TEST);
      glScissor(r.x, r.y, r.z - r.x, r.w - r.y);
      set_depth_state(v);
      glDisable(GL_POLYGON_OFFSET_FILL);  // exact depths: the peels compare them bit for bit
      glEnable(GL_DEPTH_TEST);
      glDepthFunc(GL_LESS);
      glDepthMask(GL_TRUE);
      glBindTextureUnit(kTexPeelPrevious, previous_.id());
      glBindSampler(kTexPeelPrevious, 0);
      // A peel that finds nothing leaves the deeper ones empty: they are only cleared.
      int found = peels;
      for (int j = 0; j < peels && status; ++j) {
        const int slice = layer * peels + j;
        glNamedFramebufferTextureLayer(peel_fbo_.id(), GL_COLOR_ATTACHMENT0, depth_.id(), 0, slice);
        const float empty[4] = {1.0f, 0.0f, 0.0f, 0.0f};
        glClearBufferfv(GL_COLOR, 0, empty);
        if (j >= found) continue;
        if (j == 0) {
          const float none = 0.0f;
          glClearTexSubImage(previous_.id(), 0, r.x, r.y, 0, r.z - r.x, r.w - r.y, 1, GL_RED,
                             GL_FLOAT, &none);
        } else {
          glCopyImageSubData(depth_.id(), GL_TEXTURE_2D_ARRAY, 0, r.x, r.y, slice - 1,
                             previous_.id(), GL_TEXTURE_2D, 0, r.x, r.y, 0, r.z - r.x,
                             r.w - r.y, 1);
        }
        glClearBufferfi(GL_DEPTH_STENCIL, 0, 1.0f, 0);
        glBeginQuery(GL_ANY_SAMPLES_PASSED, any_samples_.id());
        status = draw_runs(frame, list, cache, state, stats, view, runs, records,
                           &v.view_proj[std::size_t(c)], true);
        glEndQuery(GL_ANY_SAMPLES_PASSED);
        GLuint any = 0;
        glGetQueryObjectuiv(any_samples_.id(), GL_QUERY_RESULT, &any);
        if (!any) found = j;
      }
      glDisable(GL_CLIP_DISTANCE0);
      if (!status) break;
      // b. The occlusion factor of every stored point in the read rectangle (one texel more
      //    for pass 2's bilinear samples), peel by peel; the last peel's draw counts the
      //    texels where the overflow peel found a surface.
      auto program = state.use_program(Pass::lom_occlusion, list.frame_key.filtered_for(Pass::lom_occlusion));
      if (!program) {
        status = program.error();
        break;
      }
      const glm::ivec4 f = {std::max(read.x - 1, 0), std::max(read.y - 1, 0),
                            std::min(read.z + 1, size_), std::min(read.w + 1, size_)};
      glBindFramebuffer(GL_FRAMEBUFFER, factor_fbo_.id());
      glScissor(f.x, f.y, f.z - f.x, f.w - f.y);
      glDisable(GL_DEPTH_TEST);
      glDisable(GL_CULL_FACE);
      bind();
      const GLuint zero = 0;
      glNamedBufferSubData(counter_.id(), 0, sizeof zero, &zero);
      glBindBufferBase(GL_ATOMIC_COUNTER_BUFFER, 0, counter_.id());
      glBindVertexArray(empty_vao_.id());
      // Empty peels get no factors: lookups read a factor only where a depth is stored.
      for (int j = 0; j + 1 < peels && j < found; ++j) {
        glNamedFramebufferTextureLayer(factor_fbo_.id(), GL_COLOR_ATTACHMENT0, occlusion_.id(), 0,
                                       layer * peels + j);
        glProgramUniform4i(state.program().id(), kLocLomTarget, int(view), c, j,
                           j + 2 == peels ? 1 : 0);
        glDrawArrays(GL_TRIANGLES, 0, 3);
      }
      glMemoryBarrier(GL_ATOMIC_COUNTER_BARRIER_BIT);
      GLuint overflow = 0;  // 0 unless the overflow peel found something
      if (found == peels) glGetNamedBufferSubData(counter_.id(), 0, sizeof overflow, &overflow);
      layer_overflow_[std::size_t(layer)] = std::int64_t(overflow);
      drawn_[std::size_t(layer)].inputs = inputs_[std::size_t(layer)];
      drawn_[std::size_t(layer)].rect = read;
      glEnable(GL_DEPTH_TEST);
    }
  }
  glDisable(GL_SCISSOR_TEST);
  glBindVertexArray(0);
  for (std::int64_t n : layer_overflow_) stats.lom_overflow_texels += n;
  return status;
}

void LomPass::bind() {
  if (!depth_) return;
  glBindTextureUnit(kTexLomDepth, depth_.id());
  glBindSampler(kTexLomDepth, nearest_.id());
  glBindTextureUnit(kTexLomOcclusion, occlusion_.id());
  glBindSampler(kTexLomOcclusion, nearest_.id());
}

Image LomPass::read_depths() const { return read_slices(depth_, GL_RED, {"Y"}, size_, slices_); }
Image LomPass::read_factors() const { return read_slices(occlusion_, GL_RED, {"Y"}, size_, slices_); }

Image LomPass::read_first_factors() const {
  if (peels_ <= 0) return read_slices(occlusion_, GL_RED, {"Y"}, size_, 0);
  return read_slices(occlusion_, GL_RED, {"Y"}, size_, slices_ / peels_, peels_);
}

}  // namespace kaskad::render
