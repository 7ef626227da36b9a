#include "runtime/render/moments_pass.h"

#include <epoxy/gl.h>

#include <bit>
#include <string>

#include "components/shadow_technique.h"
#include "runtime/features/shader_interface.h"
#include "runtime/core/hash.h"
#include "runtime/render/texture_storage.h"

namespace kaskad::render {

void MomentsPass::ensure_storage(int size, int layers, bool four) {
  if (moments_ && size == size_ && layers == layers_ && four == four_) return;
  size_ = size;
  layers_ = layers;
  four_ = four;
  const GLenum format = four ? GL_RGBA32F : GL_RG32F;
  const int levels = std::bit_width(unsigned(size));  // down to 1 x 1
  moments_ = gpu::make_texture(GL_TEXTURE_2D_ARRAY);
  glTextureStorage3D(moments_.id(), levels, format, size, size, layers);
  along_x_ = gpu::make_texture(GL_TEXTURE_2D);
  glTextureStorage2D(along_x_.id(), 1, format, size, size);
  glTextureParameteri(along_x_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(along_x_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  fbo_ = gpu::make_framebuffer();
  glNamedFramebufferDrawBuffer(fbo_.id(), GL_COLOR_ATTACHMENT0);
  if (!filtered_) {
    filtered_ = gpu::make_sampler();
    glSamplerParameteri(filtered_.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glSamplerParameteri(filtered_.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glSamplerParameteri(filtered_.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glSamplerParameteri(filtered_.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    // Trilinear only: moments_filtered() (shadow_moments.glsl) filters anisotropically along
    // the footprint itself; the sampler's own anisotropy is slow on llvmpipe and less accurate
    // (measured: docs/design/soft_shadows.md).
    empty_vao_ = gpu::make_vertex_array();
  }
  drawn_.assign(std::size_t(layers), {});
}

Status MomentsPass::prepare(const FrameInput& frame, const ShadowMapPass& shadow,
                            FrameStats& stats) {
  stats.vsm_layers_computed = 0;
  redraw_ = 0;
  const std::vector<ShadowView>& views = frame.shadow_views;
  const ShadowTechniqueTraits& technique = traits(frame.shadow_settings.technique);
  if (views.empty() || technique.extra_pass != ShadowExtraPass::moments) return {};
  const int size = frame.shadow_settings.map_size;
  const int total = views.back().first_layer + views.back().layer_count;
  const bool four = technique.moment_channels == 4;
  if (!moments_ || size != size_ || total != layers_ || four != four_) {
    const TextureCheck check = check_array_texture(four ? GL_RGBA32F : GL_RG32F,
                                                   four ? GL_RGBA : GL_RG, size, total);
    if (check.fit != TextureCheck::fits) {
      const double mib = double(size) * size * total * (four ? 16.0 : 8.0) * 4.0 / 3.0 /
                         double(1 << 20);
      return Error{"", "shadow.technique",
                   "the OpenGL driver refuses the " +
                       std::string(technique_name(frame.shadow_settings.technique)) +
                       " moments (" + std::to_string(total) + " layers of " +
                       std::to_string(size) + "^2 with mipmaps, " + std::to_string(int(mib)) +
                       " MiB); use a smaller map_size or fewer cascades"};
    }
    ensure_storage(size, total, four);
  }
  inputs_.assign(std::size_t(total), 0);
  rects_.assign(std::size_t(total), glm::ivec4(0));
  for (const ShadowView& v : views)
    for (int c = 0; c < v.layer_count; ++c) {
      const int layer = v.first_layer + c;
      rects_[std::size_t(layer)] = stats.layer_rect[std::size_t(layer)];
      Hash h;
      h.add(shadow.layer_inputs(layer)).add(frame.shadow_settings.vsm_blur).add(four);
      inputs_[std::size_t(layer)] = h.value();
      if (!keeps_layer(frame.shadow_cache, drawn_[std::size_t(layer)], inputs_[std::size_t(layer)],
                       rects_[std::size_t(layer)], ((v.held >> c) & 1u) != 0))
        redraw_ |= 1u << layer;
    }
  stats.vsm_layers_computed = redraw_;
  return {};
}

Status MomentsPass::record(const FrameInput& frame, const DrawList& list, ShadowMapPass& shadow,
                           DrawState& state) {
  if (redraw_ == 0) return {};
  auto program = state.use_program(Pass::vsm_moments, list.frame_key.filtered_for(Pass::vsm_moments));
  if (!program) return program.error();
  const GLuint prog = state.program().id();
  shadow.bind();  // the raw depths (UNIT_SHADOW_DEPTH)
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
  glViewport(0, 0, size_, size_);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glBindVertexArray(empty_vao_.id());
  glBindTextureUnit(kTexVsmSource, along_x_.id());
  glBindSampler(kTexVsmSource, 0);
  const int side = frame.shadow_settings.vsm_blur;
  for (std::size_t view = 0; view < frame.shadow_views.size(); ++view) {
    const ShadowView& v = frame.shadow_views[view];
    for (int c = 0; c < v.layer_count; ++c) {
      const int layer = v.first_layer + c;
      if (!((redraw_ >> layer) & 1u)) continue;
      // The depth is valid in the read rectangle only (the shadow pass drew nothing else), and
      // that holds the blur's reach around every texel a lookup reads (filter_reach_texels()).
      // (Dual-paraboloid maps keep the 3x3 lookup: no moments.)
      const glm::ivec4 r = v.projection == ShadowProjection::dual_paraboloid
                               ? glm::ivec4(0)
                               : rects_[std::size_t(layer)];
      glProgramUniform4i(prog, kLocVsmRect, r.x, r.y, r.z, r.w);
      // 1. Moments of the depth, blurred along x, into along_x_ (the rectangle only).
      if (!empty_rect(r)) {
        glNamedFramebufferTexture(fbo_.id(), GL_COLOR_ATTACHMENT0, along_x_.id(), 0);
        glEnable(GL_SCISSOR_TEST);
        glScissor(r.x, r.y, r.z - r.x, r.w - r.y);
        glProgramUniform4i(prog, kLocVsmTarget, int(view), c, 0, side);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glDisable(GL_SCISSOR_TEST);
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
      }
      // 2. Blurred along y into the layer; outside the rectangle the moments of depth 1.
      glNamedFramebufferTextureLayer(fbo_.id(), GL_COLOR_ATTACHMENT0, moments_.id(), 0, layer);
      glProgramUniform4i(prog, kLocVsmTarget, int(view), c, 1, side);
      glDrawArrays(GL_TRIANGLES, 0, 3);
      drawn_[std::size_t(layer)].inputs = inputs_[std::size_t(layer)];
      drawn_[std::size_t(layer)].rect = r;
    }
  }
  glBindVertexArray(0);
  glEnable(GL_DEPTH_TEST);
  // 3. Mipmaps for trilinear lookups. Every layer's chain is rebuilt (one call); layers not
  //    recomputed get the same levels again.
  glGenerateTextureMipmap(moments_.id());
  return {};
}

void MomentsPass::bind() {
  if (!moments_) return;
  glBindTextureUnit(kTexVsmMoments, moments_.id());
  glBindSampler(kTexVsmMoments, filtered_.id());
}

Image MomentsPass::read() const {
  return four_ ? read_slices(moments_, GL_RGBA, {"R", "G", "B", "A"}, size_, layers_)
               : read_slices(moments_, GL_RG, {"R", "G"}, size_, layers_);
}

}  // namespace kaskad::render
