#include "runtime/render/renderer.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <numeric>
#include <optional>
#include <tuple>
#include <type_traits>

#include "runtime/core/log.h"
#include "runtime/gpu/shader.h"
#include "runtime/render/probe_capture.h"

namespace kaskad::render {
namespace {

constexpr int kMaxExtra = kMaxShadowedLights - 1;
// FrameStats::shadow_layers_rendered has one bit per layer of the shadow map.
static_assert(kMaxShadowedLights * kMaxCascades <= 32);

// std140 mirror of FrameBlock in content/shaders/common.glsl (change together).
struct alignas(16) FrameBlock {
  glm::mat4 view_proj;
  glm::mat4 view;
  glm::vec4 camera_pos;
  glm::vec4 ambient;
  glm::ivec4 counts;
  glm::vec4 shadow_params;
  glm::mat4 cascade_view_proj[kMaxCascades];
  glm::vec4 cascade_splits[3];  // D[0..8], four per vec4 (std140 pads float arrays to vec4)
  glm::vec4 cascade_texel[2];   // metres per texel, four per vec4
  glm::vec4 light_color[kMaxLights];
  glm::vec4 light_dir[kMaxLights];
  glm::vec4 light_pos[kMaxLights];
  glm::vec4 light_cone[kMaxLights];
  // Further shadowed directional lights (FrameInput::extra_shadows).
  glm::ivec4 extra_count;             // x: how many
  glm::ivec4 extra_light[kMaxExtra];  // x light index, y first layer, z cascades
  glm::vec4 extra_params[kMaxExtra];  // x normal offset, y blend band, z map size
  glm::mat4 extra_view_proj[kMaxExtra * kMaxCascades];
  glm::vec4 extra_splits[kMaxExtra * 3];  // D[0..8] of light k: [3k .. 3k+2]
  glm::vec4 extra_texel[kMaxExtra * 2];   // metres per texel of light k: [2k, 2k+1]
};
static_assert(sizeof(FrameBlock) == 2 * 64 + 4 * 16 + kMaxCascades * 64 + 5 * 16 +
                                        4 * kMaxLights * 16 + 16 +
                                        kMaxExtra * (2 * 16 + kMaxCascades * 64 + 5 * 16));

GLenum depth_internal_format(DepthFormat f) {
  switch (f) {
    case DepthFormat::d16: return GL_DEPTH_COMPONENT16;
    case DepthFormat::d32f: return GL_DEPTH_COMPONENT32F;
    case DepthFormat::d24: break;
  }
  return GL_DEPTH_COMPONENT24;
}

// Fixed attribute and uniform locations (see the shaders).
constexpr GLuint kAttrPosition = 0, kAttrNormal = 1, kAttrUv = 2;
constexpr GLint kUniModel = 0, kUniNormalMatrix = 4, kUniBaseColor = 8, kUniMaterial = 9,
                kUniEmissive = 10, kUniOracleFeatures = 11, kUniLightViewProj = 12,
                // Per-program locations: shadow_points (13), shadow_depth layering (13, 14, 16+),
                // forward reflections (16-19); no program has two of them.
                kUniTargetSize = 13, kUniLayerMask = 13, kUniLayerBase = 14, kUniLayerViewProj = 16,
                kUniReflection = 16, kUniReflectionBoxMin = 17, kUniReflectionBoxMax = 18,
                kUniReflectionCentre = 19;
constexpr GLuint kTexBaseColor = 0, kTexNormal = 1, kTexShadow = 2, kTexReflectionCube = 3,
                 kTexReflectionSphere = 4;

struct GpuMesh {
  gpu::VertexArray vao;
  gpu::Buffer vertices;
  gpu::Buffer indices;
  GLsizei index_count = 0;
};

struct GpuTexture {
  gpu::Texture texture;
};

// FNV-1a over the bytes of plain values: the inputs of a shadow layer (shadow caching).
struct InputHash {
  std::uint64_t h = 14695981039346656037ull;
  template <typename T>
  InputHash& add(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));
    for (unsigned char b : bytes) h = (h ^ b) * 1099511628211ull;
    return *this;
  }
  std::uint64_t value() const { return h | 1u; }  // never 0, which means "nothing drawn"
};

// A 1x1 texture standing in for a missing material texture.
gpu::Texture make_solid_texture(const std::array<float, 4>& rgba, GLenum internal_format) {
  gpu::Texture t = gpu::make_texture(GL_TEXTURE_2D);
  glTextureStorage2D(t.id(), 1, internal_format, 1, 1);
  glTextureSubImage2D(t.id(), 0, 0, 0, 1, 1, GL_RGBA, GL_FLOAT, rgba.data());
  return t;
}

}  // namespace

struct Renderer::Impl {
  std::unique_ptr<ShaderLibrary> shaders;
  bool oracle = false;
  std::uint64_t assets_uid = 0;                            // whose ids the caches below hold
  std::vector<GpuMesh> meshes;                             // indexed by MeshId
  std::vector<std::unique_ptr<GpuTexture>> textures;       // indexed by TextureId
  gpu::Texture white, flat_normal;
  gpu::Buffer frame_ubo;

  // Forward targets.
  int width = 0, height = 0;
  gpu::Framebuffer fbo;
  gpu::Texture color, position, normal, visibility, reflection, depth;
  std::unique_ptr<ProbeMaps> probes;  // reflection probe maps (probe_capture.h)

  // Shadow map: a depth texture array, one layer per cascade.
  int shadow_size = 0, shadow_layers = 0;
  DepthFormat shadow_format = DepthFormat::d24;
  ShadowFilter shadow_filter = ShadowFilter::none;
  gpu::Framebuffer shadow_fbo;
  gpu::Texture shadow_map;
  bool shadow_valid = false;
  /// Per layer of shadow_map: a hash of what its depth was last drawn from (layer_inputs()); 0
  /// = nothing valid. A layer whose inputs hash the same is kept, not re-rendered.
  std::vector<std::uint64_t> layer_drawn_from;

  // Shadow-points pass target (one pixel per point) and its point buffer.
  int points_width = 0, points_height = 0;
  gpu::Framebuffer points_fbo;
  gpu::Texture points_target;

  std::optional<VariantKey> frame_key;  // frame features of the last render()

  std::array<gpu::Query, 3> timers;  // shadow, forward, probe captures
  bool timers_pending = false;
  std::uint64_t frames_rendered = 0;
  bool aovs_written = false;
  bool layer_from_vertex = false;  // GL_ARB_shader_viewport_layer_array: gl_Layer in the VS

  // The key as this driver can build it: without gl_Layer in vertex shaders the layered shadow
  // pass falls back to one pass per layer (the same maps).
  VariantKey supported(VariantKey k) const {
    if (!layer_from_vertex) k.set(VariantKey::kShadowLayered, 0);
    return k;
  }

