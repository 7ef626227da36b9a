#include "runtime/render/renderer.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <numeric>
#include <optional>
#include <tuple>
#include <type_traits>
#include <utility>

#include "runtime/core/log.h"
#include "runtime/gpu/shader.h"
#include "runtime/render/frame_uniforms.h"
#include "runtime/render/gpu_cache.h"
#include "runtime/render/gpu_timers.h"
#include "runtime/core/hash.h"
#include "runtime/render/passes.h"
#include "runtime/render/probe_capture.h"
#include "runtime/features/shader_interface.h"

namespace kaskad::render {
struct Renderer::Impl {
  std::unique_ptr<ShaderLibrary> shaders;
  std::unique_ptr<GpuCache> cache;
  gpu::Buffer frame_ubo;  // FrameBlock of the main view (frame_uniforms.h)

  // The passes, in order (passes.h).
  DeformPass deform;
  ShadowMapPass shadow;
  LomPass lom;
  MomentsPass moments;
  ProbeCapturePass probe_capture;
  ForwardPass forward;

  // Shadow-points pass target (one pixel per point).
  int points_width = 0, points_height = 0;
  gpu::Framebuffer points_fbo;
  gpu::Texture points_target;

  std::optional<VariantKey> frame_key;  // frame features of the last render()
  /// render.visibility_cache: visibility_inputs() of the visibility the forward pass holds
  /// (0: none stored).
  std::uint64_t stored_visibility = 0;
  /// visibility_inputs() of the last frame with the cache on, stored or not.
  std::uint64_t last_visibility = 0;
  /// render.visibility_reproject: world_visibility_inputs() of the visibility held (0: none
  /// that a frame may reproject) and of the last frame, and the camera it was stored under.
  std::uint64_t stored_world = 0, last_world = 0;
  /// Whether the visibility held was looked up (or read back from a frame that looked it up):
  /// a still frame reads back only such, so that a camera that stops shows the lookup itself
  /// (after one frame that looks up), not the reprojection's approximation.
  bool stored_exact = false;
  glm::mat4 stored_view_proj{1.0f};
  glm::vec4 stored_camera_pos{0.0f};

  GpuTimers timers;  // GPU time per part of the frame (read a frame late)
  bool layer_from_vertex = false;  // GL_ARB_shader_viewport_layer_array: gl_Layer in the VS
  // Sample counts the driver offers for both multisampled forward targets, ascending (GL 4.5
  // guarantees 4 at least: GL_MAX_SAMPLES >= 4).
  std::vector<int> sample_counts;

  // The colour samples of a frame asking for `requested` (render.msaa): the request when the
  // driver offers it, else the nearest offered count above it, else the largest (with one
  // warning saying so).
  int samples_for(int requested) const {
    if (requested <= 1 || sample_counts.empty()) return 1;
    int chosen = sample_counts.back();
    for (int c : sample_counts)
      if (c >= requested) {
        chosen = c;
        break;
      }
    if (chosen != requested)
      log::warn_once("render.msaa %d: this OpenGL driver offers %s samples per pixel for the colour "
                     "and depth targets (GL_SAMPLES); using %d",
                     requested, sample_list().c_str(), chosen);
    return chosen;
  }
  std::string sample_list() const {
    std::string out;
    for (int c : sample_counts) out += (out.empty() ? "" : ", ") + std::to_string(c);
    return out;
  }

