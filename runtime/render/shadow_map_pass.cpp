#include "runtime/render/shadow_map_pass.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <bit>
#include <optional>
#include <string>

#include "runtime/features/shader_interface.h"
#include "runtime/render/depth_draws.h"
#include "runtime/core/hash.h"
#include "runtime/render/texture_storage.h"

namespace kaskad::render {
namespace {

GLenum depth_internal_format(DepthFormat f) {
  switch (f) {
    case DepthFormat::d16: return GL_DEPTH_COMPONENT16;
    case DepthFormat::d32f: return GL_DEPTH_COMPONENT32F;
    case DepthFormat::d24: break;
  }
  return GL_DEPTH_COMPONENT24;
}

/// Whether the driver can make the shadow map array.
Status check_shadow_map_size(int size, int layers, DepthFormat format) {
  const TextureCheck check =
      check_array_texture(depth_internal_format(format), GL_DEPTH_COMPONENT, size, layers);
  if (check.fit == TextureCheck::fits) return {};
  const std::string where = "shadow.map_size " + std::to_string(size);
  const std::string what = std::to_string(size) + "^2 x " + std::to_string(layers) + " layers";
  if (check.fit == TextureCheck::over_limits)
    return Error{"", where,
                 "shadow maps of " + what + " exceed this driver's limits (" + check.limits() + ")"};
  const double bytes = double(size) * size * layers * (format == DepthFormat::d16 ? 2.0 : 4.0);
  return Error{"", where, "the OpenGL driver refuses shadow maps of " + what + " (" +
                              std::to_string(int(bytes / double(1 << 20))) +
                              " MiB); use a smaller map_size or fewer cascades"};
}

// Triangles of a mesh as the passes draw it.
std::size_t triangles(const AssetStore& assets, MeshId id) {
  return assets.meshes[index(id)].indices.size() / 3;
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

}  // namespace

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
    drawn_.assign(std::size_t(layers), {});  // new storage: nothing to keep
    origin_.assign(std::size_t(layers), glm::ivec2(0));
    drawn_matrix_.assign(std::size_t(layers), glm::mat4(0.0f));
    drawn_fixed_.assign(std::size_t(layers), 0);
    drawn_casters_.assign(std::size_t(layers), {});
    drawn_pass_.assign(std::size_t(layers), 0);
    drawn_boxes_.assign(std::size_t(layers), {});
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
  stats.shadow_layers_scrolled = stats.shadow_layers_patched = 0;
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
  // casters (mesh, model matrix, pose, depth program, double-sidedness, alpha-mask parameters)
  // in order. A moved caster
  // changes its matrix, a moved camera the layer's matrix or casters; other assets (another
  // scene) change assets.uid. New storage invalidated every layer.
  auto add_caster = [&](Hash& h, std::size_t view, std::uint32_t i) {
    const DrawItem& d = frame.draws[i];
    const VariantKey key = list.depth_key(view, i).filtered_for(Pass::depth);
    h.add(d.mesh).add(d.model).add(d.pose).add(key.bits());
    h.add(d.material.double_sided);  // its faces culled (caster_cull())
    if (key.has(VariantKey::kAlphaMask) || features_by_uniform)  // blended casters too
      h.add(d.material.base_color.a)
          .add(d.material.alpha_cutoff)
          .add(d.material.base_color_texture)
          .add(d.material.base_color_transform);
  };
  auto add_pass = [&](Hash& h, const ShadowView& v) {
    h.add(assets.uid).add(shader_reloads).add(layered).add(v.projection).add(v.cull);
    h.add(v.slope_bias).add(v.constant_bias);
  };
  // Every caster of the view: one hash each (caster_ids, by draw, made once per view by
  // view_casters()) and one of them all.
  std::vector<std::uint64_t> caster_ids;
  auto view_casters = [&](std::size_t view) {
    caster_ids.assign(frame.draws.size(), 0);
    Hash all;
    for (std::uint32_t i : list.depth_order)
      if (frame.draws[i].cast_shadows) {
        Hash one;
        add_caster(one, view, i);
        caster_ids[i] = one.value();
        all.add(caster_ids[i]);
      }
    return all.value();
  };
  auto layer_inputs = [&](std::size_t view, int c) {
    const ShadowView& v = views[view];
    Hash h;
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
    Hash h;
    add_pass(h, v);
    h.add(m).add(casters);
    return h.value();
  };
  // The casters layer c of the view holds (its caster_mask), sorted: a layer that keeps texels
  // must have held every caster that falls on them.
  auto layer_casters = [&](const ShadowView& v, int c, std::vector<std::uint64_t>& out,
                           std::vector<Aabb>& boxes) {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> sorted;
    for (std::uint32_t i : list.depth_order)
      if (caster_mask(v, frame.draws[i]) & (1u << c)) sorted.push_back({caster_ids[i], i});
    std::sort(sorted.begin(), sorted.end());
    out.clear();
    boxes.clear();
    for (const auto& [id, i] : sorted) {
      out.push_back(id);
      boxes.push_back(frame.draws[i].bounds);
    }
  };
  // A layer drawn with this pass and matrix whose casters alone changed (a caster moved, came or
  // went under a still camera): the texels to redraw, those of the boxes of the casters it was
  // drawn with that are gone and of those it did not hold, each two texels wider and cut to the
  // read rectangle `needed`. None (redraw what is needed) when a box is empty (such a caster is
  // drawn everywhere) or the parts would cover half of `needed`.
  auto moved_caster_rects =
      [&](std::size_t layer, const glm::mat4& vp, const glm::ivec4& needed,
          const std::vector<std::uint64_t>& now,
          const std::vector<Aabb>& now_boxes) -> std::optional<std::vector<glm::ivec4>> {
    const std::vector<std::uint64_t>& before = drawn_casters_[layer];
    const std::vector<Aabb>& before_boxes = drawn_boxes_[layer];
    std::vector<glm::ivec4> parts;
    std::int64_t area = 0;
    auto add = [&](const Aabb& box) {
      if (box.empty()) return false;
      const Aabb b = box.transformed(vp);
      glm::ivec4 r = texel_rect(glm::vec4(b.min.x, b.min.y, b.max.x, b.max.y), map.map_size);
      r = glm::ivec4(std::max(r.x - 2, needed.x), std::max(r.y - 2, needed.y),
                     std::min(r.z + 2, needed.z), std::min(r.w + 2, needed.w));
      if (empty_rect(r)) return true;
      parts.push_back(r);
      area += std::int64_t(r.z - r.x) * (r.w - r.y);
      return true;
    };
    // One merge of the two sorted lists: what is in one and not the other.
    std::size_t a = 0, b = 0;
    while (a < before.size() || b < now.size()) {
      if (b == now.size() || (a < before.size() && before[a] < now[b])) {
        if (!add(before_boxes[a++])) return std::nullopt;
      } else if (a == before.size() || now[b] < before[a]) {
        if (!add(now_boxes[b++])) return std::nullopt;
      } else {
        ++a;
        ++b;
      }
    }
    if (area * 2 >= std::int64_t(needed.z - needed.x) * (needed.w - needed.y)) return std::nullopt;
    return parts;
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
  boxes_.assign(std::size_t(total), {});
  pass_.assign(std::size_t(total), 0);
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
      const bool keep = keeps_layer(frame.shadow_cache, drawn_[layer], inputs_[layer],
                                    rects_[layer], ((v.held >> c) & 1u) != 0);
      std::vector<LayerPiece>& pieces = pieces_[layer];
      if (!scrolls || skipped) {
        if (keep && origin_[layer] == glm::ivec2(0)) continue;
        origin_[layer] = glm::ivec2(0);
        if (tracks && !skipped) {
          fixed_[layer] = fixed_inputs(view, c, casters);
          layer_casters(v, c, casters_[layer], boxes_[layer]);
          pass_[layer] = fixed_inputs(view, c, 0);
        }
        add_pieces(rects_[layer], origin_[layer], map.map_size, pieces);
        redraw_ |= 1u << layer;
        drawn_now |= 1u << layer;
        continue;
      }
      if (keep) continue;
      fixed_[layer] = fixed_inputs(view, c, casters);
      pass_[layer] = fixed_inputs(view, c, 0);
      layer_casters(v, c, casters_[layer], boxes_[layer]);
      std::vector<glm::ivec4> regions{rects_[layer]};
      glm::ivec2 shift(0);
      const glm::mat4& vp = v.view_proj[std::size_t(c)];
      if (drawn_[layer].inputs != 0 && drawn_fixed_[layer] == fixed_[layer] &&
          moved_by_texels(drawn_matrix_[layer], vp, map.map_size, shift)) {
        const glm::ivec4 kept = shifted(drawn_[layer].rect, shift, map.map_size);
        if (!newcomer_over(v, c, layer, kept, casters_[layer])) {
          origin_[layer] = scrolled_origin(origin_[layer], shift, map.map_size);
          regions = outside(rects_[layer], kept);
          stats.shadow_layers_scrolled |= 1u << layer;
        }
      } else if (drawn_[layer].inputs != 0 && drawn_pass_[layer] == pass_[layer] &&
                 drawn_matrix_[layer] == vp && holds(drawn_[layer].rect, rects_[layer])) {
        // The same pass and matrix, other casters: only where they changed.
        if (auto parts = moved_caster_rects(layer, vp, rects_[layer], casters_[layer],
                                            boxes_[layer])) {
          regions = std::move(*parts);
          stats.shadow_layers_patched |= 1u << layer;
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
    for (const std::vector<LayerPiece>& pieces : pieces_)
      for (const LayerPiece& p : pieces)
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
      // Clears, the cheapest way on llvmpipe for each size (measured: docs/design/
      // shadow_cost.md): a whole layer by the framebuffer clear; a large part (a quarter of the
      // layer or more) as a texture region, where a scissored glClear draws a quad; a small
      // part, as a scrolled layer's strips, by a scissored glClear (the texture-region clear
      // waits for the pass).
      for (const LayerPiece& piece : pieces_[std::size_t(layer)]) {
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
    for (DrawnLayer& d : drawn_) d.inputs = 0;
    return status;
  }
  for (const ShadowView& v : frame.shadow_views)
    for (int c = 0; c < v.layer_count; ++c) {
      const std::size_t layer = std::size_t(v.first_layer + c);
      if (!((redraw_ >> layer) & 1u)) continue;
      drawn_[layer].inputs = inputs_[layer];
      drawn_[layer].rect = rects_[layer];
      drawn_matrix_[layer] = v.view_proj[std::size_t(c)];
      drawn_fixed_[layer] = fixed_[layer];
      drawn_casters_[layer].swap(casters_[layer]);
      drawn_boxes_[layer].swap(boxes_[layer]);
      drawn_pass_[layer] = pass_[layer];
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

}  // namespace kaskad::render