  const GpuMesh& mesh(MeshId id, const AssetStore& assets) {
    if (index(id) >= meshes.size()) meshes.resize(index(id) + 1);
    GpuMesh& m = meshes[index(id)];
    if (m.vao) return m;
    const MeshData& src = assets.meshes[index(id)];
    const std::size_t n = src.positions.size();
    // One buffer, three streams: positions | normals | uvs (uvs zero when the mesh has none).
    const std::size_t pos_bytes = n * sizeof(glm::vec3), uv_bytes = n * sizeof(glm::vec2);
    std::vector<std::uint8_t> data(2 * pos_bytes + uv_bytes, 0);
    std::memcpy(data.data(), src.positions.data(), pos_bytes);
    if (src.normals.size() == n) std::memcpy(data.data() + pos_bytes, src.normals.data(), pos_bytes);
    if (src.uvs.size() == n) std::memcpy(data.data() + 2 * pos_bytes, src.uvs.data(), uv_bytes);
    m.vertices = gpu::make_buffer();
    glNamedBufferStorage(m.vertices.id(), GLsizeiptr(std::max<std::size_t>(data.size(), 1)),
                         data.data(), 0);
    m.indices = gpu::make_buffer();
    glNamedBufferStorage(m.indices.id(),
                         GLsizeiptr(std::max<std::size_t>(src.indices.size() * 4, 4)),
                         src.indices.empty() ? nullptr : src.indices.data(), 0);
    m.index_count = GLsizei(src.indices.size());
    m.vao = gpu::make_vertex_array();
    const GLuint vao = m.vao.id();
    glVertexArrayVertexBuffer(vao, 0, m.vertices.id(), 0, sizeof(glm::vec3));
    glVertexArrayVertexBuffer(vao, 1, m.vertices.id(), GLintptr(pos_bytes), sizeof(glm::vec3));
    glVertexArrayVertexBuffer(vao, 2, m.vertices.id(), GLintptr(2 * pos_bytes), sizeof(glm::vec2));
    const GLuint attrs[3] = {kAttrPosition, kAttrNormal, kAttrUv};
    const GLint sizes[3] = {3, 3, 2};
    for (int i = 0; i < 3; ++i) {
      glEnableVertexArrayAttrib(vao, attrs[i]);
      glVertexArrayAttribFormat(vao, attrs[i], sizes[i], GL_FLOAT, GL_FALSE, 0);
      glVertexArrayAttribBinding(vao, attrs[i], GLuint(i));
    }
    glVertexArrayElementBuffer(vao, m.indices.id());
    return m;
  }

  GLuint texture(TextureId id, const AssetStore& assets, bool is_normal_map) {
    if (id == kNoTexture || index(id) >= assets.textures.size())
      return is_normal_map ? flat_normal.id() : white.id();
    if (index(id) >= textures.size()) textures.resize(index(id) + 1);
    if (!textures[index(id)]) {
      const TextureData& src = assets.textures[index(id)];
      auto t = std::make_unique<GpuTexture>();
      t->texture = gpu::make_texture(GL_TEXTURE_2D);
      const GLuint tex = t->texture.id();
      const int levels = 1 + int(std::floor(std::log2(std::max(1, std::max(src.width, src.height)))));
      // Colour data is sRGB-encoded; normal maps are linear. Normal maps reuse the same cache slot
      // as long as a texture is used in one role only (glTF practice).
      const GLenum fmt = (src.srgb && !is_normal_map) ? GL_SRGB8_ALPHA8 : GL_RGBA8;
      glTextureStorage2D(tex, levels, fmt, std::max(1, src.width), std::max(1, src.height));
      if (src.width > 0 && src.height > 0 &&
          src.rgba8.size() == std::size_t(src.width) * src.height * 4) {
        glTextureSubImage2D(tex, 0, 0, 0, src.width, src.height, GL_RGBA, GL_UNSIGNED_BYTE,
                            src.rgba8.data());
      }
      glGenerateTextureMipmap(tex);
      glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
      glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      glTextureParameteri(tex, GL_TEXTURE_WRAP_S, GL_REPEAT);
      glTextureParameteri(tex, GL_TEXTURE_WRAP_T, GL_REPEAT);
      textures[index(id)] = std::move(t);
    }
    return textures[index(id)]->texture.id();
  }