  // The key as this driver can build it: without gl_Layer in vertex shaders the layered shadow
  // pass falls back to one pass per layer (the same maps).
  VariantKey supported(VariantKey k) const {
    if (!layer_from_vertex) k.set(VariantKey::kShadowLayered, 0);
    return k;
  }
};

Result<std::unique_ptr<Renderer>> Renderer::create(const std::filesystem::path& shader_dir,
                                                  const RendererOptions& options) {
  std::unique_ptr<Renderer> r(new Renderer());
  r->impl_ = std::make_unique<Impl>();
  Impl& im = *r->impl_;
  if (!std::filesystem::exists(shader_dir / "forward.frag"))
    return Error{shader_dir.string(), "", "shader directory has no forward.frag"};
  auto lib = ShaderLibrary::create(shader_dir, options.shader_cache_dir, options.uber_oracle);
  if (!lib) return lib.error();
  im.shaders = std::move(lib.value());
  auto cache = GpuCache::create(shader_dir);
  if (!cache) return cache.error();
  im.cache = std::move(cache.value());
  im.layer_from_vertex = epoxy_has_gl_extension("GL_ARB_shader_viewport_layer_array");
  if (!im.layer_from_vertex)
    log::warn(
        "GL_ARB_shader_viewport_layer_array missing: shadow maps are drawn one layer at a "
        "time");
  // Sample counts offered for the forward pass's colour and depth formats (GL_SAMPLES lists
  // them in descending order; each is within GL_MAX_COLOR/DEPTH_TEXTURE_SAMPLES).
  {
    const auto list = ForwardPass::targets();
    std::vector<int> both;
    for (GLenum format : {list.front().internal_format, list.back().internal_format}) {
      GLint n = 0;
      glGetInternalformativ(GL_TEXTURE_2D_MULTISAMPLE, format, GL_NUM_SAMPLE_COUNTS, 1, &n);
      std::vector<GLint> counts(std::size_t(std::max(n, 0)));
      if (n > 0)
        glGetInternalformativ(GL_TEXTURE_2D_MULTISAMPLE, format, GL_SAMPLES, n, counts.data());
      std::vector<int> sorted(counts.begin(), counts.end());
      std::sort(sorted.begin(), sorted.end());
      if (format == list.front().internal_format) {
        both = sorted;
      } else {
        std::vector<int> common;
        std::set_intersection(both.begin(), both.end(), sorted.begin(), sorted.end(),
                              std::back_inserter(common));
        both = common;
      }
    }
    std::erase_if(both, [](int c) { return c < 2; });
    im.sample_counts = both;
  }
  im.frame_ubo = gpu::make_buffer();
  glNamedBufferStorage(im.frame_ubo.id(), sizeof(FrameBlock), nullptr, GL_DYNAMIC_STORAGE_BIT);
  im.cache->probes().ibl().set_timers(&im.timers);
  return r;
}

Renderer::~Renderer() = default;

ShaderLibrary& Renderer::shaders() { return *impl_->shaders; }

Status Renderer::prewarm(const FrameInput& frame, bool shadow_points) {
  auto requests = required_programs(frame);
  // The points pass (shadow_at_points(), the stability metrics) reads the frame's key.
  if (shadow_points)
    requests.push_back({Pass::shadow_points, frame_variant(frame).filtered_for(Pass::shadow_points)});
  for (ProgramRequest& r : requests) r.key = impl_->supported(r.key);
  Status st = impl_->shaders->prewarm(requests);
  stats_.shaders = impl_->shaders->stats();
  return st;
}

namespace {

/// MemAvailable from /proc/meminfo in bytes; 0 when unknown.
std::uint64_t available_memory() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  std::uint64_t kib = 0;
  std::string unit;
  while (in >> key >> kib >> unit)
    if (key == "MemAvailable:") return kib * 1024;
  return 0;
}

std::string gib(double bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f GiB", bytes / double(1ull << 30));
  return buf;
}

/// What of draw `d` (forward program `key`) decides which of its fragments end up in front, and
/// where: mesh, matrix, pose, program, sidedness, alpha mode, and whether it receives shadows.
void add_visibility_draw(Hash& h, const DrawItem& d, VariantKey key) {
  const Material& m = d.material;
  h.add(d.mesh).add(d.model).add(d.pose).add(d.receive_shadows).add(key.bits());
  h.add(m.double_sided).add(m.alpha_mode).add(m.alpha_cutoff).add(m.base_color.a);
  h.add(m.base_color_texture).add(m.base_color_transform);
}

/// What the main view's shadow visibility at each pixel depends on, besides the shadow maps'
/// depths: the frame block (camera, lights, shadow views' matrices, splits and parameters), the
/// frame's features, the target size, the shaders (a reload of an edited file looks up again),
/// and every draw of the forward pass with what decides which of its fragments end up in front
/// (mesh, matrix, program, sidedness, alpha mode).
std::uint64_t visibility_inputs(const FrameInput& frame, const DrawList& list,
                                const AssetStore& assets, const FrameBlock& block,
                                int shader_reloads) {
  Hash h;
  h.add(assets.uid).add(shader_reloads).add(frame.width).add(frame.height);
  h.add(list.frame_key.bits()).add(block);
  for (std::uint32_t i : list.forward_order) add_visibility_draw(h, frame.draws[i], list.keys[i]);
  return h.value();
}

/// What a world point's shadow visibility depends on, so that a frame whose camera alone moved
/// may reproject the visibility stored under another camera: the lights and the shadow views'
/// parameters (not their fitted matrices, splits or rectangles, which follow the camera), the
/// frame's features, the target size, the shaders, and every draw, caster or receiver, with
/// what it casts and receives.
std::uint64_t world_visibility_inputs(const FrameInput& frame, const DrawList& list,
                                      const AssetStore& assets, const FrameBlock& block,
                                      int shader_reloads) {
  Hash h;
  h.add(assets.uid).add(shader_reloads).add(frame.width).add(frame.height);
  h.add(list.frame_key.bits()).add(block.frame_params).add(block.counts);
  h.add(block.light_color).add(block.light_info).add(block.light_dir).add(block.light_pos);
  h.add(block.light_cone).add(frame.shadow_settings.depth_format);
  for (std::size_t k = 0; k < frame.shadow_views.size(); ++k) {
    const ShadowView& v = frame.shadow_views[k];
    h.add(v.light_index).add(v.projection).add(v.first_layer).add(v.layer_count);
    h.add(v.slope_bias).add(v.constant_bias).add(v.cull);
    if (k < std::size_t(kMaxShadowedLights)) {
      const ShadowViewBlock& b = block.shadow_views[k];
      h.add(b.info).add(b.params).add(b.soft);
    }
  }
  // Every draw, with what it casts (not shadow_layers: which cascades a caster is drawn into
  // follows their fit, and the maps hold the same depths either way).
  for (std::size_t i = 0; i < frame.draws.size(); ++i) {
    add_visibility_draw(h, frame.draws[i], list.keys[i]);
    h.add(frame.draws[i].cast_shadows);
  }
  return h.value();
}

}  // namespace

