#include "runtime/render/passes.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <map>
#include <type_traits>

#include "components/bounds.h"
#include "runtime/core/log.h"
#include "runtime/render/input_hash.h"
#include "runtime/render/renderer.h"

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

// The instance record of a depth draw: shadow_depth.vert reads the model matrix and the layer
// (the layered pass's) only, so no normal matrix is computed (one per caster and layer).
InstanceRecord depth_instance_of(const glm::mat4& model, std::uint32_t layer) {
  InstanceRecord r;
  r.model = model;
  r.layer = glm::uvec4(layer, 0, 0, 0);
  return r;
}

GLenum depth_internal_format(DepthFormat f) {
  switch (f) {
    case DepthFormat::d16: return GL_DEPTH_COMPONENT16;
    case DepthFormat::d32f: return GL_DEPTH_COMPONENT32F;
    case DepthFormat::d24: break;
  }
  return GL_DEPTH_COMPONENT24;
}

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

// The layers of view `v` that draw `d` (bit c: layer first_layer + c).
std::uint32_t caster_mask(const ShadowView& v, const DrawItem& d) {
  if (!d.cast_shadows) return 0;
  return (d.shadow_layers >> v.first_layer) & (~0u >> (32 - v.layer_count));
}

// Triangles of a mesh as the passes draw it.
std::size_t triangles(const AssetStore& assets, MeshId id) {
  return assets.meshes[index(id)].indices.size() / 3;
}

// Slices 0, step, 2 step, ... (`slices` of them) of a 2D array texture as one image, the first
// slice first, rows top to bottom within each (GL's bottom-to-top rows flipped), in the channels
// `format` reads (GL_DEPTH_COMPONENT, GL_RED, GL_RG, GL_RGBA), named `names`:
// ShadowMapPass::read(), LomPass's and MomentsPass::read(). No texture: an empty stack.
Image read_slices(const gpu::Texture& t, GLenum format, std::vector<std::string> names, int size,
                  int slices, int step = 1) {
  Image img;
  img.width = size;
  img.height = size * slices;
  img.channels = int(names.size());
  img.channel_names = std::move(names);
  if (!t) return img;
  const std::size_t row = std::size_t(size) * std::size_t(img.channels);
  const std::size_t layer = row * std::size_t(size);
  std::vector<float> stack(layer * std::size_t(slices));
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  if (step == 1) {
    glGetTextureImage(t.id(), 0, format, GL_FLOAT, GLsizei(stack.size() * sizeof(float)),
                      stack.data());
  } else {
    for (int l = 0; l < slices; ++l)
      glGetTextureSubImage(t.id(), 0, 0, 0, l * step, size, size, 1, format, GL_FLOAT,
                           GLsizei(layer * sizeof(float)), &stack[std::size_t(l) * layer]);
  }
  img.pixels.resize(stack.size());
  for (int l = 0; l < slices; ++l)
    for (int y = 0; y < size; ++y)
      std::memcpy(&img.pixels[std::size_t(l) * layer + std::size_t(y) * row],
                  &stack[std::size_t(l) * layer + std::size_t(size - 1 - y) * row],
                  row * sizeof(float));
  return img;
}

}  // namespace

// ---- DrawState ----------------------------------------------------------------------------------

DrawState::DrawState(ShaderLibrary& shaders, GpuCache& cache, FrameStats& stats)
    : shaders_(shaders),
      cache_(cache),
      stats_(stats),
      features_by_uniform_(shaders.features_by_uniform()) {}

Status DrawState::use_program(Pass pass, VariantKey key) {
  auto prog = shaders_.program(pass, key);
  if (!prog) return prog.error();
  if (*prog != program_) {
    program_ = *prog;
    glUseProgram(program_.id());
    ++stats_.program_switches;
    material_ = nullptr;  // material uniforms are per program
  }
  return {};
}

void DrawState::bind_material(const DrawItem& d, VariantKey key) {
  const Material& m = d.material;
  // Über-programs read the feature bits from a uniform: equal materials differ by their keys.
  if (material_ && *material_ == m && (!features_by_uniform_ || material_key_ == key.material()))
    return;
  material_ = &m;
  material_key_ = key.material();
  ++stats_.material_switches;
  const glm::vec4 params(m.metallic, m.roughness, m.normal_scale, m.alpha_cutoff);
  glProgramUniform4fv(program_.id(), kLocBaseColor, 1, &m.base_color[0]);
  glProgramUniform4fv(program_.id(), kLocMaterial, 1, &params[0]);
  glProgramUniform3fv(program_.id(), kLocEmissive, 1, &m.emissive[0]);
  if (features_by_uniform_) glProgramUniform1ui(program_.id(), kLocFeatureBits, GLuint(key.material().bits()));
  glBindTextureUnit(kTexBaseColor, cache_.texture(m.base_color_texture, false).id());
  glBindTextureUnit(kTexNormal, cache_.texture(m.normal_texture, true).id());
  // The optional features' uniforms exist only in programs compiled with them (elsewhere their
  // location is an error or another uniform's): set them where `key` (the key the current
  // program was compiled for, as far as material features go) has the feature.
  const VariantKey features = key.material();
  if (features.has(VariantKey::kOcclusionTexture) || features_by_uniform_) {
    const glm::vec4 extra(m.occlusion_strength, 0.0f, 0.0f, 0.0f);
    glProgramUniform4fv(program_.id(), kLocMaterialExtra, 1, &extra[0]);
    glBindTextureUnit(kTexOcclusion, cache_.texture(m.occlusion_texture, false).id());
  }
  if (features.has(VariantKey::kEmissiveTexture) || features_by_uniform_)
    glBindTextureUnit(kTexEmissive, cache_.texture(m.emissive_texture, false).id());
  if (features.has(VariantKey::kMetallicRoughnessTexture) || features_by_uniform_)
    glBindTextureUnit(kTexMetallicRoughness,
                      cache_.texture(m.metallic_roughness_texture, false).id());
  if (features.has(VariantKey::kTextureTransform) || features_by_uniform_) {
    std::array<glm::vec4, 2 * kUvSlotCount> rows{};
    const TextureTransform* slots[kUvSlotCount] = {};
    slots[kUvSlotBaseColor] = &m.base_color_transform;
    slots[kUvSlotNormal] = &m.normal_transform;
    slots[kUvSlotOcclusion] = &m.occlusion_transform;
    slots[kUvSlotEmissive] = &m.emissive_transform;
    slots[kUvSlotMetallicRoughness] = &m.metallic_roughness_transform;
    for (int i = 0; i < kUvSlotCount; ++i) {
      const auto r = uv_transform_rows(*slots[i]);
      rows[std::size_t(2 * i)] = glm::vec4(r[0], 0.0f);
      rows[std::size_t(2 * i + 1)] = glm::vec4(r[1], 0.0f);
    }
    glProgramUniform4fv(program_.id(), kLocUvTransform, GLsizei(rows.size()), &rows[0][0]);
  }
}