  void ensure_targets(int w, int h) {
    if (fbo && w == width && h == height) return;
    width = w;
    height = h;
    auto make = [&](gpu::Texture& t, GLenum fmt) {
      t = gpu::make_texture(GL_TEXTURE_2D);
      glTextureStorage2D(t.id(), 1, fmt, w, h);
      glTextureParameteri(t.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTextureParameteri(t.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    };
    make(color, GL_SRGB8_ALPHA8);
    make(position, GL_RGBA32F);
    make(normal, GL_RGBA32F);
    make(visibility, GL_RG32F);  // r visibility, g cascade index
    make(reflection, GL_RGBA16F);  // rgb reflected colour C_t (S3 eq. (3)), 0 without a map
    make(depth, GL_DEPTH_COMPONENT32F);
    fbo = gpu::make_framebuffer();
    glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT0, color.id(), 0);
    glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT1, position.id(), 0);
    glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT2, normal.id(), 0);
    glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT3, visibility.id(), 0);
    glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT4, reflection.id(), 0);
    glNamedFramebufferTexture(fbo.id(), GL_DEPTH_ATTACHMENT, depth.id(), 0);
  }

  void ensure_shadow_map(int size, int layers, DepthFormat format, ShadowFilter filter) {
    if (shadow_fbo && size == shadow_size && layers == shadow_layers && format == shadow_format &&
        filter == shadow_filter)
      return;
    if (!shadow_fbo || size != shadow_size || layers != shadow_layers || format != shadow_format) {
      shadow_size = size;
      shadow_layers = layers;
      shadow_format = format;
      shadow_map = gpu::make_texture(GL_TEXTURE_2D_ARRAY);
      glTextureStorage3D(shadow_map.id(), 1, depth_internal_format(format), size, size, layers);
      // S4: clamp to border with border depth 1, so lookups outside the map compare as lit.
      glTextureParameteri(shadow_map.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
      glTextureParameteri(shadow_map.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
      const float border[4] = {1.0f, 1.0f, 1.0f, 1.0f};
      glTextureParameterfv(shadow_map.id(), GL_TEXTURE_BORDER_COLOR, border);
      glTextureParameteri(shadow_map.id(), GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
      glTextureParameteri(shadow_map.id(), GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
      layer_drawn_from.assign(std::size_t(layers), 0);  // new storage: nothing to keep
      shadow_fbo = gpu::make_framebuffer();
      glNamedFramebufferTextureLayer(shadow_fbo.id(), GL_DEPTH_ATTACHMENT, shadow_map.id(), 0, 0);
      glNamedFramebufferDrawBuffer(shadow_fbo.id(), GL_NONE);
      glNamedFramebufferReadBuffer(shadow_fbo.id(), GL_NONE);
    }
    shadow_filter = filter;
    const GLint f = filter == ShadowFilter::bilinear ? GL_LINEAR : GL_NEAREST;
    glTextureParameteri(shadow_map.id(), GL_TEXTURE_MIN_FILTER, f);
    glTextureParameteri(shadow_map.id(), GL_TEXTURE_MAG_FILTER, f);
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
  im.oracle = options.uber_oracle;
  auto probes = ProbeMaps::create(shader_dir);
  if (!probes) return probes.error();
  im.probes = std::move(probes.value());
  im.white = make_solid_texture({1, 1, 1, 1}, GL_SRGB8_ALPHA8);
  // Exactly (0.5, 0.5, 1): decodes to (0, 0, 1), so the cotangent frame leaves the normal as is.
  // An 8-bit 128 would tilt every normal by 0.2 degrees, with visible derivative noise.
  im.flat_normal = make_solid_texture({0.5f, 0.5f, 1, 1}, GL_RGBA16F);
  im.layer_from_vertex = epoxy_has_gl_extension("GL_ARB_shader_viewport_layer_array");
  if (!im.layer_from_vertex)
    log::warn(
        "GL_ARB_shader_viewport_layer_array missing: shadow maps are drawn one layer at a "
        "time");
  im.frame_ubo = gpu::make_buffer();
  glNamedBufferStorage(im.frame_ubo.id(), sizeof(FrameBlock), nullptr, GL_DYNAMIC_STORAGE_BIT);
  im.timers[0] = gpu::make_query(GL_TIME_ELAPSED);
  im.timers[1] = gpu::make_query(GL_TIME_ELAPSED);
  im.timers[2] = gpu::make_query(GL_TIME_ELAPSED);
  // Empty shadow map so the sampler is complete even in frames without a shadow pass.
  im.ensure_shadow_map(64, 1, DepthFormat::d24, ShadowFilter::none);
  return r;
}

Renderer::~Renderer() = default;

ShaderLibrary& Renderer::shaders() { return *impl_->shaders; }

namespace {
int cascade_layers(const ShadowPass& p) { return std::clamp(p.cascade_count, 1, kMaxCascades); }

int shaded_lights(const FrameInput& frame) {
  return std::min<int>(int(frame.lights.size()), kMaxLights);
}

bool has_shadow(const FrameInput& frame) {
  return frame.shadow.light_index >= 0 && frame.shadow.light_index < shaded_lights(frame);
}

// The further shadowed directional lights the frame draws and shades: of
// FrameInput::extra_shadows those with a shaded light and orthographic cascades, at most
// kMaxExtra; none without the first shadowed light. Their number is a variant field
// (shadow_lights), so render() and frame_variant() must agree: both call this.
std::vector<const ShadowPass*> drawn_extra_shadows(const FrameInput& frame) {
  std::vector<const ShadowPass*> out;
  if (!has_shadow(frame)) return out;
  for (const ShadowPass& e : frame.extra_shadows) {
    if (int(out.size()) == kMaxExtra) break;
    if (e.light_index < 0 || e.light_index >= shaded_lights(frame) ||
        e.projection != ShadowProjection::ortho)
      continue;
    out.push_back(&e);
  }
  return out;
}
}  // namespace

VariantKey frame_variant(const FrameInput& frame) {
  VariantKey k;
  if (has_shadow(frame)) {
    const ShadowSettings& s = frame.shadow.settings;
    k.set(VariantKey::kShadow, 1);
    k.set(VariantKey::kShadowLightsMinus1, std::uint32_t(drawn_extra_shadows(frame).size()));
    k.set(VariantKey::kShadowFilter, std::uint32_t(s.filter));
    k.set(VariantKey::kShadowProjection, std::uint32_t(frame.shadow.projection));
    // Paraboloid hemispheres are projected in code, one pass each: no layered pass for them.
    if (s.layered && frame.shadow.projection != ShadowProjection::dual_paraboloid)
      k.set(VariantKey::kShadowLayered, 1);
    // Layers of spot and point lights are faces, not cascades: no cascade selection code.
    if (frame.shadow.projection == ShadowProjection::ortho)
      k.set(VariantKey::kCascadeCountMinus1, std::uint32_t(cascade_layers(frame.shadow) - 1));
    k.set(VariantKey::kCascadeSelection, s.selection == CascadeSelection::map_bounds ? 1u : 0u);
    k.set(VariantKey::kDebugCascades, s.debug_cascades ? 1u : 0u);
  }
  if (frame.write_aovs) k.set(VariantKey::kAovs, 1);
  return k;
}

VariantKey capture_frame_variant(VariantKey frame) {
  VariantKey k = VariantKey(frame.bits() & ~VariantKey::kAovs.mask());
  if (k.has(VariantKey::kShadow) && k.get(VariantKey::kShadowProjection) == 0)  // ortho cascades
    k.set(VariantKey::kCascadeSelection, 1);
  return k;
}

VariantKey material_variant(const DrawItem& d) {
  // receive_shadows is a per-object flag, but it selects code like a material feature.
  VariantKey k = VariantKey(d.material.features & VariantKey::kMaterialMask & ~VariantKey::kReceiveShadows.mask());
  if (d.receive_shadows) k.set(VariantKey::kReceiveShadows, 1);
  return k;
}

std::vector<ProgramRequest> required_programs(const FrameInput& frame) {
  const VariantKey fk = frame_variant(frame);
  // Probe captures draw without AOVs; a reflector's draw gets its map feature once its first
  // capture completes (possibly frames later when time-sliced): compile those up front too.
  const VariantKey capture_fk = capture_frame_variant(fk);
  std::vector<ProgramRequest> out;
  for (const DrawItem& d : frame.draws) {
    const VariantKey k = material_variant(d) | fk;
    out.push_back({Pass::forward, k.filtered_for(Pass::forward)});
    if (fk.has(VariantKey::kShadow) && d.cast_shadows) {
      out.push_back({Pass::depth, k.filtered_for(Pass::depth)});
      // Extra (directional) lights draw with the plain depth program, whatever the first's is.
      if (!frame.extra_shadows.empty())
        out.push_back({Pass::depth,
                       VariantKey(k).set(VariantKey::kShadowProjection, 0).filtered_for(Pass::depth)});
    }
    std::vector<VariantKey> materials = {material_variant(d)};
    for (const ProbeJob& job : frame.probes)
      if (job.handle == d.probe)
        materials.push_back(VariantKey(materials[0])
                                .set(job.sphere ? VariantKey::kReflectionSphere
                                                : VariantKey::kReflectionCube, 1)
                                .set(VariantKey::kReflectionBox, job.box ? 1u : 0u));
    for (const VariantKey m : materials) {
      out.push_back({Pass::forward, (m | fk).filtered_for(Pass::forward)});
      if (!frame.probes.empty()) out.push_back({Pass::forward, (m | capture_fk).filtered_for(Pass::forward)});
    }
  }
  auto less = [](const ProgramRequest& a, const ProgramRequest& b) {
    return std::pair(a.pass, a.key) < std::pair(b.pass, b.key);
  };
  std::sort(out.begin(), out.end(), less);
  out.erase(std::unique(out.begin(), out.end(),
                        [](const ProgramRequest& a, const ProgramRequest& b) {
                          return a.pass == b.pass && a.key == b.key;
                        }),
            out.end());
  return out;
}

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

/// Whether the driver can make the shadow map array (GL limits, then a proxy texture).
Status check_shadow_map_size(int size, int layers, DepthFormat format) {
  const std::string where = "shadow.map_size " + std::to_string(size);
  GLint max_size = 0, max_layers = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
  const double bytes = double(size) * size * layers * (format == DepthFormat::d16 ? 2.0 : 4.0);
  std::string what = std::to_string(size) + "^2 x " + std::to_string(layers) + " layers";
  if (size > max_size || layers > max_layers)
    return Error{"", where, "shadow maps of " + what + " exceed this driver's limits (GL_MAX_TEXTURE_SIZE " +
                                std::to_string(max_size) + ", GL_MAX_ARRAY_TEXTURE_LAYERS " +
                                std::to_string(max_layers) + ")"};
  glTexImage3D(GL_PROXY_TEXTURE_2D_ARRAY, 0, GLint(depth_internal_format(format)), size, size, layers,
               0, GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
  GLint got = 0;
  glGetTexLevelParameteriv(GL_PROXY_TEXTURE_2D_ARRAY, 0, GL_TEXTURE_WIDTH, &got);
  if (got == 0)
    return Error{"", where, "the OpenGL driver refuses shadow maps of " + what + " (" +
                                std::to_string(int(bytes / double(1 << 20))) +
                                " MiB); use a smaller map_size or fewer cascades"};
  return {};
}

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

}  // namespace

Status Renderer::check_target_size(int width, int height, bool read_aovs) const {
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
  // The targets of ensure_targets() (change together), asked of the driver through proxy
  // textures: nothing is allocated, a refused format reads back width 0.
  struct Target {
    const char* name;
    GLenum internal, format, type;
    int bytes;
  };
  const Target targets[] = {{"colour (GL_SRGB8_ALPHA8)", GL_SRGB8_ALPHA8, GL_RGBA, GL_UNSIGNED_BYTE, 4},
                            {"position (GL_RGBA32F)", GL_RGBA32F, GL_RGBA, GL_FLOAT, 16},
                            {"normal (GL_RGBA32F)", GL_RGBA32F, GL_RGBA, GL_FLOAT, 16},
                            {"visibility (GL_RG32F)", GL_RG32F, GL_RG, GL_FLOAT, 8},
                            {"reflection (GL_RGBA16F)", GL_RGBA16F, GL_RGBA, GL_HALF_FLOAT, 8},
                            {"depth (GL_DEPTH_COMPONENT32F)", GL_DEPTH_COMPONENT32F,
                             GL_DEPTH_COMPONENT, GL_FLOAT, 4}};
  const double pixels = double(width) * double(height);
  double gpu_bytes = 0.0;
  for (const Target& t : targets) {
    glTexImage2D(GL_PROXY_TEXTURE_2D, 0, GLint(t.internal), width, height, 0, t.format, t.type,
                 nullptr);
    GLint got = 0;
    glGetTexLevelParameteriv(GL_PROXY_TEXTURE_2D, 0, GL_TEXTURE_WIDTH, &got);
    if (got == 0)
      return Error{"", where,
                   std::string("the OpenGL driver refuses a ") + t.name + " target of this size (" +
                       gib(pixels * t.bytes) + ")"};
    gpu_bytes += pixels * t.bytes;
  }
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
  // Timer results of the previous frame (available after finish()).
  if (im.timers_pending) {
    GLuint64 ns[3] = {0, 0, 0};
    glGetQueryObjectui64v(im.timers[0].id(), GL_QUERY_RESULT, &ns[0]);
    glGetQueryObjectui64v(im.timers[1].id(), GL_QUERY_RESULT, &ns[1]);
    glGetQueryObjectui64v(im.timers[2].id(), GL_QUERY_RESULT, &ns[2]);
    stats_.shadow_gpu_ms = double(ns[0]) * 1e-6;
    stats_.forward_gpu_ms = double(ns[1]) * 1e-6;
    stats_.probe_gpu_ms = double(ns[2]) * 1e-6;
    stats_.probe_faces_timed = stats_.probe_faces;  // still the previous frame's count here
  }
  stats_.draw_calls = stats_.shadow_draw_calls = 0;
  stats_.triangles = stats_.shadow_triangles = 0;

  // Frame uniforms.
  FrameBlock fb{};
  fb.view_proj = frame.camera.proj * frame.camera.view;
  fb.view = frame.camera.view;
  fb.camera_pos = glm::vec4(frame.camera.position, 1.0f);
  fb.ambient = glm::vec4(frame.ambient, frame.exposure);
  const int light_count = std::min<int>(int(frame.lights.size()), kMaxLights);
  if (int(frame.lights.size()) > kMaxLights)
    log::warn("%zu lights; only the first %d are shaded", frame.lights.size(), kMaxLights);
  const bool shadowed = has_shadow(frame);
  const int cascades = shadowed ? cascade_layers(frame.shadow) : 0;
  // Further shadowed directional lights: their cascades follow the first light's layers.
  const std::vector<const ShadowPass*> extras = drawn_extra_shadows(frame);
  std::array<int, kMaxShadowedLights> first_layer{};
  int total_layers = cascades;
  for (std::size_t k = 0; k < extras.size(); ++k) {
    first_layer[k] = total_layers;
    total_layers += cascade_layers(*extras[k]);
  }
  const int aov_light = frame.aov_shadow_light >= 0 && frame.aov_shadow_light <= int(extras.size())
                            ? frame.aov_shadow_light
                            : 0;
  fb.counts =
      glm::ivec4(light_count, shadowed ? frame.shadow.light_index : -1, cascades, aov_light);
  // The basic map (fit scene) is biased by polygon offset alone, as before the cascades.
  auto normal_offset_of = [](const ShadowPass& sp) {
    return sp.projection == ShadowProjection::ortho && sp.settings.fit_mode == FitMode::scene
               ? 0.0f
               : sp.settings.normal_offset_bias;
  };
  fb.extra_count = glm::ivec4(int(extras.size()), 0, 0, 0);
  for (std::size_t k = 0; k < extras.size(); ++k) {
    const ShadowPass& e = *extras[k];
    const int n = cascade_layers(e);
    fb.extra_light[k] = glm::ivec4(e.light_index, first_layer[k], n, 0);
    fb.extra_params[k] = glm::vec4(normal_offset_of(e), e.settings.blend_band,
                                   float(frame.shadow.settings.map_size), 0);
    for (int i = 0; i < n; ++i) {
      fb.extra_view_proj[k * kMaxCascades + std::size_t(i)] = e.view_proj[std::size_t(i)];
      fb.extra_texel[k * 2 + std::size_t(i / 4)][i % 4] = e.texel_size[std::size_t(i)];
    }
    for (int i = 0; i <= n; ++i)
      fb.extra_splits[k * 3 + std::size_t(i / 4)][i % 4] = e.splits[std::size_t(i)];
  }
  if (shadowed) {
    const ShadowPass& sp = frame.shadow;
    const float normal_offset = normal_offset_of(sp);
    fb.shadow_params = glm::vec4(normal_offset, sp.settings.blend_band, float(sp.settings.map_size), 0);
    for (int i = 0; i < cascades; ++i) {
      fb.cascade_view_proj[i] = sp.view_proj[std::size_t(i)];
      fb.cascade_texel[i / 4][i % 4] = sp.texel_size[std::size_t(i)];
    }
    for (int i = 0; i <= cascades; ++i) fb.cascade_splits[i / 4][i % 4] = sp.splits[std::size_t(i)];
  }
  for (int i = 0; i < light_count; ++i) {
    const LightItem& l = frame.lights[std::size_t(i)];
    fb.light_color[i] = glm::vec4(l.color, float(int(l.type)));
    fb.light_dir[i] = glm::vec4(l.direction, l.range);
    fb.light_pos[i] = glm::vec4(l.position, l.cos_outer);
    fb.light_cone[i] = glm::vec4(l.cos_inner, 0, 0, 0);
  }
  glNamedBufferSubData(im.frame_ubo.id(), 0, sizeof fb, &fb);
  glBindBufferBase(GL_UNIFORM_BUFFER, 0, im.frame_ubo.id());

  // GPU meshes and textures are cached by id; ids of another AssetStore are other assets.
  if (assets.uid != im.assets_uid) {
    im.meshes.clear();
    im.textures.clear();
    im.probes->clear();  // probe handles name entities of that scene
    im.assets_uid = assets.uid;
  }
  {  // Maps of reflectors that no longer exist (destroyed entities) are dropped.
    std::vector<ProbeHandle> live;
    for (const ProbeJob& job : frame.probes) live.push_back(job.handle);
    std::sort(live.begin(), live.end());
    im.probes->retain(live);
  }
  for (const DrawItem& d : frame.draws)
    if (index(d.mesh) >= assets.meshes.size())
      return Error{"", "draw list", "mesh id " + std::to_string(index(d.mesh)) + " is out of range"};

  // Draw order: sorted by program (variant key), then by material, so program and material
  // state change as rarely as possible. Keys are computed once per draw.
  const VariantKey frame_key = im.supported(frame_variant(frame));
  im.frame_key = frame_key;
  std::vector<VariantKey> keys(frame.draws.size());
  for (std::size_t i = 0; i < frame.draws.size(); ++i)
    keys[i] = material_variant(frame.draws[i]) | frame_key;
  auto material_order = [&](std::uint32_t a, std::uint32_t b) {
    const Material& ma = frame.draws[a].material;
    const Material& mb = frame.draws[b].material;
    return std::tie(ma.base_color_texture, ma.normal_texture, ma.double_sided, ma.metallic,
                    ma.roughness) < std::tie(mb.base_color_texture, mb.normal_texture,
                                             mb.double_sided, mb.metallic, mb.roughness);
  };
  auto sorted_by = [&](Pass pass, const std::vector<VariantKey>& by) {
    std::vector<std::uint32_t> order(frame.draws.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      const VariantKey ka = by[a].filtered_for(pass), kb = by[b].filtered_for(pass);
      if (ka != kb) return ka < kb;
      return material_order(a, b);
    });
    return order;
  };
  stats_.program_switches = stats_.material_switches = 0;
  // Material uniforms and textures for a draw; skipped when equal to the previous draw's.
  const Material* bound_material = nullptr;
  VariantKey bound_key;  // the oracle's feature bits also differ between equal materials
  auto bind_material = [&](GLuint prog, const DrawItem& d, VariantKey key) {
    const Material& m = d.material;
    if (bound_material && *bound_material == m && (!im.oracle || bound_key == key.material()))
      return;
    bound_material = &m;
    bound_key = key.material();
    ++stats_.material_switches;
    const glm::vec4 params(m.metallic, m.roughness, m.normal_scale, m.alpha_cutoff);
    glProgramUniform4fv(prog, kUniBaseColor, 1, &m.base_color[0]);
    glProgramUniform4fv(prog, kUniMaterial, 1, &params[0]);
    glProgramUniform3fv(prog, kUniEmissive, 1, &m.emissive[0]);
    if (im.oracle) glProgramUniform1ui(prog, kUniOracleFeatures, key.material().bits());
    glBindTextureUnit(kTexBaseColor, im.texture(m.base_color_texture, assets, false));
    glBindTextureUnit(kTexNormal, im.texture(m.normal_texture, assets, true));
  };
  auto use_program = [&](Pass pass, VariantKey key, GLuint& current) -> Status {
    auto prog = im.shaders->program(pass, key);
    if (!prog) return prog.error();
    if (prog->id() != current) {
      current = prog->id();
      glUseProgram(current);
      ++stats_.program_switches;
      bound_material = nullptr;  // material uniforms are per program
    }
    return {};
  };

  // A shadow map array the driver refuses (llvmpipe: over 1 GiB, e.g. 16384^2 x 4 cascades) is
  // an error before any pass starts, not a string of GL errors.
  if (shadowed) {
    const ShadowSettings& s = frame.shadow.settings;
    if (!im.shadow_fbo || s.map_size != im.shadow_size || total_layers != im.shadow_layers ||
        s.depth_format != im.shadow_format)
      KASKAD_TRY(check_shadow_map_size(s.map_size, total_layers, s.depth_format));
  }

  // Pass 1: shadow maps (S4, S0 step 6): depth only, one layer per cascade, light viewport, bias
  // by polygon offset, chosen culling. Each layer gets only the casters overlapping its cascade.
  glBeginQuery(GL_TIME_ELAPSED, im.timers[0].id());
  stats_.cascades = cascades;
  stats_.cascade_draw_calls.fill(0);
  stats_.cascade_triangles.fill(0);
  stats_.cascade_texel_size.fill(0.0f);
  stats_.cascade_receiver_pixels.fill(0);
  stats_.shadow_layers_rendered = 0;
  stats_.shadow_layers = 0;
  for (int c = 0; c < cascades; ++c)
    stats_.cascade_texel_size[std::size_t(c)] = frame.shadow.texel_size[std::size_t(c)];
  if (shadowed) {
    const ShadowSettings& s = frame.shadow.settings;
    im.ensure_shadow_map(s.map_size, total_layers, s.depth_format, s.filter);
    glBindFramebuffer(GL_FRAMEBUFFER, im.shadow_fbo.id());
    glViewport(0, 0, s.map_size, s.map_size);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glClearDepth(1.0);
    glEnable(GL_POLYGON_OFFSET_FILL);
    // Paraboloid hemispheres end at a clip distance (shadow_depth.vert).
    const bool paraboloid = frame.shadow.projection == ShadowProjection::dual_paraboloid;
    if (paraboloid) glEnable(GL_CLIP_DISTANCE0);
    const std::vector<std::uint32_t> order = sorted_by(Pass::depth, keys);
    GLuint current = 0;  // kept across layers: the light matrix is a per-draw uniform
    // Layered: every layer attached at once and cleared together (skipped layers stay clear);
    // each caster is drawn once per light, instanced over the layers it overlaps, and the vertex
    // shader routes instance i to the i-th of them (shadow_depth.vert). The same maps as one pass
    // per layer (render test), with fewer draw calls.
    const bool layered = frame_key.has(VariantKey::kShadowLayered);
    // Light 0 is the first shadowed light, 1.. the extra directional ones; each with its own
    // culling, bias and casters per cascade, into consecutive layers.
    auto pass_of = [&](std::size_t light) -> const ShadowPass& {
      return light == 0 ? frame.shadow : *extras[light - 1];
    };
    auto base_of = [&](std::size_t light) { return light == 0 ? 0 : first_layer[light - 1]; };
    auto layers_of = [&](std::size_t light) {
      return light == 0 ? cascades : cascade_layers(pass_of(light));
    };
    auto caster_mask = [&](std::size_t light, const DrawItem& d) -> std::uint32_t {
      if (!d.cast_shadows) return 0;
      return light == 0 ? d.cascade_mask : (d.extra_cascade_masks >> (8 * (light - 1))) & 0xffu;
    };
    // Extra lights are cascades: the plain depth program even after paraboloid maps.
    auto depth_key = [&](std::size_t light, std::uint32_t i) {
      VariantKey k = keys[i];
      if (light > 0) k.set(VariantKey::kShadowProjection, 0);
      return k;
    };
    // Shadow caching (issue 13): a layer keeps last frame's depth when it would be drawn from the
    // same inputs: its matrix (and paraboloid data), bias and culling, pass mode, and the same
    // casters (mesh, model matrix, depth program, alpha-mask parameters) in the same order. A
    // moved caster changes its matrix, a moved camera the layer's matrix or casters; other
    // assets (another scene) change assets.uid. New map storage invalidates every layer.
    auto layer_inputs = [&](std::size_t light, int c) {
      const ShadowPass& pass = pass_of(light);
      InputHash h;
      h.add(assets.uid).add(layered).add(pass.projection).add(pass.settings.cull);
      h.add(pass.settings.slope_bias).add(pass.settings.constant_bias);
      h.add(pass.view_proj[std::size_t(c)]).add(pass.skipped[std::size_t(c)]);
      // Only the paraboloid depth pass reads splits (near, far, margin: shadow_depth.vert).
      if (pass.projection == ShadowProjection::dual_paraboloid) h.add(pass.splits);
      if (pass.skipped[std::size_t(c)]) return h.value();
      for (std::uint32_t i : order) {
        const DrawItem& d = frame.draws[i];
        if (!(caster_mask(light, d) & (1u << c))) continue;
        h.add(d.mesh).add(d.model).add(depth_key(light, i).filtered_for(Pass::depth).bits());
        if (d.material.alpha_mask || im.oracle)
          h.add(d.material.base_color.a).add(d.material.alpha_cutoff)
              .add(d.material.base_color_texture);
      }
      return h.value();
    };
    std::vector<std::uint64_t> inputs(std::size_t(total_layers), 0);
    bool any_dirty = false;
    for (std::size_t light = 0; light <= extras.size(); ++light)
      for (int c = 0; c < layers_of(light); ++c) {
        const std::size_t layer = std::size_t(base_of(light) + c);
        inputs[layer] = layer_inputs(light, c);
        if (inputs[layer] != im.layer_drawn_from[layer]) {
          stats_.shadow_layers_rendered |= 1u << layer;
          any_dirty = true;
        }
      }
    // The layered pass draws every layer at once: it redraws all of them or none.
    if (layered && any_dirty)  // up to 32 layers (4 lights x 8 cascades): no 1u << 32
      stats_.shadow_layers_rendered = ~0u >> (32 - total_layers);
    stats_.shadow_layers = total_layers;
    auto redraw = [&](int layer) { return (stats_.shadow_layers_rendered >> layer) & 1u; };
    if (layered && any_dirty) {
      glNamedFramebufferTexture(im.shadow_fbo.id(), GL_DEPTH_ATTACHMENT, im.shadow_map.id(), 0);
      glClear(GL_DEPTH_BUFFER_BIT);
    }
    // Stats count the casters each layer holds, whether drawn now or kept from an earlier frame.
    for (std::size_t light = 0; light <= extras.size(); ++light) {
      const ShadowPass& pass = pass_of(light);
      const int base = base_of(light);
      const int layers = layers_of(light);
      if (pass.settings.cull == CullMode::none) {
        glDisable(GL_CULL_FACE);
      } else {
        glEnable(GL_CULL_FACE);
        glCullFace(pass.settings.cull == CullMode::front ? GL_FRONT : GL_BACK);
      }
      glPolygonOffset(pass.settings.slope_bias, pass.settings.constant_bias);
      if (light > 0) glDisable(GL_CLIP_DISTANCE0);  // only paraboloid hemispheres clip
      if (layered) {
        std::uint32_t live = 0;
        for (int c = 0; c < layers; ++c)
          if (!pass.skipped[std::size_t(c)]) live |= 1u << c;
        for (std::uint32_t i : order) {
          const DrawItem& d = frame.draws[i];
          const std::uint32_t mask = live & caster_mask(light, d);
          if (mask == 0) continue;
          const GpuMesh& m = im.mesh(d.mesh, assets);
          if (m.index_count == 0) continue;
          const int instances = std::popcount(mask);
          if (any_dirty) {
            if (Status st = use_program(Pass::depth, keys[i], current); !st) {
              glDisable(GL_POLYGON_OFFSET_FILL);
              glEndQuery(GL_TIME_ELAPSED);
              return st;
            }
            if (keys[i].has(VariantKey::kAlphaMask) || im.oracle)
              bind_material(current, d, keys[i]);
            glProgramUniform1ui(current, kUniLayerMask, mask);
            glProgramUniform1i(current, kUniLayerBase, base);
            glProgramUniformMatrix4fv(current, kUniLayerViewProj, layers, GL_FALSE,
                                      &pass.view_proj[0][0][0]);
            glProgramUniformMatrix4fv(current, kUniModel, 1, GL_FALSE, &d.model[0][0]);
            glBindVertexArray(m.vao.id());
            glDrawElementsInstanced(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr,
                                    instances);
          }
          ++stats_.shadow_draw_calls;
          stats_.shadow_triangles += std::size_t(instances) * std::size_t(m.index_count / 3);
          for (int c = 0; light == 0 && c < layers; ++c)
            if (mask & (1u << c)) {
              ++stats_.cascade_draw_calls[std::size_t(c)];
              stats_.cascade_triangles[std::size_t(c)] += std::size_t(m.index_count / 3);
            }
        }
        continue;
      }
      for (int c = 0; c < layers; ++c) {
        const bool draw = redraw(base + c);
        if (draw) {
          glNamedFramebufferTextureLayer(im.shadow_fbo.id(), GL_DEPTH_ATTACHMENT,
                                         im.shadow_map.id(), 0, base + c);
          glClear(GL_DEPTH_BUFFER_BIT);
        }
        if (pass.skipped[std::size_t(c)]) continue;
        const glm::mat4& light_vp = pass.view_proj[std::size_t(c)];
        for (std::uint32_t i : order) {
          const DrawItem& d = frame.draws[i];
          if (!(caster_mask(light, d) & (1u << c))) continue;
          const GpuMesh& m = im.mesh(d.mesh, assets);
          if (m.index_count == 0) continue;
          if (draw) {
            if (Status st = use_program(Pass::depth, depth_key(light, i), current); !st) {
              glDisable(GL_POLYGON_OFFSET_FILL);
              glDisable(GL_CLIP_DISTANCE0);
              glEndQuery(GL_TIME_ELAPSED);
              return st;
            }
            // The oracle's one depth program reads the material bits from a uniform: set it for
            // every draw, or an alpha-masked draw's bits leak into the next layer's opaque draws.
            if (keys[i].has(VariantKey::kAlphaMask) || im.oracle)
              bind_material(current, d, keys[i]);
            glProgramUniformMatrix4fv(current, kUniLightViewProj, 1, GL_FALSE, &light_vp[0][0]);
            glProgramUniformMatrix4fv(current, kUniModel, 1, GL_FALSE, &d.model[0][0]);
            glBindVertexArray(m.vao.id());
            glDrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
          }
          ++stats_.shadow_draw_calls;
          stats_.shadow_triangles += std::size_t(m.index_count / 3);
          if (light == 0) {
            ++stats_.cascade_draw_calls[std::size_t(c)];
            stats_.cascade_triangles[std::size_t(c)] += std::size_t(m.index_count / 3);
          }
        }
      }
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_CLIP_DISTANCE0);
    for (std::size_t layer = 0; layer < inputs.size(); ++layer)
      if (redraw(int(layer))) im.layer_drawn_from[layer] = inputs[layer];
    im.shadow_valid = true;
  }
  glEndQuery(GL_TIME_ELAPSED);

  // Forward draws: the main view and every probe face go through this one path. Draws reflecting
  // a probe get its map (`visible_before`: the map as of before this frame's captures, so a probe
  // never sees a cube that is being captured) and k_s * p_r.
  std::map<ProbeHandle, const ProbeJob*> probe_jobs;
  for (const ProbeJob& job : frame.probes) probe_jobs[job.handle] = &job;
  auto bind_reflection = [&](GLuint prog, const DrawItem& d, VariantKey key, bool capture) {
    if (!key.has(VariantKey::kReflectionCube) && !key.has(VariantKey::kReflectionSphere)) return;
    auto it = probe_jobs.find(d.probe);
    if (it == probe_jobs.end()) return;
    const ProbeJob& job = *it->second;
    const bool swapped_now = job.faces != 0 && job.target == job.visible;
    const int buffer = capture && swapped_now ? 1 - job.visible : job.visible;
    glBindTextureUnit(kTexReflectionCube, im.probes->existing_cube(job.handle, buffer).id());
    glBindTextureUnit(kTexReflectionSphere, im.probes->existing_sphere(job.handle).id());
    glProgramUniform4f(prog, kUniReflection, d.reflection_scale, 0.0f, 0.0f, 0.0f);
    if (key.has(VariantKey::kReflectionBox)) {
      glProgramUniform4f(prog, kUniReflectionBoxMin, job.box_min.x, job.box_min.y, job.box_min.z, 0);
      glProgramUniform4f(prog, kUniReflectionBoxMax, job.box_max.x, job.box_max.y, job.box_max.z, 0);
      glProgramUniform4f(prog, kUniReflectionCentre, job.center.x, job.center.y, job.center.z, 0);
    }
  };
  // `view_proj`: the view drawn (main camera or probe face); draws outside it are culled.
  auto draw_forward = [&](const std::vector<VariantKey>& by, const ProbeJob* capture,
                          const glm::mat4& view_proj) -> Status {
    GLuint current = 0;
    for (std::uint32_t i : sorted_by(Pass::forward, by)) {
      const DrawItem& d = frame.draws[i];
      if (capture && (d.probe == capture->handle ||
                      (capture->exclude_layers & (1u << (d.layer & 31)))))
        continue;  // the reflector itself and excluded layers are not in its probe
      if (outside_clip_volume(view_proj, d.bounds)) {
        ++(capture ? stats_.probe_culled : stats_.frustum_culled);
        continue;
      }
      const GpuMesh& m = im.mesh(d.mesh, assets);
      if (m.index_count == 0) continue;
      KASKAD_TRY(use_program(Pass::forward, by[i], current));
      if (d.material.double_sided) {
        glDisable(GL_CULL_FACE);
      } else {
        glEnable(GL_CULL_FACE);
        glCullFace(GL_BACK);
      }
      bind_material(current, d, by[i]);
      bind_reflection(current, d, by[i], capture != nullptr);
      const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(d.model)));
      glProgramUniformMatrix4fv(current, kUniModel, 1, GL_FALSE, &d.model[0][0]);
      glProgramUniformMatrix3fv(current, kUniNormalMatrix, 1, GL_FALSE, &normal_matrix[0][0]);
      glBindVertexArray(m.vao.id());
      glDrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
      ++stats_.draw_calls;
      stats_.triangles += std::size_t(m.index_count / 3);
    }
    return {};
  };
  if (shadowed) glBindTextureUnit(kTexShadow, im.shadow_map.id());

  // Pass 2: reflection probes (S3): each scheduled face of a probe's back cube is rendered by a
  // 90° camera at the probe centre through the forward path, shadows included, without AOVs and
  // without exposure (the cube holds linear radiance), with cascades selected by map bounds
  // (capture_frame_variant()). u_view stays the main camera's: sphere-map lookups are the main
  // view's. Then mips, then sphere maps.
  stats_.probe_faces = 0;
  stats_.probe_draw_calls = 0;
  stats_.probe_culled = 0;
  stats_.frustum_culled = 0;
  glBeginQuery(GL_TIME_ELAPSED, im.timers[2].id());
  if (!frame.probes.empty()) {
    const VariantKey capture_frame = capture_frame_variant(frame_key);
    std::vector<VariantKey> capture_keys(frame.draws.size());
    for (std::size_t i = 0; i < frame.draws.size(); ++i)
      capture_keys[i] = material_variant(frame.draws[i]) | capture_frame;
    glDisable(GL_FRAMEBUFFER_SRGB);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    for (const ProbeJob& job : frame.probes) {
      if (job.env_map != kNoProbe && job.env_map < assets.env_maps.size()) {
        im.probes->upload(job.handle, job.visible, assets.env_maps[job.env_map]);
        continue;
      }
      if (job.faces == 0) continue;
      im.probes->cube(job.handle, job.target, job.resolution);
      for (int f = 0; f < 6; ++f) {
        if (!(job.faces & (1u << f))) continue;
        FrameBlock face_fb = fb;
        face_fb.view_proj = job.view_proj[std::size_t(f)];
        face_fb.camera_pos = glm::vec4(job.center, 1.0f);
        face_fb.ambient.w = 1.0f;  // linear radiance: exposure applies where the map is shown
        glNamedBufferSubData(im.frame_ubo.id(), 0, sizeof face_fb, &face_fb);
        im.probes->begin_face(job.handle, job.target, f, frame.clear_color);
        const int before = stats_.draw_calls;
        const std::size_t triangles_before = stats_.triangles;
        if (Status st = draw_forward(capture_keys, &job, face_fb.view_proj); !st) {
          glNamedBufferSubData(im.frame_ubo.id(), 0, sizeof fb, &fb);  // the main view's block
          glEndQuery(GL_TIME_ELAPSED);
          return st;
        }
        stats_.probe_draw_calls += stats_.draw_calls - before;
        stats_.draw_calls = before;
        stats_.triangles = triangles_before;
        ++stats_.probe_faces;
      }
      // Complete (the target is now the visible buffer): rebuild its mip chain.
      if (job.target == job.visible) im.probes->finish_cube(job.handle, job.target);
    }
    glNamedBufferSubData(im.frame_ubo.id(), 0, sizeof fb, &fb);
    for (const ProbeJob& job : frame.probes)
      if (job.sphere && im.probes->existing_cube(job.handle, job.visible))
        im.probes->update_sphere(job.handle, job.visible, glm::mat3(frame.camera.view));
  }
  glEndQuery(GL_TIME_ELAPSED);

  // Pass 3: forward shading into colour (+ AOV targets when asked for).
  glBeginQuery(GL_TIME_ELAPSED, im.timers[1].id());
  im.ensure_targets(frame.width, frame.height);
  const GLenum bufs[5] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2,
                          GL_COLOR_ATTACHMENT3, GL_COLOR_ATTACHMENT4};
  glNamedFramebufferDrawBuffers(im.fbo.id(), frame.write_aovs ? 5 : 1, bufs);
  im.aovs_written = frame.write_aovs;
  glBindFramebuffer(GL_FRAMEBUFFER, im.fbo.id());
  glViewport(0, 0, frame.width, frame.height);
  glEnable(GL_FRAMEBUFFER_SRGB);
  const float clear_color[4] = {frame.clear_color.r * frame.exposure,
                                frame.clear_color.g * frame.exposure,
                                frame.clear_color.b * frame.exposure, 1.0f};
  const float zero[4] = {0, 0, 0, 0};
  const float one = 1.0f;
  glClearBufferfv(GL_COLOR, 0, clear_color);
  if (frame.write_aovs) {
    glClearBufferfv(GL_COLOR, 1, zero);
    glClearBufferfv(GL_COLOR, 2, zero);
    glClearBufferfv(GL_COLOR, 3, zero);
    glClearBufferfv(GL_COLOR, 4, zero);
  }
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glClearBufferfv(GL_DEPTH, 0, &one);
  if (Status st = draw_forward(keys, nullptr, fb.view_proj); !st) {
    glDisable(GL_FRAMEBUFFER_SRGB);
    glEndQuery(GL_TIME_ELAPSED);
    return st;
  }
  stats_.shaders = im.shaders->stats();
  glDisable(GL_FRAMEBUFFER_SRGB);
  glEndQuery(GL_TIME_ELAPSED);
  // llvmpipe returns garbage for the very first GL_TIME_ELAPSED queries of a context (seen:
  // 3.4e6 ms), and frame 0 times uploads anyway: results are read from frame 1's queries on.
  im.timers_pending = im.frames_rendered++ > 0;
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return {};
}