Status Renderer::check_target_size(int width, int height, bool read_aovs, int msaa) const {
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  const std::string where = "render size " + size;
  if (width < 1 || height < 1) return Error{"", where, "width and height must be at least 1"};
  GLint max_texture = 0, max_renderbuffer = 0, max_viewport[2] = {0, 0};
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_texture);
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_renderbuffer);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, max_viewport);
  const int limit = std::min({max_texture, max_renderbuffer, max_viewport[0], max_viewport[1]});
  if (width > limit || height > limit)
    return Error{"", where,
                 "larger than this OpenGL driver allows: " + std::to_string(limit) +
                     " pixels a side (GL_MAX_TEXTURE_SIZE " + std::to_string(max_texture) +
                     ", GL_MAX_RENDERBUFFER_SIZE " + std::to_string(max_renderbuffer) +
                     ", GL_MAX_VIEWPORT_DIMS " + std::to_string(max_viewport[0]) + ")"};
  // The forward pass's targets, asked of the driver through proxy textures: nothing is
  // allocated, a refused format reads back width 0.
  const double pixels = double(width) * double(height);
  double gpu_bytes = 0.0;
  for (const ForwardPass::Target& t : ForwardPass::targets()) {
    glTexImage2D(GL_PROXY_TEXTURE_2D, 0, GLint(t.internal_format), width, height, 0, t.format,
                 t.type, nullptr);
    GLint got = 0;
    glGetTexLevelParameteriv(GL_PROXY_TEXTURE_2D, 0, GL_TEXTURE_WIDTH, &got);
    if (got == 0)
      return Error{"", where,
                   std::string("the OpenGL driver refuses a ") + t.name + " target of this size (" +
                       gib(pixels * t.bytes_per_pixel) + ")"};
    gpu_bytes += pixels * t.bytes_per_pixel;
  }
  // With render.msaa, the multisampled colour and depth targets too, at the count used.
  if (const int samples = impl_->samples_for(msaa); samples > 1) {
    const auto list = ForwardPass::targets();
    for (const ForwardPass::Target* t : {&list.front(), &list.back()}) {
      glTexImage2DMultisample(GL_PROXY_TEXTURE_2D_MULTISAMPLE, samples, t->internal_format, width,
                              height, GL_TRUE);
      GLint got = 0;
      glGetTexLevelParameteriv(GL_PROXY_TEXTURE_2D_MULTISAMPLE, 0, GL_TEXTURE_WIDTH, &got);
      const double bytes = pixels * t->bytes_per_pixel * samples;
      if (got == 0)
        return Error{"", where,
                     "the OpenGL driver refuses a " + std::to_string(samples) + "-sample " +
                         t->name + " target of this size (" + gib(bytes) + "; render.msaa)"};
      gpu_bytes += bytes;
    }
  }
  // The stored shadow visibility (render.visibility_cache, single-sample frames without AOVs):
  // two targets (one read while the other is stored) of at most four floats.
  if (!read_aovs && impl_->samples_for(msaa) <= 1)
    gpu_bytes += 2.0 * pixels * ForwardPass::visibility_target(kMaxShadowedLights).bytes_per_pixel;
  // Read-backs: colour as float RGBA, and with AOVs 14 float channels plus their staging.
  const double host_bytes = pixels * (16.0 + (read_aovs ? 2.0 * 14 * 4 + 64 : 0.0));
  const std::uint64_t available = available_memory();
  if (available > 0 && gpu_bytes + host_bytes > double(available))
    return Error{"", where,
                 "needs about " + gib(gpu_bytes + host_bytes) + " for its targets and read-back, " +
                     "but only " + gib(double(available)) + " of memory is available"};
  return {};
}