bool DrawState::depth_reads_material(VariantKey key) const {
  return key.has(VariantKey::kAlphaMask) || features_by_uniform_;
}

// ---- ShadowMapPass ------------------------------------------------------------------------------

void ShadowMapPass::ensure_storage(int size, int layers, DepthFormat format, ShadowFilter filter) {
  if (fbo_ && size == size_ && layers == layers_ && format == format_ && filter == filter_) return;
  if (!fbo_ || size != size_ || layers != layers_ || format != format_) {
    size_ = size;
    layers_ = layers;
    format_ = format;
    map_ = gpu::make_texture(GL_TEXTURE_2D_ARRAY);
    glTextureStorage3D(map_.id(), 1, depth_internal_format(format), size, size, layers);
    // S4: clamp to border with border depth 1, so lookups outside the map compare as lit.
    glTextureParameteri(map_.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
    glTextureParameteri(map_.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
    const float border[4] = {1.0f, 1.0f, 1.0f, 1.0f};
    glTextureParameterfv(map_.id(), GL_TEXTURE_BORDER_COLOR, border);
    glTextureParameteri(map_.id(), GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTextureParameteri(map_.id(), GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    drawn_from_.assign(std::size_t(layers), 0);  // new storage: nothing to keep
    drawn_rect_.assign(std::size_t(layers), glm::ivec4(0));
    origin_.assign(std::size_t(layers), glm::ivec2(0));
    drawn_matrix_.assign(std::size_t(layers), glm::mat4(0.0f));
    drawn_fixed_.assign(std::size_t(layers), 0);
    drawn_casters_.assign(std::size_t(layers), {});
    wrapped_ = false;
    fbo_ = gpu::make_framebuffer();
    glNamedFramebufferTextureLayer(fbo_.id(), GL_DEPTH_ATTACHMENT, map_.id(), 0, 0);
    glNamedFramebufferDrawBuffer(fbo_.id(), GL_NONE);
    glNamedFramebufferReadBuffer(fbo_.id(), GL_NONE);
  }
  filter_ = filter;
  const GLint f = filter == ShadowFilter::bilinear ? GL_LINEAR : GL_NEAREST;
  glTextureParameteri(map_.id(), GL_TEXTURE_MIN_FILTER, f);
  glTextureParameteri(map_.id(), GL_TEXTURE_MAG_FILTER, f);
}

namespace {

// A sampler of shadow data with border 1, as the map itself (S4): outside it every compare is
// lit, every raw depth 1 (LOM: nothing stored). `compare`: depth compare LEQUAL, else none.
gpu::Sampler border_sampler(bool compare, GLint filter) {
  gpu::Sampler s = gpu::make_sampler();
  const GLuint id = s.id();
  glSamplerParameteri(id, GL_TEXTURE_COMPARE_MODE, compare ? GL_COMPARE_REF_TO_TEXTURE : GL_NONE);
  glSamplerParameteri(id, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  glSamplerParameteri(id, GL_TEXTURE_MIN_FILTER, filter);
  glSamplerParameteri(id, GL_TEXTURE_MAG_FILTER, filter);
  glSamplerParameteri(id, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
  glSamplerParameteri(id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
  const float border[4] = {1.0f, 1.0f, 1.0f, 1.0f};
  glSamplerParameterfv(id, GL_TEXTURE_BORDER_COLOR, border);
  return s;
}

}  // namespace

void ShadowMapPass::bind() {
  const gpu::TextureRef map = texture();
  if (!raw_depth_) raw_depth_ = border_sampler(false, GL_NEAREST);
  if (!linear_compare_) linear_compare_ = border_sampler(true, GL_LINEAR);
  glBindTextureUnit(kTexShadow, map.id());
  glBindTextureUnit(kTexShadowDepth, map.id());
  glBindSampler(kTexShadowDepth, raw_depth_.id());
  glBindTextureUnit(kTexShadowLinear, map.id());
  glBindSampler(kTexShadowLinear, linear_compare_.id());
}

gpu::TextureRef ShadowMapPass::texture() {
  if (!fbo_) ensure_storage(64, 1, DepthFormat::d24, ShadowFilter::none);
  return map_;
}

namespace {

// The texels of a layer of `size`^2 that cover the NDC rectangle `ndc` (min x, min y, max x,
// max y) as (x0, y0, x1, y1), ends exclusive; (0, 0, 0, 0) when it is empty.
glm::ivec4 texel_rect(const glm::vec4& ndc, int size) {
  if (!(ndc.x <= ndc.z && ndc.y <= ndc.w)) return glm::ivec4(0);
  auto texel = [size](float v, bool up) {
    const float t = (v + 1.0f) * 0.5f * float(size);
    return std::clamp(int(up ? std::ceil(t) : std::floor(t)), 0, size);
  };
  return {texel(ndc.x, false), texel(ndc.y, false), texel(ndc.z, true), texel(ndc.w, true)};
}

bool empty_rect(const glm::ivec4& r) { return r.x >= r.z || r.y >= r.w; }

// Whether `inner` lies in `outer` (an empty one lies anywhere).
bool holds(const glm::ivec4& outer, const glm::ivec4& inner) {
  return empty_rect(inner) || (outer.x <= inner.x && outer.y <= inner.y && outer.z >= inner.z &&
                               outer.w >= inner.w);
}

// The NDC rectangle (x0, y0, x1, y1) of texels `r` of a layer of `size`^2, two texels wider on
// each side: casters are tested against it, as the rectangle is whole texels and the
// rasteriser's coverage rules are its own.
glm::vec4 drawn_ndc(const glm::ivec4& r, int size) {
  const float texel = 2.0f / float(size);
  return glm::vec4(r) * texel - 1.0f + glm::vec4(-2, -2, 2, 2) * texel;
}

// Whether `box`, through the affine (ortho) light matrix `light_vp`, misses NDC rectangle `ndc`.
bool box_misses(const Aabb& box, const glm::mat4& light_vp, const glm::vec4& ndc) {
  const Aabb b = box.transformed(light_vp);
  return b.max.x < ndc.x || b.min.x > ndc.z || b.max.y < ndc.y || b.min.y > ndc.w;
}

// `r` moved by `shift` texels and cut to a layer of `size`^2.
glm::ivec4 shifted(const glm::ivec4& r, glm::ivec2 shift, int size) {
  if (empty_rect(r)) return glm::ivec4(0);
  const glm::ivec4 moved = glm::clamp(r + glm::ivec4(shift, shift), glm::ivec4(0), glm::ivec4(size));
  return empty_rect(moved) ? glm::ivec4(0) : moved;
}

// The texels of `r` outside `kept`: up to four rectangles (below, above, left and right of it).
std::vector<glm::ivec4> outside(const glm::ivec4& r, const glm::ivec4& kept) {
  if (empty_rect(r)) return {};
  const glm::ivec4 k(std::max(r.x, kept.x), std::max(r.y, kept.y), std::min(r.z, kept.z),
                     std::min(r.w, kept.w));
  if (empty_rect(kept) || empty_rect(k)) return {r};
  std::vector<glm::ivec4> out;
  if (r.y < k.y) out.push_back({r.x, r.y, r.z, k.y});
  if (k.w < r.w) out.push_back({r.x, k.w, r.z, r.w});
  if (r.x < k.x) out.push_back({r.x, k.y, k.x, k.w});
  if (k.z < r.z) out.push_back({k.z, k.y, r.z, k.w});
  return out;
}

// Whether ortho matrix `now` is `before` moved by whole texels of a layer of `size`^2 (every
// entry the same but the x and y translation), and by how many: a fixed point's map texel moves
// by `shift`.
bool moved_by_texels(const glm::mat4& before, const glm::mat4& now, int size, glm::ivec2& shift) {
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 4; ++row)
      if ((col != 3 || row > 1) && before[col][row] != now[col][row]) return false;
  for (int a = 0; a < 2; ++a) {
    const double texels = (double(now[3][a]) - double(before[3][a])) * 0.5 * size;
    const double whole = std::round(texels);
    if (!(std::abs(texels - whole) < 1e-3 && std::abs(whole) < size)) return false;
    shift[a] = int(whole);
  }
  return true;
}

// Whether this frame's lookups can read a scrolled layer: through its matrix with the origin
// added (FrameBlock), at coordinates that may wrap. The plain lookups (pcf, filter none,
// bilinear, 3x3) select cascades by depth and read only around the point; cascades selected by
// map bounds, the wide kernels, PCSS, LOM and the moments read or derive from the maps in ways
// that do not wrap.
bool lookups_can_wrap(const VariantKey& frame_key) {
  const bool wide = frame_key.get(VariantKey::kShadowFilter) == 2 &&
                    frame_key.get(VariantKey::kShadowKernel) != 0;
  return frame_key.get(VariantKey::kCascadeSelection) == 0 &&
         shadow_technique_of(frame_key).may_wrap && !wide;
}

// The texture rectangles of map rectangle `r` in a layer whose texture holds map texel x at
// (x + origin) mod size (origin in [0, size)): up to two pieces per axis, each within one wrap.
template <typename Piece>
void add_pieces(const glm::ivec4& r, glm::ivec2 origin, int size, std::vector<Piece>& out) {
  if (empty_rect(r)) return;
  // Per axis: [lo, hi) of the unwrapped texture in [0, 2 size), cut at size.
  auto parts = [size](int lo, int hi, int o) {
    std::array<glm::ivec3, 2> p{};  // texture x0, x1, viewport
    int n = 0;
    if (lo + o < size) p[std::size_t(n++)] = {lo + o, std::min(hi + o, size), o};
    if (hi + o > size) p[std::size_t(n++)] = {std::max(lo + o, size) - size, hi + o - size, o - size};
    return std::pair(p, n);
  };
  const auto [xs, nx] = parts(r.x, r.z, origin.x);
  const auto [ys, ny] = parts(r.y, r.w, origin.y);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      const glm::ivec3 x = xs[std::size_t(i)], y = ys[std::size_t(j)];
      out.push_back({glm::ivec4(x.x, y.x, x.y, y.y), glm::ivec2(x.z, y.z)});
    }
}

}  // namespace

Status ShadowMapPass::prepare(const FrameInput& frame, const DrawList& list,
                              const AssetStore& assets, bool layered, bool features_by_uniform,
                              int shader_reloads, FrameStats& stats) {
  const std::vector<ShadowView>& views = frame.shadow_views;
  const ShadowSettings& map = frame.shadow_settings;
  const int total = views.empty() ? 0 : views.back().first_layer + views.back().layer_count;
  stats.layer_casters.fill(0);
  stats.layer_triangles.fill(0);
  stats.layer_texel_size.fill(0.0f);
  stats.layer_rect.fill(glm::ivec4(0));
  stats.shadow_layers = total;
  stats.shadow_layers_rendered = 0;
  stats.shadow_rect_culled = 0;
  stats.shadow_layers_scrolled = 0;
  stats.shadow_texels_drawn = 0;
  stats.shadow_draw_calls = stats.shadow_mesh_draws = 0;
  stats.shadow_instances = 0;
  stats.shadow_triangles = 0;
  redraw_ = 0;
  layered_ = layered;
  if (views.empty()) return {};
  // A shadow map array the driver refuses (llvmpipe: over 1 GiB, e.g. 16384^2 x 4 cascades) is
  // an error before any pass starts, not a string of GL errors.
  if (!fbo_ || map.map_size != size_ || total != layers_ || map.depth_format != format_)
    KASKAD_TRY(check_shadow_map_size(map.map_size, total, map.depth_format));
  ensure_storage(map.map_size, total, map.depth_format, map.filter);

  // A layer's inputs: its matrix (and paraboloid data), bias and culling, pass mode, and the
  // casters (mesh, model matrix, depth program, alpha-mask parameters) in order. A moved caster
  // changes its matrix, a moved camera the layer's matrix or casters; other assets (another
  // scene) change assets.uid. New storage invalidated every layer.
  auto add_caster = [&](InputHash& h, std::size_t view, std::uint32_t i) {
    const DrawItem& d = frame.draws[i];
    const VariantKey key = list.depth_key(view, i);
    h.add(d.mesh).add(d.model).add(key.filtered_for(Pass::depth).bits());
    if (key.has(VariantKey::kAlphaMask) || features_by_uniform)
      h.add(d.material.base_color.a)
          .add(d.material.alpha_cutoff)
          .add(d.material.base_color_texture)
          .add(d.material.base_color_transform);
  };
  auto add_pass = [&](InputHash& h, const ShadowView& v) {
    h.add(assets.uid).add(shader_reloads).add(layered).add(v.projection).add(v.cull);
    h.add(v.slope_bias).add(v.constant_bias);
  };
  // Every caster of the view: one hash each (caster_ids, by draw, made once per view by
  // view_casters()) and one of them all.
  std::vector<std::uint64_t> caster_ids;
  auto view_casters = [&](std::size_t view) {
    caster_ids.assign(frame.draws.size(), 0);
    InputHash all;
    for (std::uint32_t i : list.depth_order)
      if (frame.draws[i].cast_shadows) {
        InputHash one;
        add_caster(one, view, i);
        caster_ids[i] = one.value();
        all.add(caster_ids[i]);
      }
    return all.value();
  };
  auto layer_inputs = [&](std::size_t view, int c) {
    const ShadowView& v = views[view];
    InputHash h;
    add_pass(h, v);
    h.add(v.view_proj[std::size_t(c)]).add(v.skipped[std::size_t(c)]);
    // Only the paraboloid depth pass reads splits (near, far) and the margin (shadow_depth.vert).
    if (v.projection == ShadowProjection::dual_paraboloid) h.add(v.splits).add(v.paraboloid_margin);
    if (v.skipped[std::size_t(c)]) return h.value();
    for (std::uint32_t i : list.depth_order)
      if (caster_mask(v, frame.draws[i]) & (1u << c)) h.add(caster_ids[i]);
    return h.value();
  };
  // What a scrolled layer's kept texels were drawn from, but its translation: the pass, the
  // matrix without its x and y translation, and every caster of the view wherever it lies (a
  // caster that moved anywhere redraws the layer whole).
  auto fixed_inputs = [&](std::size_t view, int c, std::uint64_t casters) {
    const ShadowView& v = views[view];
    glm::mat4 m = v.view_proj[std::size_t(c)];
    m[3][0] = m[3][1] = 0.0f;
    InputHash h;
    add_pass(h, v);
    h.add(m).add(casters);
    return h.value();
  };
  // The casters layer c of the view holds (its caster_mask), sorted: a layer that keeps texels
  // must have held every caster that falls on them.
  auto layer_casters = [&](const ShadowView& v, int c, std::vector<std::uint64_t>& out) {
    out.clear();
    for (std::uint32_t i : list.depth_order)
      if (caster_mask(v, frame.draws[i]) & (1u << c)) out.push_back(caster_ids[i]);
    std::sort(out.begin(), out.end());
  };
  // Whether a caster of layer c that the layer did not hold when drawn (as can happen without
  // any caster moving: shadow.cull_by_receivers assigns casters by the receivers the slice
  // serves) reaches the texels `kept` (two texels wider, as in caster_runs()).
  // `now` is the layer's casters (layer_casters()), sorted like the ones it was drawn with: the
  // newcomers, the hashes in `now` that `before` does not hold at all, come from one merge.
  auto newcomer_over = [&](const ShadowView& v, int c, std::size_t layer, const glm::ivec4& kept,
                           const std::vector<std::uint64_t>& now) {
    if (empty_rect(kept)) return false;
    const std::vector<std::uint64_t>& before = drawn_casters_[layer];
    std::vector<std::uint64_t> joined;
    auto b = before.begin();
    for (std::uint64_t id : now) {
      while (b != before.end() && *b < id) ++b;
      if ((b == before.end() || *b != id) && (joined.empty() || joined.back() != id))
        joined.push_back(id);
    }
    if (joined.empty()) return false;
    const glm::vec4 ndc = drawn_ndc(kept, map.map_size);
    for (std::uint32_t i : list.depth_order) {
      const DrawItem& d = frame.draws[i];
      if (!(caster_mask(v, d) & (1u << c)) ||
          !std::binary_search(joined.begin(), joined.end(), caster_ids[i]))
        continue;
      if (d.bounds.empty() || !box_misses(d.bounds, v.view_proj[std::size_t(c)], ndc)) return true;
    }
    return false;
  };
  // The texels each layer needs: its read rectangle, or all of it when a pass that reads
  // anywhere in the maps runs this frame (a probe face selects cascades by map bounds; the
  // layered pass draws every layer through one viewport). A layer is kept when it was drawn
  // over at least those texels and its inputs are unchanged or it is held (ShadowView::held).
  const bool whole = layered || std::any_of(frame.probes.begin(), frame.probes.end(),
                                            [](const ProbeJob& p) { return p.faces != 0; });
  // Scrolling (render.shadow_scroll): a layer to be redrawn whose matrix only moved by whole
  // texels, and whose other inputs (fixed_inputs) are those it was drawn from, keeps its texture
  // and moves its origin the other way; only its read rectangle's texels outside what it held
  // are cleared and drawn. Where scrolling does not apply, a layer's origin returns to 0 (and
  // the layer is redrawn) so that lookups read it through its own matrix.
  const bool scroll =
      frame.shadow_cache && frame.shadow_scroll && !whole && lookups_can_wrap(list.frame_key);
  inputs_.assign(std::size_t(total), 0);
  fixed_.assign(std::size_t(total), 0);
  casters_.assign(std::size_t(total), {});
  rects_.assign(std::size_t(total), glm::ivec4(0, 0, map.map_size, map.map_size));
  pieces_.assign(std::size_t(total), {});
  std::uint32_t drawn_now = 0;  // layers with texels to draw
  for (std::size_t view = 0; view < views.size(); ++view) {
    const ShadowView& v = views[view];
    const bool scrolls = scroll && v.projection == ShadowProjection::ortho;
    // What a later frame needs to scroll a layer drawn now (also by a frame that cannot scroll,
    // such as a probe capture's, which draws whole layers at origin 0).
    const bool tracks = frame.shadow_cache && frame.shadow_scroll && !layered &&
                        v.projection == ShadowProjection::ortho;
    const std::uint64_t casters = view_casters(view);
    for (int c = 0; c < v.layer_count; ++c) {
      const std::size_t layer = std::size_t(v.first_layer + c);
      const bool skipped = v.skipped[std::size_t(c)];
      inputs_[layer] = layer_inputs(view, c);
      if (!whole && !skipped) rects_[layer] = texel_rect(v.read_rect[std::size_t(c)], map.map_size);
      const bool drawn = drawn_from_[layer] != 0 && holds(drawn_rect_[layer], rects_[layer]);
      const bool held = ((v.held >> c) & 1u) != 0;
      const bool keep =
          frame.shadow_cache && drawn && (inputs_[layer] == drawn_from_[layer] || held);
      std::vector<Piece>& pieces = pieces_[layer];
      if (!scrolls || skipped) {
        if (keep && origin_[layer] == glm::ivec2(0)) continue;
        origin_[layer] = glm::ivec2(0);
        if (tracks && !skipped) {
          fixed_[layer] = fixed_inputs(view, c, casters);
          layer_casters(v, c, casters_[layer]);
        }
        add_pieces(rects_[layer], origin_[layer], map.map_size, pieces);
        redraw_ |= 1u << layer;
        drawn_now |= 1u << layer;
        continue;
      }
      if (keep) continue;
      fixed_[layer] = fixed_inputs(view, c, casters);
      layer_casters(v, c, casters_[layer]);
      std::vector<glm::ivec4> regions{rects_[layer]};
      glm::ivec2 shift(0);
      if (drawn_from_[layer] != 0 && drawn_fixed_[layer] == fixed_[layer] &&
          moved_by_texels(drawn_matrix_[layer], v.view_proj[std::size_t(c)], map.map_size, shift)) {
        const glm::ivec4 kept = shifted(drawn_rect_[layer], shift, map.map_size);
        if (!newcomer_over(v, c, layer, kept, casters_[layer])) {
          origin_[layer] = ((origin_[layer] - shift) % map.map_size + map.map_size) % map.map_size;
          regions = outside(rects_[layer], kept);
          stats.shadow_layers_scrolled |= 1u << layer;
        }
      }
      for (const glm::ivec4& r : regions) add_pieces(r, origin_[layer], map.map_size, pieces);
      redraw_ |= 1u << layer;
      if (!pieces.empty()) drawn_now |= 1u << layer;
    }
  }
  // The layered pass draws every layer at once: it redraws all of them or none.
  if (layered && redraw_ != 0) redraw_ = drawn_now = ~0u >> (32 - total);  // total <= 32
  stats.shadow_layers_rendered = drawn_now;
  if (layered) {
    stats.shadow_texels_drawn = std::int64_t(std::popcount(drawn_now)) * map.map_size * map.map_size;
  } else {
    for (const std::vector<Piece>& pieces : pieces_)
      for (const Piece& p : pieces)
        stats.shadow_texels_drawn +=
            std::int64_t(p.texture.z - p.texture.x) * (p.texture.w - p.texture.y);
  }
  // Lookups wrap while any layer is scrolled; otherwise the border (depth 1) lies outside.
  const bool wrap = std::any_of(origin_.begin(), origin_.end(),
                                [](glm::ivec2 o) { return o != glm::ivec2(0); });
  if (wrap != wrapped_) {
    const GLint mode = wrap ? GL_REPEAT : GL_CLAMP_TO_BORDER;
    glTextureParameteri(map_.id(), GL_TEXTURE_WRAP_S, mode);
    glTextureParameteri(map_.id(), GL_TEXTURE_WRAP_T, mode);
    wrapped_ = wrap;
  }

  // Stats: the casters each layer holds, whether drawn now or kept from an earlier frame (the
  // draw calls are counted as they are recorded).
  for (const ShadowView& v : views) {
    std::uint32_t live = 0;
    for (int c = 0; c < v.layer_count; ++c)
      if (!v.skipped[std::size_t(c)]) live |= 1u << c;
    for (std::uint32_t i : list.depth_order) {
      const DrawItem& d = frame.draws[i];
      const std::uint32_t mask = live & caster_mask(v, d);
      const std::size_t tris = triangles(assets, d.mesh);
      if (mask == 0 || tris == 0) continue;
      stats.shadow_instances += std::popcount(mask);
      stats.shadow_triangles += std::size_t(std::popcount(mask)) * tris;
      for (int c = 0; c < v.layer_count; ++c)
        if (mask & (1u << c)) {
          ++stats.layer_casters[std::size_t(v.first_layer + c)];
          stats.layer_triangles[std::size_t(v.first_layer + c)] += tris;
        }
    }
  }
  for (const ShadowView& v : views)
    for (int c = 0; c < v.layer_count; ++c)
      stats.layer_texel_size[std::size_t(v.first_layer + c)] = v.texel_size[std::size_t(c)];
  for (int l = 0; l < total; ++l) stats.layer_rect[std::size_t(l)] = rects_[std::size_t(l)];
  return {};
}

namespace {

// Draws `batch` (draws of one program, material and winding) as one multi-draw, or with
// render.multi_draw off one call per mesh, counting both.
void draw_batch(const FrameInput& frame, GpuCache& cache, std::span<const MeshDraw> batch,
                int& calls, int& mesh_draws) {
  mesh_draws += int(batch.size());
  if (frame.multi_draw) {
    cache.draw_batch(batch);
    calls += batch.empty() ? 0 : 1;
    return;
  }
  for (const MeshDraw& d : batch) cache.draw_batch({&d, 1});
  calls += int(batch.size());
}

// Casters of one shadow view drawn by one instanced draw: draw list entry `draw` gives the mesh,
// program and material; records first .. first + count - 1 the instances. Consecutive runs with
// the same program, material (where it reads one) and winding are one batch (one multi-draw).
struct CasterRun {
  std::uint32_t draw;
  std::size_t first, count;
  bool mirrored;      ///< the casters' transforms mirror (negative determinant): reversed winding
  bool starts_batch;  ///< its program, material or winding differs from the run before's
};

// Draws of view `view` as instanced runs that share a draw (same mesh and depth program, and
// the same material where the depth program reads it), in depth order, marked where a batch
// starts. `mask_of(i)`: the layers of the view (bit c) draw i goes to; `record_of(i, c)`: its
// instance record in layer c. The records go to `records`, one per draw and layer.
// The depth program's key of draw i in view `view`; `peel`: a LomPass depth peel (one layer per
// pass, never the layered program).
VariantKey depth_program_key(const DrawList& list, std::size_t view, std::uint32_t i, bool peel) {
  VariantKey k = list.depth_key(view, i);
  if (peel) k.set(VariantKey::kShadowPeel, 1).set(VariantKey::kShadowLayered, 0);
  return k;
}

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

// The casters of view `view` in `layers` (bit c: layer c of the view; a caster goes to the layers
// of its mask in `layers`), their instance records carrying the layer when `per_layer` (the
// layered pass).
// With `rect` (one layer drawn over part of it, ortho: x0, y0, x1, y1 in NDC through `light_vp`),
// casters whose box lies outside it are left out (counted in `rect_culled`): they would write only
// texels no lookup reads, and on a software rasteriser each costs its vertices and set-up.
std::vector<CasterRun> caster_runs(const FrameInput& frame, const DrawList& list, GpuCache& cache,
                                   const DrawState& state, std::size_t view, std::uint32_t layers,
                                   bool per_layer, std::vector<InstanceRecord>& records,
                                   const glm::mat4* light_vp = nullptr,
                                   const glm::vec4* rect = nullptr, int* rect_culled = nullptr) {
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

// Culling, polygon offset and clipping of view `v`'s depth pass.
void set_depth_state(const ShadowView& v) {
  if (v.cull == CullMode::none) {
    glDisable(GL_CULL_FACE);
  } else {
    glEnable(GL_CULL_FACE);
    glCullFace(v.cull == CullMode::front ? GL_FRONT : GL_BACK);
  }
  glPolygonOffset(v.slope_bias, v.constant_bias);
  // Paraboloid hemispheres end at a clip distance (shadow_depth.vert).
  if (v.projection == ShadowProjection::dual_paraboloid) {
    glEnable(GL_CLIP_DISTANCE0);
  } else {
    glDisable(GL_CLIP_DISTANCE0);
  }
}

// Records instanced depth draws of `runs` of view `view` (their records uploaded first);
// light_vp: the one layer's matrix, null for the layered pass.
Status draw_runs(const FrameInput& frame, const DrawList& list, GpuCache& cache, DrawState& state,
                 FrameStats& stats, std::size_t view, std::span<const CasterRun> runs,
                 std::span<const InstanceRecord> records, const glm::mat4* light_vp,
                 bool peel = false) {
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
    draw_batch(frame, cache, batch, stats.shadow_draw_calls, stats.shadow_mesh_draws);
    first = end;
  }
  glFrontFace(GL_CCW);
  return {};
}

}  // namespace

Status ShadowMapPass::record(const FrameInput& frame, const DrawList& list, GpuCache& cache,
                             DrawState& state, FrameStats& stats) {
  if (redraw_ == 0) return {};
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
  glViewport(0, 0, size_, size_);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glClearDepth(1.0);
  glEnable(GL_POLYGON_OFFSET_FILL);
  // Layered: every layer attached at once and cleared together (skipped layers stay clear);
  // every caster goes once per layer it overlaps as an instance carrying that layer, which the
  // vertex shader sends there (shadow_depth.vert). The same maps as one pass per layer (render
  // test), with fewer draw calls.
  if (layered_) {
    glNamedFramebufferTexture(fbo_.id(), GL_DEPTH_ATTACHMENT, map_.id(), 0);
    glClear(GL_DEPTH_BUFFER_BIT);
  }
  Status status;
  std::vector<InstanceRecord> records;
  for (std::size_t view = 0; view < frame.shadow_views.size() && status; ++view) {
    const ShadowView& v = frame.shadow_views[view];
    set_depth_state(v);
    if (layered_) {
      std::uint32_t live = 0;
      for (int c = 0; c < v.layer_count; ++c)
        if (!v.skipped[std::size_t(c)]) live |= 1u << c;
      const auto runs = caster_runs(frame, list, cache, state, view, live, true, records);
      status = draw_runs(frame, list, cache, state, stats, view, runs, records, nullptr);
      continue;
    }
    for (int c = 0; c < v.layer_count && status; ++c) {
      const int layer = v.first_layer + c;
      if (!((redraw_ >> layer) & 1u) || pieces_[std::size_t(layer)].empty()) continue;
      glNamedFramebufferTextureLayer(fbo_.id(), GL_DEPTH_ATTACHMENT, map_.id(), 0, layer);
      // Only the texels lookups read are cleared and drawn (ShadowView::read_rect), and of a
      // scrolled layer only those it did not hold, each piece within one wrap of the texture.
      // Clears on llvmpipe: a whole layer by the framebuffer clear (faster than the same as a
      // texture region); a large part (a quarter of the layer or more) as a texture region
      // (about half the time for half the texels, where a scissored glClear draws a quad and
      // cost more than clearing the whole layer); a small part, as a scrolled layer's strips,
      // by a scissored glClear (the texture-region clear waits for the pass: 0.3-0.4 ms of the
      // default scene's moving frame).
      for (const Piece& piece : pieces_[std::size_t(layer)]) {
        const glm::ivec4 t = piece.texture;
        const bool whole = t == glm::ivec4(0, 0, size_, size_);
        if (whole) {
          glDisable(GL_SCISSOR_TEST);
          glClear(GL_DEPTH_BUFFER_BIT);
        } else {
          glEnable(GL_SCISSOR_TEST);
          glScissor(t.x, t.y, t.z - t.x, t.w - t.y);
          if (std::int64_t(t.z - t.x) * (t.w - t.y) * 4 >= std::int64_t(size_) * size_) {
            const float far_depth = 1.0f;
            glClearTexSubImage(map_.id(), 0, t.x, t.y, layer, t.z - t.x, t.w - t.y, 1,
                               GL_DEPTH_COMPONENT, GL_FLOAT, &far_depth);
          } else {
            glClear(GL_DEPTH_BUFFER_BIT);
          }
        }
        if (v.skipped[std::size_t(c)]) continue;
        // Map texel x lands on texture texel x + viewport.
        glViewport(piece.viewport.x, piece.viewport.y, size_, size_);
        // Part of a cascade: casters outside the drawn texels are left out.
        const glm::mat4& vp = v.view_proj[std::size_t(c)];
        const bool part = !whole && v.projection == ShadowProjection::ortho;
        const glm::vec4 ndc = drawn_ndc(t - glm::ivec4(piece.viewport, piece.viewport), size_);
        const auto runs = caster_runs(frame, list, cache, state, view, 1u << c, false, records,
                                      &vp, part ? &ndc : nullptr, &stats.shadow_rect_culled);
        status = draw_runs(frame, list, cache, state, stats, view, runs, records, &vp);
        if (!status) break;
      }
    }
  }
  glViewport(0, 0, size_, size_);
  glDisable(GL_POLYGON_OFFSET_FILL);
  glDisable(GL_CLIP_DISTANCE0);
  glDisable(GL_SCISSOR_TEST);
  if (!status) {
    // Origins have moved for layers not drawn: none of them can be kept or scrolled.
    std::fill(drawn_from_.begin(), drawn_from_.end(), 0);
    return status;
  }
  for (const ShadowView& v : frame.shadow_views)
    for (int c = 0; c < v.layer_count; ++c) {
      const std::size_t layer = std::size_t(v.first_layer + c);
      if (!((redraw_ >> layer) & 1u)) continue;
      drawn_from_[layer] = inputs_[layer];
      drawn_rect_[layer] = rects_[layer];
      drawn_matrix_[layer] = v.view_proj[std::size_t(c)];
      drawn_fixed_[layer] = fixed_[layer];
      drawn_casters_[layer].swap(casters_[layer]);
    }
  return {};
}

void ShadowMapPass::offset_lookups(const FrameInput& frame, FrameBlock& block) const {
  for (std::size_t k = 0; k < frame.shadow_views.size(); ++k) {
    const ShadowView& v = frame.shadow_views[k];
    for (int c = 0; c < v.layer_count; ++c) {
      const glm::ivec2 o = origin_[std::size_t(v.first_layer + c)];
      glm::mat4& m = block.shadow_views[k].view_proj[c];
      for (int a = 0; a < 2; ++a)
        if (o[a] != 0) m[3][a] = float(double(m[3][a]) + 2.0 * o[a] / size_);
    }
  }
}

Image ShadowMapPass::read() const {
  Image img = read_slices(map_, GL_DEPTH_COMPONENT, {"Y"}, size_, layers_);  // empty before the first frame
  if (img.pixels.empty()) return img;
  // A scrolled layer's texture holds map texel (x, y) at (x + origin) mod size, GL rows bottom
  // to top; the image's rows run top to bottom.
  const std::size_t n = std::size_t(size_);
  std::vector<float> layer(n * n);
  for (std::size_t l = 0; l < origin_.size() && l < std::size_t(layers_); ++l) {
    const glm::ivec2 o = origin_[l];
    if (o == glm::ivec2(0)) continue;
    float* base = &img.pixels[l * n * n];
    std::copy(base, base + n * n, layer.begin());
    for (std::size_t gy = 0; gy < n; ++gy) {
      const std::size_t from_row = n - 1 - (gy + std::size_t(o.y)) % n, to_row = n - 1 - gy;
      for (std::size_t x = 0; x < n; ++x)
        base[to_row * n + x] = layer[from_row * n + (x + std::size_t(o.x)) % n];
    }
  }
  return img;
}

// ---- LomPass -------------------------------------------------------------------------------------

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
  drawn_from_.assign(std::size_t(layers), 0);
  drawn_rect_.assign(std::size_t(layers), glm::ivec4(0));
  layer_overflow_.assign(std::size_t(layers), 0);
}

Status LomPass::prepare(const FrameInput& frame, const DrawList& list, const ShadowMapPass& shadow,
                        FrameStats& stats) {
  stats.lom_layers_computed = 0;
  stats.lom_overflow_texels = 0;
  redraw_ = 0;
  const std::vector<ShadowView>& views = frame.shadow_views;
  if (views.empty() || traits(frame.shadow_settings.technique).extra_pass != ShadowExtraPass::lom_peeling)
    return {};
  const int size = frame.shadow_settings.map_size;
  const int total = views.back().first_layer + views.back().layer_count;
  const int peels = frame.shadow_settings.lom_layers + 1;
  const int slices = total * peels;
  if (!depth_ || size != size_ || slices != slices_ || peels != peels_) {
    GLint max_layers = 0;
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
    const double mib = double(size) * size * slices * 5.0 / double(1 << 20);
    const std::string what = std::to_string(slices) + " slices of " + std::to_string(size) +
                             "^2 (" + std::to_string(int(mib)) + " MiB)";
    if (slices > max_layers)
      return Error{"", "shadow.lom_layers", "the layered occlusion map needs " + what +
                                                ", more than this driver's GL_MAX_ARRAY_TEXTURE_LAYERS " +
                                                std::to_string(max_layers)};
    glTexImage3D(GL_PROXY_TEXTURE_2D_ARRAY, 0, GL_R32F, size, size, slices, 0, GL_RED, GL_FLOAT,
                 nullptr);
    GLint got = 0;
    glGetTexLevelParameteriv(GL_PROXY_TEXTURE_2D_ARRAY, 0, GL_TEXTURE_WIDTH, &got);
    if (got == 0)
      return Error{"", "shadow.lom_layers",
                   "the OpenGL driver refuses the layered occlusion map's " + what +
                       "; use a smaller map_size, fewer lom_layers or fewer cascades"};
    peels_ = peels;
    depth_ = {};
    ensure_storage(size, slices);
    // Pass 1 works per map texel and layer: past S1's one 1024^2 map, a software rasteriser
    // takes seconds whenever the maps are redrawn (the first frame, a moving camera or light).
    if (double(size) * size * total > 2.0 * 1024.0 * 1024.0)
      log::warn_once("shadow.technique lom: %d map layers of %d^2 with %d depth peels each; its "
                     "pass 1 runs per map texel and layer, so every frame that redraws the maps "
                     "pays for all of them (S1's set-up is one 1024^2 map; a smaller "
                     "shadow.map_size or a smaller shadow.cascade_count cuts it)",
                     total, size, peels - 1);
  }
  // A layer's inputs beyond its casters: the receivers that cast nothing (stored, so that they
  // are shaded; hashed once for every layer), the light's size and the layer count.
  InputHash receivers;
  for (std::uint32_t i : list.depth_order) {
    const DrawItem& d = frame.draws[i];
    if (d.receive_shadows && !d.cast_shadows) receivers.add(d.mesh).add(d.model);
  }
  inputs_.assign(std::size_t(total), 0);
  for (const ShadowView& v : views)
    for (int c = 0; c < v.layer_count; ++c) {
      const int layer = v.first_layer + c;
      InputHash h;
      h.add(shadow.layer_inputs(layer)).add(v.light_size).add(peels).add(v.cull);
      h.add(receivers.value());
      inputs_[std::size_t(layer)] = h.value();
      if (!lom_view(v) || v.skipped[std::size_t(c)]) continue;
      const glm::ivec4 rect = stats.layer_rect[std::size_t(layer)];
      const bool drawn = drawn_from_[std::size_t(layer)] != 0 &&
                         holds(drawn_rect_[std::size_t(layer)], rect);
      const bool held = ((v.held >> c) & 1u) != 0;
      if (!frame.shadow_cache || !drawn || (inputs_[std::size_t(layer)] != drawn_from_[std::size_t(layer)] && !held))
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
      drawn_from_[std::size_t(layer)] = inputs_[std::size_t(layer)];
      drawn_rect_[std::size_t(layer)] = read;
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

// ---- MomentsPass ---------------------------------------------------------------------------------

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
    // Trilinear only: moments_filtered() (shadow.glsl) filters anisotropically along the
    // footprint itself. The sampler's 8x anisotropy made a spot's vsm frame take 15 s at 640x360
    // on llvmpipe and misclassified 0.16% of the default scene's pixels (0.059% now).
    empty_vao_ = gpu::make_vertex_array();
  }
  drawn_from_.assign(std::size_t(layers), 0);
  drawn_rect_.assign(std::size_t(layers), glm::ivec4(0));
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
    const GLenum format = four ? GL_RGBA32F : GL_RG32F;
    glTexImage3D(GL_PROXY_TEXTURE_2D_ARRAY, 0, GLint(format), size, size, total, 0,
                 four ? GL_RGBA : GL_RG, GL_FLOAT, nullptr);
    GLint got = 0;
    glGetTexLevelParameteriv(GL_PROXY_TEXTURE_2D_ARRAY, 0, GL_TEXTURE_WIDTH, &got);
    if (got == 0) {
      const double mib = double(size) * size * total * (four ? 16.0 : 8.0) * 4.0 / 3.0 /
                         double(1 << 20);
      return Error{"", "shadow.technique",
                   "the OpenGL driver refuses the " +
                       std::string(technique_name(frame.shadow_settings.technique)) + " moments (" + std::to_string(total) + " layers of " +
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
      InputHash h;
      h.add(shadow.layer_inputs(layer)).add(frame.shadow_settings.vsm_blur).add(four);
      inputs_[std::size_t(layer)] = h.value();
      const glm::ivec4 rect = stats.layer_rect[std::size_t(layer)];
      const bool drawn = drawn_from_[std::size_t(layer)] != 0 &&
                         holds(drawn_rect_[std::size_t(layer)], rect);
      const bool held = ((v.held >> c) & 1u) != 0;
      if (!frame.shadow_cache || !drawn ||
          (inputs_[std::size_t(layer)] != drawn_from_[std::size_t(layer)] && !held))
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
      drawn_from_[std::size_t(layer)] = inputs_[std::size_t(layer)];
      drawn_rect_[std::size_t(layer)] = r;
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

// ---- Forward drawing (main view and probe faces) ------------------------------------------------

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
  // Runs of visible draws with the same program, material and winding become one batch: one
  // instanced draw per mesh, all in one multi-draw; a reflective draw (its own probe map and
  // k_s * p_r) stays alone. The draw list orders a batch's draws by mesh.
  std::vector<MeshDraw> batch;
  for (std::size_t first = 0; first < visible.size();) {
    const std::uint32_t i = visible[first];
    const DrawItem& d = frame.draws[i];
    const bool mirrored = mirrors(d.model);
    std::size_t end = first + 1;
    if (!reflective(i))
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
    draw_batch(frame, cache, batch, stats.draw_calls, stats.mesh_draws);
    stats.instances += int(end - first);
    first = end;
  }
  glFrontFace(GL_CCW);
  return {};
}

// ---- ProbeCapturePass ---------------------------------------------------------------------------

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

// ---- ForwardPass --------------------------------------------------------------------------------

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
  if (views <= 1) return {"stored visibility (GL_R32F)", GL_R32F, GL_RED, GL_FLOAT, 4};
  if (views == 2) return {"stored visibility (GL_RG32F)", GL_RG32F, GL_RG, GL_FLOAT, 8};
  return {"stored visibility (GL_RGBA32F)", GL_RGBA32F, GL_RGBA, GL_FLOAT, 16};
}

void ForwardPass::prepare(const FrameInput& frame, int samples) {
  const bool resized = !fbo_ || frame.width != width_ || frame.height != height_;
  if (resized) {
    visibility_.reset();
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
    const Status st = draw_forward(frame, list.forward_order, list.msaa_keys, nullptr, 0,
                                   view_proj, cache, state, stats);
    glDisable(GL_SAMPLE_ALPHA_TO_ONE);
    glDisable(GL_SAMPLE_ALPHA_TO_COVERAGE);
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
  // it, which an attached texture must not be).
  const GLenum visibility_attachment = GL_COLOR_ATTACHMENT5;
  if (reuse == VariantKey::kReuseStore) {
    const int views = std::min<int>(int(frame.shadow_views.size()), kMaxShadowedLights);
    if (!visibility_ || views != visibility_views_) {
      const Target t = visibility_target(views);
      visibility_ = gpu::make_texture(GL_TEXTURE_2D);
      glTextureStorage2D(visibility_.id(), 1, t.internal_format, width_, height_);
      visibility_views_ = views;
    }
    glNamedFramebufferTexture(fbo_.id(), visibility_attachment, visibility_.id(), 0);
    const GLenum store_bufs[2] = {GL_COLOR_ATTACHMENT0, visibility_attachment};
    glNamedFramebufferDrawBuffers(fbo_.id(), 2, store_bufs);
  } else if (reuse == VariantKey::kReuseLoad) {
    KASKAD_CHECK(visibility_, "a frame loads shadow visibility that no frame stored");
    glBindTextureUnit(kTexCachedVisibility, visibility_.id());
    glBindSampler(kTexCachedVisibility, 0);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
  if (single_colour) glClearBufferfv(GL_COLOR, 0, clear_color);
  if (frame.write_aovs)
    for (int i = 1; i < 5; ++i) glClearBufferfv(GL_COLOR, i, zero);
  glClearBufferfv(GL_DEPTH, 0, &one);
  // The AOV pass draws what the colour pass drew: its culling is counted once.
  const int culled = stats.frustum_culled;
  const Status st = draw_forward(frame, list.forward_order, keys, nullptr, 0, view_proj,
                                 cache, state, stats);
  if (!single_colour) stats.frustum_culled = culled;
  if (reuse == VariantKey::kReuseStore) glNamedFramebufferTexture(fbo_.id(), visibility_attachment, 0, 0);
  glDisable(GL_FRAMEBUFFER_SRGB);
  return st;
}

}  // namespace kaskad::render