Result<std::vector<glm::vec2>> Renderer::shadow_at_points(std::span<const glm::vec3> points,
                                                          std::span<const glm::vec3> normals) {
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
    glTextureStorage2D(im.points_target.id(), 1, GL_RG32F, w, h);
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
  glProgramUniform2i(program->id(), kUniTargetSize, w, h);
  // The frame block and shadow map are still those of the last render(); bind them again in
  // case other GL work ran in between.
  glBindBufferBase(GL_UNIFORM_BUFFER, 0, im.frame_ubo.id());
  glBindTextureUnit(kTexShadow, im.shadow_map.id());
  glBindFramebuffer(GL_FRAMEBUFFER, im.points_fbo.id());
  glViewport(0, 0, w, h);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  const float clear[4] = {1.0f, -1.0f, 0.0f, 0.0f};
  glClearBufferfv(GL_COLOR, 0, clear);
  glBindVertexArray(vao.id());
  glDrawArrays(GL_POINTS, 0, count);
  glBindVertexArray(0);
  std::vector<glm::vec2> out(std::size_t(w) * h);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(im.points_target.id(), 0, GL_RG, GL_FLOAT,
                    GLsizei(out.size() * sizeof(glm::vec2)), out.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glEnable(GL_DEPTH_TEST);
  out.resize(std::size_t(count));
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
  const Impl& im = *impl_;
  Image img;
  img.width = im.width;
  img.height = im.height;
  img.channels = 4;
  img.channel_names = {"R", "G", "B", "A"};
  // The sRGB target stores encoded values; reading as GL_RGBA/GL_FLOAT returns them unconverted
  // only for non-sRGB formats, so read bytes instead.
  std::vector<std::uint8_t> bytes(std::size_t(im.width) * im.height * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(im.color.id(), 0, GL_RGBA, GL_UNSIGNED_BYTE, GLsizei(bytes.size()),
                    bytes.data());
  img.pixels.resize(bytes.size());
  const std::size_t row = std::size_t(im.width) * 4;
  for (int y = 0; y < im.height; ++y)
    for (std::size_t i = 0; i < row; ++i)
      img.pixels[std::size_t(y) * row + i] = bytes[std::size_t(im.height - 1 - y) * row + i] / 255.0f;
  return img;
}

Image Renderer::read_aovs() const {
  const Impl& im = *impl_;
  KASKAD_CHECK(im.aovs_written, "the last frame was rendered without write_aovs");
  const int w = im.width, h = im.height;
  const auto pos = read_texture(im.position.id(), w, h, GL_RGBA, 4);
  const auto nrm = read_texture(im.normal.id(), w, h, GL_RGBA, 4);
  const auto vis = read_texture(im.visibility.id(), w, h, GL_RG, 2);
  Image img;
  img.width = w;
  img.height = h;
  const auto refl = read_texture(im.reflection.id(), w, h, GL_RGBA, 4);
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
  const Impl& im = *impl_;
  KASKAD_CHECK(im.aovs_written, "the last frame was rendered without write_aovs");
  std::array<std::size_t, kMaxCascades> out{};
  const auto vis = read_texture(im.visibility.id(), im.width, im.height, GL_RG, 2);
  const auto pos = read_texture(im.position.id(), im.width, im.height, GL_RGBA, 4);
  for (std::size_t i = 0; i < vis.size() / 2; ++i) {
    if (pos[i * 4 + 3] != 1.0f) continue;  // AOV mask: only shadow-receiving surfaces count
    const int c = int(vis[i * 2 + 1]);
    if (c >= 0 && c < kMaxCascades) ++out[std::size_t(c)];
  }
  return out;
}

Image Renderer::read_shadow_map() const {
  const Impl& im = *impl_;
  Image img;
  img.width = im.shadow_size;
  img.height = im.shadow_size * im.shadow_layers;
  img.channels = 1;
  img.channel_names = {"Y"};
  // All layers in one read; read_texture flips the whole stack, so flip the layer order back.
  const std::size_t layer = std::size_t(im.shadow_size) * im.shadow_size;
  const auto stack = read_texture(im.shadow_map.id(), im.shadow_size, img.height,
                                  GL_DEPTH_COMPONENT, 1);
  img.pixels.resize(stack.size());
  for (int l = 0; l < im.shadow_layers; ++l)
    std::memcpy(&img.pixels[std::size_t(l) * layer],
                &stack[std::size_t(im.shadow_layers - 1 - l) * layer], layer * sizeof(float));
  return img;
}

CubeMap Renderer::read_probe_cube(ProbeHandle handle, int buffer) const {
  return impl_->probes->read_cube(handle, buffer);
}

SphereMap Renderer::read_probe_sphere(ProbeHandle handle) const {
  return impl_->probes->read_sphere(handle);
}

void Renderer::present(int window_width, int window_height) const {
  const Impl& im = *impl_;
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glNamedFramebufferReadBuffer(im.fbo.id(), GL_COLOR_ATTACHMENT0);
  glBlitNamedFramebuffer(im.fbo.id(), 0, 0, 0, im.width, im.height, 0, 0, window_width,
                         window_height, GL_COLOR_BUFFER_BIT, GL_LINEAR);
}

}  // namespace kaskad::render