Status Renderer::render(const FrameInput& frame, const AssetStore& assets) {
  Impl& im = *impl_;
  KASKAD_CHECK(frame.width > 0 && frame.height > 0 && frame.width <= 16384 &&
                   frame.height <= 16384,
               "frame size must be in [1, 16384], was " + std::to_string(frame.width) + "x" +
                   std::to_string(frame.height));
  if (std::string bad = shadow_views_error(frame); !bad.empty())
    return Error{"", "frame input", bad};
  for (const DrawItem& d : frame.draws)
    if (index(d.mesh) >= assets.meshes.size())
      return Error{"", "draw list", "mesh id " + std::to_string(index(d.mesh)) + " is out of range"};
  if (int(frame.lights.size()) > kMaxLights)
    log::warn_once("%zu lights; only the first %d are shaded", frame.lights.size(), kMaxLights);
  read_timers();
  stats_.draw_calls = stats_.mesh_draws = stats_.instances = 0;
  stats_.triangles = 0;
  stats_.frustum_culled = 0;
  stats_.program_switches = stats_.material_switches = 0;
  stats_.probe_faces = stats_.probe_draw_calls = stats_.probe_instances = stats_.probe_culled = 0;
  stats_.probe_prefilters = stats_.probe_prefilter_faces = 0;
  stats_.cascade_receiver_pixels.fill(0);

  // The frame block of the main view (uploaded once the shadow pass has said where its scrolled
  // layers lie) is bound at binding 0: every pass reads it.
  FrameBlock block = pack_frame_block(frame);
  // The GPU cache holds this frame's assets (another scene's ids start it afresh).
  im.cache->use(assets);
  im.cache->begin_frame();
  // Keys and submission orders, once per frame.
  const DrawList list = build_draw_list(frame, im.supported(frame_variant(frame)));
  im.frame_key = list.frame_key;
  DrawState state(*im.shaders, *im.cache, stats_);

  // 0. Deformed meshes. After it: every posed mesh holds this frame's pose.
  KASKAD_TRY(im.deform.record(frame, assets.uid, *im.cache, *im.shaders, stats_));

  // 1. Shadow maps. After it: every layer of every shadow view holds its casters' depth.
  KASKAD_TRY(im.shadow.prepare(frame, list, assets, list.frame_key.has(VariantKey::kShadowLayered),
                               state.features_by_uniform(), im.shaders->stats().reloads, stats_));
  im.shadow.offset_lookups(frame, block);
  glNamedBufferSubData(im.frame_ubo.id(), 0, sizeof block, &block);
  glBindBufferBase(GL_UNIFORM_BUFFER, 0, im.frame_ubo.id());
  im.timers.begin(TimedPart::shadow_depth);
  Status st = im.shadow.record(frame, list, *im.cache, state, stats_);
  im.timers.end(TimedPart::shadow_depth);
  // S1's layered occlusion map (technique lom) from those layers.
  const ShadowExtraPass extra_pass = shadow_technique_of(list.frame_key).extra_pass;
  const bool lom = extra_pass == ShadowExtraPass::lom_peeling;
  const bool moments = extra_pass == ShadowExtraPass::moments;
  if (lom) im.timers.begin(TimedPart::lom);
  if (st) st = im.lom.prepare(frame, list, im.shadow, stats_);
  if (st) st = im.lom.record(frame, list, *im.cache, state, stats_);
  if (lom) im.timers.end(TimedPart::lom);
  // The moments of vsm/evsm from those layers.
  if (moments) im.timers.begin(TimedPart::moments);
  if (st) st = im.moments.prepare(frame, im.shadow, stats_);
  if (st) st = im.moments.record(frame, list, im.shadow, state);
  if (moments) im.timers.end(TimedPart::moments);
  KASKAD_TRY(st);
  im.shadow.bind();
  im.lom.bind();
  im.moments.bind();

  // 2. Probe captures. After it: every probe's visible cube (and sphere map) is the one the
  //    frame's reflections read.
  im.probe_capture.prepare(frame, assets, *im.cache);
  im.timers.begin(TimedPart::probe_captures);
  st = im.probe_capture.record(frame, list, block, im.frame_ubo, *im.cache, state, stats_);
  im.timers.end(TimedPart::probe_captures);
  KASKAD_TRY(st);

  // 3. Forward. After it: colour (and the AOVs) of the main view. With render.visibility_cache
  //    a frame whose visibility inputs are those of the visibility stored and whose shadow
  //    maps were all kept reads it back instead of looking the maps up.
  im.forward.prepare(frame, im.samples_for(frame.msaa));
  stats_.msaa_samples = im.forward.samples();
  //    A storing frame writes its visibility only when it sees what the frame before saw, so
  //    that the frames of a moving camera, which no frame could read back, do not pay for it
  //    (docs/design/shadow_cost.md, "Visibility cache"): a camera that stops looks up
  //    twice, stores on the second frame and reads back from the third.
  std::uint32_t reuse = list.frame_key.get(VariantKey::kShadowReuse);
  const std::uint64_t stored = std::exchange(im.stored_visibility, 0);
  const std::uint64_t stored_world = std::exchange(im.stored_world, 0);
  bool store = false;
  if (reuse != 0) {
    const std::uint64_t inputs =
        visibility_inputs(frame, list, assets, block, im.shaders->stats().reloads);
    // The world inputs (a hash over every draw) only where the frame may reproject.
    const bool reprojects = reprojects_visibility(frame);
    const std::uint64_t world =
        reprojects ? world_visibility_inputs(frame, list, assets, block, im.shaders->stats().reloads)
                   : 0;
    const bool maps_kept = stats_.shadow_layers_rendered == 0 && stats_.lom_layers_computed == 0 &&
                           stats_.vsm_layers_computed == 0;
    // A held layer (shadow.far_cascade_interval) may keep depth that its casters have left:
    // visibility looked up through one is not reprojected, nor stored for reprojection.
    bool held = false;
    for (const ShadowView& v : frame.shadow_views) held = held || v.held != 0;
    if (maps_kept && inputs == stored && im.stored_exact && im.forward.holds_visibility()) {
      reuse = VariantKey::kReuseLoad;
    } else if (reprojects && !held && world == stored_world &&
               inputs != stored && im.forward.holds_visibility()) {
      // (A frame that sees what a reprojecting frame saw looks up instead: the camera stopped.)
      reuse = VariantKey::kReuseReproject;
    }
    // A frame stores when a later one may read it: one that sees what this frame saw (a camera
    // that stops), or one whose camera alone moved.
    store = reuse == VariantKey::kReuseStore &&
            (inputs == im.last_visibility ||
             (reprojects && world == im.last_world));
    im.last_visibility = inputs;
    im.last_world = world;
    // What the target holds and a later frame may read: this frame's visibility. After a frame
    // that neither stores nor loads, nothing: what changed in between may not all be in the
    // inputs (a caster's cast_shadows redraws the maps, and the maps' inputs are their own).
    const bool holds = reuse != VariantKey::kReuseStore || store;
    im.stored_visibility = holds ? inputs : 0;
    im.stored_world = holds && !held ? world : 0;
    if (reuse != VariantKey::kReuseLoad) im.stored_exact = reuse != VariantKey::kReuseReproject;
  }
  // A loading or reprojecting frame draws with its own programs. Those not built yet are built
  // now (prewarm() builds them up front), each once (the order runs by program); one that does
  // not build (a shader edited into an error since the storing programs were built) leaves the
  // frame to look up with the programs it has.
  std::vector<VariantKey> reuse_keys;
  if (reuse == VariantKey::kReuseLoad || reuse == VariantKey::kReuseReproject) {
    reuse_keys = list.keys;
    for (VariantKey& k : reuse_keys)
      if (k.get(VariantKey::kShadowReuse) == VariantKey::kReuseStore)
        k.set(VariantKey::kShadowReuse, reuse);
    std::optional<VariantKey> built;
    for (std::uint32_t i : list.forward_order) {
      const VariantKey key = reuse_keys[i];
      if (key.get(VariantKey::kShadowReuse) != reuse || key == built) continue;
      if (auto program = im.shaders->program(Pass::forward, key); !program) {
        log::warn_once("render.visibility_cache: a program that reads the stored visibility does "
                       "not build (%s); frames look the shadow maps up instead",
                       program.error().to_string().c_str());
        // A reprojecting frame would have stored; the target holds the frame before's.
        if (reuse == VariantKey::kReuseReproject) im.stored_visibility = im.stored_world = 0;
        reuse = VariantKey::kReuseStore;
        break;
      }
      built = key;
    }
  }
  // The storing programs draw a frame that does not store; their visibility output goes to no
  // target.
  const std::uint32_t pass_reuse = reuse == VariantKey::kReuseStore && !store ? 0u : reuse;
  stats_.visibility_reused = reuse == VariantKey::kReuseLoad;
  stats_.visibility_reprojected = reuse == VariantKey::kReuseReproject;
  stats_.visibility_stored = pass_reuse == VariantKey::kReuseStore || stats_.visibility_reprojected;
  // A reprojecting frame reads the visibility stored under the camera of the frame that stored
  // it (the block's previous_* members, zero in every other frame's block).
  if (reuse == VariantKey::kReuseReproject) {
    struct {
      glm::mat4 view_proj;
      glm::vec4 camera_pos;
    } previous{im.stored_view_proj, im.stored_camera_pos};
    static_assert(offsetof(FrameBlock, previous_camera_pos) ==
                  offsetof(FrameBlock, previous_view_proj) + sizeof(glm::mat4));
    glNamedBufferSubData(im.frame_ubo.id(), offsetof(FrameBlock, previous_view_proj),
                         sizeof previous, &previous);
  }
  if (stats_.visibility_stored) {
    im.stored_view_proj = block.view_proj;
    im.stored_camera_pos = block.camera_pos;
  }
  im.timers.begin(TimedPart::forward);
  st = im.forward.record(frame, list, reuse_keys.empty() ? list.keys : reuse_keys, pass_reuse,
                         *im.cache, state, stats_);
  im.timers.end(TimedPart::forward);
  if (!st) im.stored_visibility = im.stored_world = 0;
  KASKAD_TRY(st);

  stats_.shaders = im.shaders->stats();
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return {};
}

