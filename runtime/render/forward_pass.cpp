#include "runtime/render/forward_pass.h"

#include <epoxy/gl.h>

#include <algorithm>

#include "components/tone_mapping.h"
#include "runtime/features/shader_interface.h"

namespace kaskad::render {
namespace {

// The instance record of a forward draw with model matrix `model`.
InstanceRecord instance_of(const glm::mat4& model) {
  InstanceRecord r;
  r.model = model;
  const glm::mat3 n = glm::transpose(glm::inverse(glm::mat3(model)));
  for (int c = 0; c < 3; ++c) r.normal_matrix[c] = glm::vec4(n[c], 0.0f);
  return r;
}

}  // namespace

Status draw_forward(const FrameInput& frame, std::span<const std::uint32_t> order,
                    const std::vector<VariantKey>& keys, const ProbeJob* capture, int round,
                    const glm::mat4& view_proj, GpuCache& cache, DrawState& state,
                    FrameStats& stats) {
  int& culled = capture ? stats.probe_culled : stats.frustum_culled;
  std::vector<std::uint32_t> visible = visible_draws(frame, order, view_proj, capture, culled);
  std::erase_if(visible, [&](std::uint32_t i) { return cache.mesh(frame.draws[i].mesh).index_count == 0; });
  std::vector<InstanceRecord> records(visible.size());
  for (std::size_t k = 0; k < visible.size(); ++k) records[k] = instance_of(frame.draws[visible[k]].model);
  const std::uint32_t base = cache.upload(records);
  auto reflective = [&](std::uint32_t i) {
    return keys[i].has(VariantKey::kReflectionCube) || keys[i].has(VariantKey::kReflectionSphere);
  };
  // A blended double-sided draw: its back faces, then its front faces (a closed convex mesh
  // then blends in depth order within itself).
  auto two_passes = [&](std::uint32_t i) {
    return keys[i].has(VariantKey::kAlphaBlend) && frame.draws[i].material.double_sided;
  };
  // Runs of visible draws with the same program, material and winding become one batch: one
  // instanced draw per mesh, all in one multi-draw; a reflective draw (its own probe map and
  // k_s * p_r) and a two-pass one stay alone. The draw list orders a batch's draws by mesh; a
  // batch keeps the order of its draws (a blended view's back to front).
  std::vector<MeshDraw> batch;
  for (std::size_t first = 0; first < visible.size();) {
    const std::uint32_t i = visible[first];
    const DrawItem& d = frame.draws[i];
    const bool mirrored = mirrors(d.model);
    std::size_t end = first + 1;
    if (!reflective(i) && !two_passes(i))
      while (end < visible.size() && keys[visible[end]] == keys[i] &&
             frame.draws[visible[end]].material == d.material &&
             mirrors(frame.draws[visible[end]].model) == mirrored)
        ++end;
    batch.clear();
    for (std::size_t k = first; k < end; ++k) {
      const MeshId mesh = frame.draws[visible[k]].mesh;
      if (k > first && frame.draws[visible[k - 1]].mesh == mesh) {
        ++batch.back().count;
      } else {
        batch.push_back({cache.mesh(mesh), base + std::uint32_t(k), 1});
      }
      stats.triangles += std::size_t(batch.back().mesh.index_count / 3);
    }
    KASKAD_TRY(state.use_program(Pass::forward, keys[i]));
    const GLuint prog = state.program().id();
    if (d.material.double_sided) {
      glDisable(GL_CULL_FACE);
    } else {
      glEnable(GL_CULL_FACE);
      glCullFace(GL_BACK);
    }
    glFrontFace(mirrored ? GL_CW : GL_CCW);
    state.bind_material(d, keys[i]);
    // A draw reflecting a probe gets its map (probe_read_buffer(): never a cube being
    // captured), and k_s * p_r.
    const VariantKey key = keys[i];
    if (reflective(i)) {
      for (const ProbeJob& job : frame.probes) {
        if (job.handle != d.probe) continue;
        const int buffer = probe_read_buffer(job, capture ? round : 0);
        if (key.has(VariantKey::kReflectionPbr)) {
          // The pbr model: the probe's prefiltered cube, SH row and last level, and p_r.
          glBindTextureUnit(kTexReflectionCube, cache.probes().existing_specular(job.handle).id());
          glProgramUniform4f(prog, kLocReflection, d.reflection_scale,
                             float(cache.probes().sh_row(job.handle)),
                             float(cache.probes().specular_last_level(job.handle)), 0.0f);
        } else {
          glBindTextureUnit(kTexReflectionCube, cache.probes().existing_cube(job.handle, buffer).id());
          glProgramUniform4f(prog, kLocReflection, d.reflection_scale, 0.0f, 0.0f, 0.0f);
        }
        glBindTextureUnit(kTexReflectionSphere, cache.probes().existing_sphere(job.handle).id());
        if (key.has(VariantKey::kReflectionBox)) {
          glProgramUniform4f(prog, kLocReflectionBoxMin, job.box_min.x, job.box_min.y, job.box_min.z, 0);
          glProgramUniform4f(prog, kLocReflectionBoxMax, job.box_max.x, job.box_max.y, job.box_max.z, 0);
          glProgramUniform4f(prog, kLocReflectionCentre, job.center.x, job.center.y, job.center.z, 0);
        }
        break;
      }
    }
    if (two_passes(i)) {
      glEnable(GL_CULL_FACE);
      glCullFace(GL_FRONT);
      draw_batch(frame, cache, batch, stats.draw_calls, stats.mesh_draws);
      glCullFace(GL_BACK);
    }
    draw_batch(frame, cache, batch, stats.draw_calls, stats.mesh_draws);
    stats.instances += int(end - first);
    first = end;
  }
  glFrontFace(GL_CCW);
  return {};
}

Status draw_transparent(const FrameInput& frame, const DrawList& list,
                        const std::vector<VariantKey>& keys, const ProbeJob* capture, int round,
                        const glm::mat4& view_proj, const glm::vec4& depth_plane,
                        int draw_buffers, GpuCache& cache, DrawState& state, FrameStats& stats) {
  if (list.blend_draws.empty()) return {};
  const std::vector<std::uint32_t> order = back_to_front(frame, list.blend_draws, depth_plane);
  // Depth tested against the opaque draws, not written: blended draws never hide each other.
  // Premultiplied over (forward.frag); the target's alpha is kept. Only colour (buffer 0) is
  // blended: the AOVs and the stored visibility keep the opaque surface behind.
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ZERO, GL_ONE);
  for (int b = 1; b < draw_buffers; ++b) glColorMaski(GLuint(b), GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  const Status st =
      draw_forward(frame, order, keys, capture, round, view_proj, cache, state, stats);
  for (int b = 1; b < draw_buffers; ++b) glColorMaski(GLuint(b), GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);
  return st;
}

std::span<const ForwardPass::Target> ForwardPass::targets() {
  static const Target list[] = {
      {"colour (GL_SRGB8_ALPHA8)", GL_SRGB8_ALPHA8, GL_RGBA, GL_UNSIGNED_BYTE, 4},
      {"position (GL_RGBA32F)", GL_RGBA32F, GL_RGBA, GL_FLOAT, 16},  // xyz, w mask
      {"normal (GL_RGBA32F)", GL_RGBA32F, GL_RGBA, GL_FLOAT, 16},    // xyz, w view depth
      {"visibility (GL_RG32F)", GL_RG32F, GL_RG, GL_FLOAT, 8},       // visibility, cascade
      // rgb reflected colour C_t (S3 eq. (3)), a 1 where a map applies
      {"reflection (GL_RGBA16F)", GL_RGBA16F, GL_RGBA, GL_HALF_FLOAT, 8},
      {"depth (GL_DEPTH_COMPONENT32F)", GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT, GL_FLOAT, 4},
  };
  return list;
}

ForwardPass::Target ForwardPass::visibility_target(int views) {
  // A channel per view; with one view a second for the reprojection code (forward.frag).
  if (views <= 2) return {"stored visibility (GL_RG32F)", GL_RG32F, GL_RG, GL_FLOAT, 8};
  return {"stored visibility (GL_RGBA32F)", GL_RGBA32F, GL_RGBA, GL_FLOAT, 16};
}

void ForwardPass::prepare(const FrameInput& frame, int samples) {
  const bool resized = !fbo_ || frame.width != width_ || frame.height != height_;
  if (resized) {
    for (gpu::Texture& t : visibility_) t.reset();
    width_ = frame.width;
    height_ = frame.height;
    fbo_ = gpu::make_framebuffer();
    const auto list = targets();
    for (std::size_t i = 0; i < list.size(); ++i) {
      gpu::Texture& t = textures_[i];
      t = gpu::make_texture(GL_TEXTURE_2D);
      glTextureStorage2D(t.id(), 1, list[i].internal_format, width_, height_);
      glTextureParameteri(t.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTextureParameteri(t.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      const bool depth = list[i].format == GL_DEPTH_COMPONENT;
      glNamedFramebufferTexture(fbo_.id(), depth ? GL_DEPTH_ATTACHMENT : GLenum(GL_COLOR_ATTACHMENT0 + i),
                                t.id(), 0);
    }
  }
  if (!resized && samples == samples_) return;
  samples_ = samples;
  msaa_fbo_.reset();
  for (gpu::Texture& t : msaa_textures_) t.reset();
  if (samples_ <= 1) return;
  // The colour and depth formats of targets(), multisampled (fixed sample locations: the
  // resolve blit does not care, and every driver offers them).
  msaa_fbo_ = gpu::make_framebuffer();
  const auto list = targets();
  const std::size_t which[2] = {0, list.size() - 1};
  for (std::size_t k = 0; k < 2; ++k) {
    gpu::Texture& t = msaa_textures_[k];
    t = gpu::make_texture(GL_TEXTURE_2D_MULTISAMPLE);
    glTextureStorage2DMultisample(t.id(), samples_, list[which[k]].internal_format, width_, height_,
                                  GL_TRUE);
    glNamedFramebufferTexture(msaa_fbo_.id(), k == 0 ? GL_COLOR_ATTACHMENT0 : GL_DEPTH_ATTACHMENT,
                              t.id(), 0);
  }
}

Status ForwardPass::record(const FrameInput& frame, const DrawList& list,
                           const std::vector<VariantKey>& keys, std::uint32_t reuse,
                           GpuCache& cache, DrawState& state, FrameStats& stats) {
  const GLenum bufs[5] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2,
                          GL_COLOR_ATTACHMENT3, GL_COLOR_ATTACHMENT4};
  aovs_written_ = frame.write_aovs;
  glViewport(0, 0, frame.width, frame.height);
  glEnable(GL_FRAMEBUFFER_SRGB);
  const glm::vec3 background = tone_map(frame.tone_mapping, frame.clear_color * frame.exposure);
  const float clear_color[4] = {background.r, background.g, background.b, 1.0f};
  const float zero[4] = {0, 0, 0, 0};
  const float one = 1.0f;
  const glm::mat4 view_proj = frame.camera.proj * frame.camera.view;
  const glm::vec4 depth_plane = view_depth_plane(frame.camera.view);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  // Whether the single-sample pass below draws colour (no MSAA) or only the AOVs.
  bool single_colour = true;
  if (samples_ > 1) {
    // a. Colour, multisampled. Alpha-masked draws write their coverage as alpha (forward.frag,
    //    VARIANT_ALPHA_TO_COVERAGE); every stored alpha is 1 (alpha to one).
    glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_.id());
    glClearBufferfv(GL_COLOR, 0, clear_color);
    glClearBufferfv(GL_DEPTH, 0, &one);
    glEnable(GL_SAMPLE_ALPHA_TO_COVERAGE);
    glEnable(GL_SAMPLE_ALPHA_TO_ONE);
    Status st = draw_forward(frame, list.forward_order, list.msaa_keys, nullptr, 0,
                             view_proj, cache, state, stats);
    glDisable(GL_SAMPLE_ALPHA_TO_ONE);
    glDisable(GL_SAMPLE_ALPHA_TO_COVERAGE);
    // The blended draws, per sample (their alpha is opacity, not coverage).
    if (st)
      st = draw_transparent(frame, list, list.msaa_keys, nullptr, 0, view_proj, depth_plane, 1,
                            cache, state, stats);
    // b. The resolve: the samples' average, taken in linear space (GL_FRAMEBUFFER_SRGB).
    glNamedFramebufferDrawBuffers(fbo_.id(), 1, bufs);
    glBlitNamedFramebuffer(msaa_fbo_.id(), fbo_.id(), 0, 0, width_, height_, 0, 0, width_, height_,
                           GL_COLOR_BUFFER_BIT, GL_NEAREST);
    if (!st || !frame.write_aovs) {
      glDisable(GL_FRAMEBUFFER_SRGB);
      return st;
    }
    single_colour = false;
  }
  // c. Single sample: colour and the AOVs, or the AOVs alone beside the multisampled colour
  //    (the same programs as without MSAA; their colour output is dropped).
  const GLenum aov_bufs[5] = {GL_NONE, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2,
                              GL_COLOR_ATTACHMENT3, GL_COLOR_ATTACHMENT4};
  glNamedFramebufferDrawBuffers(fbo_.id(), frame.write_aovs ? 5 : 1,
                                single_colour ? bufs : aov_bufs);
  // The stored visibility (render.visibility_cache, never with AOVs): a storing frame writes it
  // through output 1 into attachment 5, attached for this pass only (a loading frame samples
  // it, which an attached texture must not be). There are two targets: a reprojecting frame
  // reads the one stored last and stores into the other.
  const GLenum visibility_attachment = GL_COLOR_ATTACHMENT5;
  const bool stores = reuse == VariantKey::kReuseStore || reuse == VariantKey::kReuseReproject;
  const bool reads = reuse == VariantKey::kReuseLoad || reuse == VariantKey::kReuseReproject;
  if (reads) {
    KASKAD_CHECK(visibility_[current_], "a frame reads shadow visibility that no frame stored");
    glBindTextureUnit(kTexCachedVisibility, visibility_[current_].id());
    glBindSampler(kTexCachedVisibility, 0);
  }
  if (stores) {
    const int views = std::min<int>(int(frame.shadow_views.size()), kMaxShadowedLights);
    if (views != visibility_views_)
      for (gpu::Texture& t : visibility_) t.reset();
    visibility_views_ = views;
    current_ ^= 1;
    gpu::Texture& target = visibility_[current_];
    if (!target) {
      const Target t = visibility_target(views);
      target = gpu::make_texture(GL_TEXTURE_2D);
      glTextureStorage2D(target.id(), 1, t.internal_format, width_, height_);
    }
    glNamedFramebufferTexture(fbo_.id(), visibility_attachment, target.id(), 0);
    const GLenum store_bufs[2] = {GL_COLOR_ATTACHMENT0, visibility_attachment};
    glNamedFramebufferDrawBuffers(fbo_.id(), 2, store_bufs);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
  if (single_colour) glClearBufferfv(GL_COLOR, 0, clear_color);
  if (frame.write_aovs)
    for (int i = 1; i < 5; ++i) glClearBufferfv(GL_COLOR, i, zero);
  // No surface: reprojection code 0, which a reprojecting frame never reuses.
  const float no_surface[4] = {-1.0f, 0.0f, -1.0f, -1.0f};
  if (stores) glClearBufferfv(GL_COLOR, 1, no_surface);
  glClearBufferfv(GL_DEPTH, 0, &one);
  // The AOV pass draws what the colour pass drew: its culling is counted once.
  const int culled = stats.frustum_culled;
  Status st = draw_forward(frame, list.forward_order, keys, nullptr, 0, view_proj,
                           cache, state, stats);
  // A reprojecting frame's second pass: its first drew every pixel whose visibility it could
  // reuse and discarded the rest; the shadow-receiving draws again with the lookup, where the
  // depth test (less) lets through only the pixels the first pass left (and nearer surfaces
  // it discarded). One pass with a branch would do on a GPU; llvmpipe runs a branch's body
  // for every pixel of a SIMD vector, but skips vectors whose early depth test fails.
  if (st && reuse == VariantKey::kReuseReproject) {
    std::vector<std::uint32_t> receivers;
    for (std::uint32_t i : list.forward_order)
      if (keys[i].get(VariantKey::kShadowReuse) == VariantKey::kReuseReproject) receivers.push_back(i);
    const int culled_once = stats.frustum_culled;
    st = draw_forward(frame, receivers, list.keys, nullptr, 0, view_proj, cache, state, stats);
    stats.frustum_culled = culled_once;
  }
  // The blended draws over the colour; the AOV-only pass beside a multisampled colour pass has
  // no colour to blend into: the AOVs show the opaque surfaces either way.
  const int draw_buffers = stores ? 2 : frame.write_aovs ? 5 : 1;
  if (st && single_colour)
    st = draw_transparent(frame, list, keys, nullptr, 0, view_proj, depth_plane, draw_buffers,
                          cache, state, stats);
  if (!single_colour) stats.frustum_culled = culled;
  if (stores) glNamedFramebufferTexture(fbo_.id(), visibility_attachment, 0, 0);
  glDisable(GL_FRAMEBUFFER_SRGB);
  return st;
}

}  // namespace kaskad::render