void Renderer::read_timers() {
  Impl& im = *impl_;
  im.timers.begin_frame();  // the previous frame's results (available after its finish())
  const auto& ms = im.timers.last();
  auto part = [&](TimedPart p) { return ms[std::size_t(p)]; };
  stats_.shadow_gpu_ms = part(TimedPart::shadow_depth) + part(TimedPart::lom) + part(TimedPart::moments);
  stats_.lom_gpu_ms = part(TimedPart::lom);
  stats_.moments_gpu_ms = part(TimedPart::moments);
  stats_.forward_gpu_ms = part(TimedPart::forward);
  stats_.probe_gpu_ms = part(TimedPart::probe_captures) + part(TimedPart::probe_prefilter);
  stats_.prefilter_gpu_ms = part(TimedPart::probe_prefilter);
  stats_.probe_faces_timed = stats_.probe_faces;  // still the previous frame's count here
}

Result<std::vector<glm::vec2>> Renderer::shadow_at_points(std::span<const glm::vec3> points,
                                                          std::span<const glm::vec3> normals,
                                                          std::vector<float>* blend_weights) {
  Impl& im = *impl_;
  if (points.size() != normals.size())
    return Error{"", "shadow_at_points", std::to_string(points.size()) + " points but " +
                                             std::to_string(normals.size()) + " normals"};
  if (points.empty()) return std::vector<glm::vec2>{};
  constexpr int kRow = 1024;
  if (points.size() > std::size_t(kRow) * 16384)
    return Error{"", "shadow_at_points", std::to_string(points.size()) +
                                             " points; at most 16777216 per call"};
  const int count = int(points.size());
  const int w = std::min(count, kRow), h = (count + kRow - 1) / kRow;
  if (!im.points_fbo || w != im.points_width || h != im.points_height) {
    im.points_width = w;
    im.points_height = h;
    im.points_target = gpu::make_texture(GL_TEXTURE_2D);
    glTextureStorage2D(im.points_target.id(), 1, GL_RGBA32F, w, h);
    im.points_fbo = gpu::make_framebuffer();
    glNamedFramebufferTexture(im.points_fbo.id(), GL_COLOR_ATTACHMENT0, im.points_target.id(), 0);
  }
  // Interleaved position | normal per point; a short-lived buffer (a metrics path, not a frame).
  std::vector<glm::vec3> data(std::size_t(count) * 2);
  for (int i = 0; i < count; ++i) {
    data[std::size_t(i) * 2] = points[std::size_t(i)];
    data[std::size_t(i) * 2 + 1] = normals[std::size_t(i)];
  }
  gpu::Buffer buffer = gpu::make_buffer();
  glNamedBufferStorage(buffer.id(), GLsizeiptr(data.size() * sizeof(glm::vec3)), data.data(), 0);
  gpu::VertexArray vao = gpu::make_vertex_array();
  glVertexArrayVertexBuffer(vao.id(), 0, buffer.id(), 0, 2 * sizeof(glm::vec3));
  for (GLuint attr : {kAttrPosition, kAttrNormal}) {
    glEnableVertexArrayAttrib(vao.id(), attr);
    glVertexArrayAttribFormat(vao.id(), attr, 3, GL_FLOAT, GL_FALSE,
                              attr == kAttrNormal ? GLuint(sizeof(glm::vec3)) : 0);
    glVertexArrayAttribBinding(vao.id(), attr, 0);
  }
  if (!im.frame_key) return Error{"", "shadow_at_points", "no frame rendered yet"};
  auto program =
      im.shaders->program(Pass::shadow_points, im.frame_key->filtered_for(Pass::shadow_points));
  if (!program) return program.error();
  glUseProgram(program->id());
  glProgramUniform2i(program->id(), kLocTargetSize, w, h);
  // The frame block and shadow map are still those of the last render(); bind them again in
  // case other GL work ran in between.
  glBindBufferBase(GL_UNIFORM_BUFFER, 0, im.frame_ubo.id());
  im.shadow.bind();
  im.lom.bind();
  im.moments.bind();
  glBindFramebuffer(GL_FRAMEBUFFER, im.points_fbo.id());
  glViewport(0, 0, w, h);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  const float clear[4] = {1.0f, -1.0f, 0.0f, 0.0f};  // lit, no cascade, no blend
  glClearBufferfv(GL_COLOR, 0, clear);
  glBindVertexArray(vao.id());
  glDrawArrays(GL_POINTS, 0, count);
  glBindVertexArray(0);
  std::vector<glm::vec4> texels(std::size_t(w) * h);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(im.points_target.id(), 0, GL_RGBA, GL_FLOAT,
                    GLsizei(texels.size() * sizeof(glm::vec4)), texels.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glEnable(GL_DEPTH_TEST);
  std::vector<glm::vec2> out(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = glm::vec2(texels[i]);
  if (blend_weights) {
    blend_weights->resize(std::size_t(count));
    for (std::size_t i = 0; i < out.size(); ++i) (*blend_weights)[i] = texels[i].z;
  }
  return out;
}

void Renderer::finish() { glFinish(); }

namespace {

// Reads one attachment as floats and flips rows so the image is top to bottom.
std::vector<float> read_texture(GLuint tex, int w, int h, GLenum format, int channels) {
  std::vector<float> px(std::size_t(w) * h * channels);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(tex, 0, format, GL_FLOAT, GLsizei(px.size() * sizeof(float)), px.data());
  std::vector<float> flipped(px.size());
  const std::size_t row = std::size_t(w) * channels;
  for (int y = 0; y < h; ++y)
    std::memcpy(&flipped[std::size_t(y) * row], &px[std::size_t(h - 1 - y) * row],
                row * sizeof(float));
  return flipped;
}

}  // namespace

Image Renderer::read_color() const {
  const ForwardPass& fw = impl_->forward;
  Image img;
  img.width = fw.width();
  img.height = fw.height();
  img.channels = 4;
  img.channel_names = {"R", "G", "B", "A"};
  // The sRGB target stores encoded values; reading as GL_RGBA/GL_FLOAT returns them unconverted
  // only for non-sRGB formats, so read bytes instead.
  std::vector<std::uint8_t> bytes(std::size_t(img.width) * img.height * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(fw.texture(0).id(), 0, GL_RGBA, GL_UNSIGNED_BYTE, GLsizei(bytes.size()),
                    bytes.data());
  img.pixels.resize(bytes.size());
  const std::size_t row = std::size_t(img.width) * 4;
  for (int y = 0; y < img.height; ++y)
    for (std::size_t i = 0; i < row; ++i)
      img.pixels[std::size_t(y) * row + i] = bytes[std::size_t(img.height - 1 - y) * row + i] / 255.0f;
  return img;
}

Image Renderer::read_aovs() const {
  const ForwardPass& fw = impl_->forward;
  KASKAD_CHECK(fw.aovs_written(), "the last frame was rendered without write_aovs");
  const int w = fw.width(), h = fw.height();
  const auto pos = read_texture(fw.texture(1).id(), w, h, GL_RGBA, 4);
  const auto nrm = read_texture(fw.texture(2).id(), w, h, GL_RGBA, 4);
  const auto vis = read_texture(fw.texture(3).id(), w, h, GL_RG, 2);
  const auto refl = read_texture(fw.texture(4).id(), w, h, GL_RGBA, 4);
  Image img;
  img.width = w;
  img.height = h;
  img.channel_names = {"P.X",          "P.Y",          "P.Z",          "N.X",
                       "N.Y",          "N.Z",          "Z",            "visibility",
                       "mask",         "cascade",      "reflection.R", "reflection.G",
                       "reflection.B", "reflector"};
  img.channels = int(img.channel_names.size());
  img.pixels.resize(std::size_t(w) * h * img.channels);
  for (std::size_t i = 0; i < std::size_t(w) * h; ++i) {
    float* o = &img.pixels[i * img.channels];
    o[0] = pos[i * 4 + 0];
    o[1] = pos[i * 4 + 1];
    o[2] = pos[i * 4 + 2];
    o[3] = nrm[i * 4 + 0];
    o[4] = nrm[i * 4 + 1];
    o[5] = nrm[i * 4 + 2];
    o[6] = nrm[i * 4 + 3];
    o[7] = vis[i * 2];
    o[8] = pos[i * 4 + 3];
    o[9] = vis[i * 2 + 1];
    o[10] = refl[i * 4 + 0];
    o[11] = refl[i * 4 + 1];
    o[12] = refl[i * 4 + 2];
    o[13] = refl[i * 4 + 3];
  }
  return img;
}

std::array<std::size_t, kMaxCascades> Renderer::cascade_pixel_counts() const {
  const ForwardPass& fw = impl_->forward;
  KASKAD_CHECK(fw.aovs_written(), "the last frame was rendered without write_aovs");
  std::array<std::size_t, kMaxCascades> out{};
  const auto vis = read_texture(fw.texture(3).id(), fw.width(), fw.height(), GL_RG, 2);
  const auto pos = read_texture(fw.texture(1).id(), fw.width(), fw.height(), GL_RGBA, 4);
  for (std::size_t i = 0; i < vis.size() / 2; ++i) {
    if (pos[i * 4 + 3] != 1.0f) continue;  // AOV mask: only shadow-receiving surfaces count
    const int c = int(vis[i * 2 + 1]);
    if (c >= 0 && c < kMaxCascades) ++out[std::size_t(c)];
  }
  return out;
}

Image Renderer::read_shadow_map() const { return impl_->shadow.read(); }

std::vector<glm::vec3> Renderer::read_mesh_positions(MeshId id) const {
  return impl_->cache->read_positions(id);
}
Image Renderer::read_lom_depths() const { return impl_->lom.read_depths(); }
Image Renderer::read_lom_factors() const { return impl_->lom.read_factors(); }

Image Renderer::read_soft_shadow_maps() const {
  const Impl& im = *impl_;
  if (!im.frame_key || !im.frame_key->has(VariantKey::kShadow)) return {};
  const ShadowExtraPass extra_pass = shadow_technique_of(*im.frame_key).extra_pass;
  if (extra_pass == ShadowExtraPass::lom_peeling) return im.lom.read_first_factors();
  if (extra_pass != ShadowExtraPass::moments) return {};
  const Image moments = im.moments.read();
  if (moments.pixels.empty()) return {};
  Image first;
  first.width = moments.width;
  first.height = moments.height;
  first.channels = 1;
  first.channel_names = {"Y"};
  first.pixels.resize(std::size_t(moments.width) * std::size_t(moments.height));
  for (std::size_t i = 0; i < first.pixels.size(); ++i)
    first.pixels[i] = moments.pixels[i * std::size_t(moments.channels)];
  return first;
}

CubeMap Renderer::read_probe_cube(ProbeHandle handle, int buffer) const {
  return impl_->cache->probes().read_cube(handle, buffer);
}

CubeMap Renderer::read_environment_level(int level) const {
  return impl_->cache->probes().ibl().read_environment_level(level);
}

std::vector<glm::vec3> Renderer::read_sh_row(int row) const {
  return impl_->cache->probes().ibl().read_sh_row(row);
}

int Renderer::probe_sh_row(ProbeHandle handle) const { return impl_->cache->probes().sh_row(handle); }

SphereMap Renderer::read_probe_sphere(ProbeHandle handle) const {
  return impl_->cache->probes().read_sphere(handle);
}

void Renderer::present(int window_width, int window_height) const {
  const ForwardPass& fw = impl_->forward;
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glNamedFramebufferReadBuffer(fw.framebuffer().id(), GL_COLOR_ATTACHMENT0);
  glBlitNamedFramebuffer(fw.framebuffer().id(), 0, 0, 0, fw.width(), fw.height(), 0, 0, window_width,
                         window_height, GL_COLOR_BUFFER_BIT, GL_LINEAR);
}

}  // namespace kaskad::render
