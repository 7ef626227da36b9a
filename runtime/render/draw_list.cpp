#include "runtime/render/draw_list.h"

#include <algorithm>
#include <array>
#include <bit>
#include <tuple>
#include <type_traits>
#include <unordered_map>
#include <utility>

#include "components/bounds.h"
#include "runtime/core/hash.h"

namespace kaskad::render {

VariantKey frame_variant(const FrameInput& frame) {
  VariantKey k;
  if (!frame.shadow_views.empty()) {
    const ShadowSettings& s = frame.shadow_settings;
    const ShadowView& first = frame.shadow_views.front();
    const int views = std::min<int>(int(frame.shadow_views.size()), kMaxShadowedLights);
    k.set(VariantKey::kShadow, 1);
    k.set(VariantKey::kShadowLightsMinus1, std::uint32_t(views - 1));
    k.set(VariantKey::kShadowFilter, std::uint32_t(s.filter));
    k.set(VariantKey::kShadowTechnique, std::uint32_t(s.technique));
    // The kernel is pcf3x3's footprint; pcss filters with its own disc: one key for each.
    if (s.filter == ShadowFilter::pcf3x3 && traits(s.technique).uses_pcf_kernel)
      k.set(VariantKey::kShadowKernel, std::uint32_t(s.pcf_kernel));
    k.set(VariantKey::kShadowProjection, std::uint32_t(first.projection));
    // Paraboloid hemispheres are projected in code, one pass each: no layered pass for them.
    if (s.layered && first.projection != ShadowProjection::dual_paraboloid)
      k.set(VariantKey::kShadowLayered, 1);
    // Layers of spot and point lights are faces, not cascades: no cascade selection code.
    if (first.projection == ShadowProjection::ortho)
      k.set(VariantKey::kCascadeCountMinus1,
            std::uint32_t(std::clamp(first.layer_count, 1, kMaxCascades) - 1));
    k.set(VariantKey::kCascadeSelection, s.selection == CascadeSelection::map_bounds ? 1u : 0u);
    k.set(VariantKey::kDebugCascades, s.debug_cascades ? 1u : 0u);
    // The cache holds visibility only: not the cascade the tint and the AOVs show, and one
    // value per pixel, not per sample.
    if (frame.visibility_cache && !frame.write_aovs && frame.msaa <= 1 && !s.debug_cascades)
      k.set(VariantKey::kShadowReuse, VariantKey::kReuseStore);
  }
  if (frame.write_aovs) k.set(VariantKey::kAovs, 1);
  k.set(VariantKey::kToneMapping, std::uint32_t(frame.tone_mapping));
  if (frame.environment) k.set(VariantKey::kEnvironment, 1);
  return k;
}

bool reprojects_visibility(const FrameInput& frame) {
  return frame.visibility_reproject && frame.shadow_views.size() == 1;
}

VariantKey capture_frame_variant(VariantKey frame) {
  // Cubes hold linear radiance: no AOVs, no tone mapping.
  VariantKey k = VariantKey(frame.bits() & ~VariantKey::kAovs.mask() & ~VariantKey::kToneMapping.mask() &
                            ~VariantKey::kShadowReuse.mask());
  if (k.has(VariantKey::kShadow) && k.get(VariantKey::kShadowProjection) == 0)  // ortho cascades
    k.set(VariantKey::kCascadeSelection, 1);
  return k;
}

VariantKey msaa_frame_variant(VariantKey frame) {
  return VariantKey(frame.bits() & ~VariantKey::kAovs.mask()).set(VariantKey::kAlphaToCoverage, 1);
}

VariantKey material_variant(const DrawItem& d) {
  // receive_shadows is a per-object flag, but it selects code like a material feature.
  VariantKey k = VariantKey(d.material.features & VariantKey::kMaterialMask & ~VariantKey::kReceiveShadows.mask());
  if (d.receive_shadows) k.set(VariantKey::kReceiveShadows, 1);
  return k;
}

VariantKey deform_variant(const DeformJob& job) {
  VariantKey k;
  k.set(VariantKey::kSkin, job.influences > 4 ? 2u : job.influences > 0 ? 1u : 0u);
  k.set(VariantKey::kMorph, job.weight_count > 0 ? 1u : 0u);
  return k;
}

std::vector<ProgramRequest> required_programs(const FrameInput& frame) {
  const VariantKey fk = frame_variant(frame);
  // Probe captures draw without AOVs; a reflector's draw gets its map feature once its first
  // capture completes (possibly frames later when time-sliced): compile those up front too.
  const VariantKey capture_fk = capture_frame_variant(fk);
  // The main view's forward programs: single-sample (colour, or the AOVs beside a multisampled
  // colour pass) and multisampled colour.
  std::vector<VariantKey> main_fks;
  if (frame.msaa <= 1 || frame.write_aovs) main_fks.push_back(fk);
  if (frame.msaa > 1) main_fks.push_back(msaa_frame_variant(fk));
  // With the visibility cache, a still frame's programs (the shadow-receiving ones) load it,
  // and a moving camera's reproject it where there is a channel for the distance.
  if (fk.get(VariantKey::kShadowReuse) == VariantKey::kReuseStore) {
    main_fks.push_back(VariantKey(fk).set(VariantKey::kShadowReuse, VariantKey::kReuseLoad));
    if (reprojects_visibility(frame))
      main_fks.push_back(VariantKey(fk).set(VariantKey::kShadowReuse, VariantKey::kReuseReproject));
  }
  // The technique's own pass (none without shadows: the key then holds pcf).
  const ShadowExtraPass extra_pass = shadow_technique_of(fk).extra_pass;
  std::vector<ProgramRequest> out;
  for (const DeformJob& job : frame.deforms) out.push_back({Pass::deform, deform_variant(job)});
  for (const DrawItem& d : frame.draws) {
    const VariantKey k = material_variant(d) | fk;
    for (const VariantKey main : main_fks)
      out.push_back({Pass::forward, (material_variant(d) | main).filtered_for(Pass::forward)});
    if (extra_pass == ShadowExtraPass::lom_peeling &&
        (d.cast_shadows || d.receive_shadows)) {  // LomPass's peels
      const VariantKey peel =
          VariantKey(k).set(VariantKey::kShadowPeel, 1).set(VariantKey::kShadowLayered, 0);
      out.push_back({Pass::depth, peel.filtered_for(Pass::depth)});
      if (frame.shadow_views.size() > 1)
        out.push_back({Pass::depth,
                       VariantKey(peel).set(VariantKey::kShadowProjection, 0).filtered_for(Pass::depth)});
    }
    if (fk.has(VariantKey::kShadow) && d.cast_shadows) {
      out.push_back({Pass::depth, k.filtered_for(Pass::depth)});
      // Views after the first are cascades: the plain depth program, whatever the first's is.
      if (frame.shadow_views.size() > 1)
        out.push_back({Pass::depth,
                       VariantKey(k).set(VariantKey::kShadowProjection, 0).filtered_for(Pass::depth)});
    }
    std::vector<VariantKey> materials = {material_variant(d)};
    for (const ProbeJob& job : frame.probes)
      if (job.handle == d.probe)
        materials.push_back(VariantKey(materials[0])
                                .set(job.sphere ? VariantKey::kReflectionSphere
                                                : VariantKey::kReflectionCube, 1)
                                .set(VariantKey::kReflectionBox, job.box ? 1u : 0u)
                                .set(VariantKey::kReflectionPbr,
                                     !job.sphere && d.material.reflection_model == ReflectionModel::pbr));
    for (const VariantKey m : materials) {
      for (const VariantKey main : main_fks)
        out.push_back({Pass::forward, (m | main).filtered_for(Pass::forward)});
      if (!frame.probes.empty()) out.push_back({Pass::forward, (m | capture_fk).filtered_for(Pass::forward)});
    }
  }
  if (extra_pass == ShadowExtraPass::lom_peeling)
    out.push_back({Pass::lom_occlusion, fk.filtered_for(Pass::lom_occlusion)});
  if (extra_pass == ShadowExtraPass::moments)
    out.push_back({Pass::vsm_moments, fk.filtered_for(Pass::vsm_moments)});
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

VariantKey DrawList::depth_key(std::size_t view, std::uint32_t i) const {
  VariantKey k = keys[i];
  if (view > 0) k.set(VariantKey::kShadowProjection, 0);
  return k;
}

namespace {

// The material's fields in the order draws sort by: textures first (the costliest binds). The
// texture transforms are left out: draws that differ only there still bind apart (Material's
// operator== decides), they just need not sort next to each other.
auto material_fields(const Material& m) {
  return std::tie(m.base_color_texture, m.normal_texture, m.occlusion_texture,
                  m.emissive_texture, m.metallic_roughness_texture, m.occlusion_strength, m.double_sided, m.alpha_mode,
                  m.metallic, m.roughness, m.base_color.r, m.base_color.g, m.base_color.b,
                  m.base_color.a, m.normal_scale, m.emissive.r, m.emissive.g, m.emissive.b,
                  m.alpha_cutoff, m.k_s, m.features);
}

// One material field as bits to hash: a float with -0 made +0 (they compare equal), an enum
// or integer as it is.
template <class T>
std::uint64_t field_bits(const T& v) {
  if constexpr (std::is_floating_point_v<T>)
    return std::bit_cast<std::uint32_t>(float(v) + 0.0f);
  else if constexpr (std::is_enum_v<T>)
    return std::uint64_t(static_cast<std::underlying_type_t<T>>(v));
  else
    return std::uint64_t(v);
}

// A material's fields as bits, for finding equal materials by hashing.
auto material_bits(const Material& m) {
  return std::apply(
      [](const auto&... f) { return std::array<std::uint64_t, sizeof...(f)>{field_bits(f)...}; },
      material_fields(m));
}
using MaterialBits = decltype(material_bits(Material{}));

struct MaterialBitsHash {
  std::size_t operator()(const MaterialBits& bits) const {
    return std::size_t(Hash().add(bits).value());
  }
};

// Each draw's material as a rank: draws with equal material_fields() share a rank, and ranks
// order as material_fields() do. A scene's thousands of draws have few materials: they are
// found by hashing and only they are sorted.
std::vector<std::uint32_t> material_ranks(const FrameInput& frame) {
  std::unordered_map<MaterialBits, std::uint32_t, MaterialBitsHash> id_of;
  std::vector<std::uint32_t> first_draw;  // of each distinct material
  std::vector<std::uint32_t> id(frame.draws.size());
  for (std::uint32_t i = 0; i < frame.draws.size(); ++i) {
    const auto [it, added] =
        id_of.try_emplace(material_bits(frame.draws[i].material), std::uint32_t(first_draw.size()));
    if (added) first_draw.push_back(i);
    id[i] = it->second;
  }
  std::vector<std::uint32_t> order(first_draw.size()), rank(first_draw.size());
  for (std::uint32_t k = 0; k < order.size(); ++k) order[k] = k;
  // Stable: a NaN field makes the order no strict weak ordering, which std::sort may overrun.
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return material_sorts_before(frame.draws[first_draw[a]].material,
                                 frame.draws[first_draw[b]].material);
  });
  for (std::uint32_t r = 0; r < order.size(); ++r) rank[order[r]] = r;
  for (std::uint32_t& k : id) k = rank[k];
  return id;
}

// Draw indices sorted by `by[i]` as pass `pass` sees it, then by winding, material and mesh: draws
// that may share one call (same program, winding and material) end up next to each other, and
// within them draws of one mesh (one instanced draw of the call). The depth pass reads a material
// only to discard alpha-masked texels: without that, draws of one mesh share a draw whatever
// their materials, so there mesh comes before material.
std::vector<std::uint32_t> sorted_by(const FrameInput& frame, Pass pass,
                                     const std::vector<VariantKey>& by,
                                     const std::vector<std::uint32_t>& material_rank) {
  struct SortKey {
    VariantKey key;
    bool mirrored;
    bool mesh_first;
    std::uint32_t material;
    MeshId mesh;
  };
  std::vector<SortKey> k(frame.draws.size());
  for (std::size_t i = 0; i < k.size(); ++i) {
    const VariantKey key = by[i].filtered_for(pass);
    k[i] = {key, mirrors(frame.draws[i].model),
            pass == Pass::depth && !key.has(VariantKey::kAlphaMask), material_rank[i],
            frame.draws[i].mesh};
  }
  std::vector<std::uint32_t> order(frame.draws.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const SortKey& ka = k[a];
    const SortKey& kb = k[b];
    if (ka.key != kb.key) return ka.key < kb.key;
    if (ka.mirrored != kb.mirrored) return kb.mirrored;
    if (ka.mesh_first && ka.mesh != kb.mesh) return ka.mesh < kb.mesh;
    if (ka.material != kb.material) return ka.material < kb.material;
    return ka.mesh < kb.mesh;
  });
  return order;
}

}  // namespace

bool material_sorts_before(const Material& a, const Material& b) {
  return material_fields(a) < material_fields(b);
}

DrawList build_draw_list(const FrameInput& frame, VariantKey frame_key) {
  DrawList list;
  list.frame_key = frame_key;
  list.keys.resize(frame.draws.size());
  for (std::size_t i = 0; i < frame.draws.size(); ++i)
    list.keys[i] = material_variant(frame.draws[i]) | frame_key;
  const std::vector<std::uint32_t> material_rank = material_ranks(frame);
  if (!frame.shadow_views.empty())
    list.depth_order = sorted_by(frame, Pass::depth, list.keys, material_rank);
  list.forward_order = sorted_by(frame, Pass::forward, list.keys, material_rank);
  // Blended draws leave the forward orders for the transparent phase.
  auto blended = [&](std::uint32_t i) { return list.keys[i].has(VariantKey::kAlphaBlend); };
  for (std::uint32_t i = 0; i < frame.draws.size(); ++i)
    if (blended(i)) list.blend_draws.push_back(i);
  if (!list.blend_draws.empty()) std::erase_if(list.forward_order, blended);
  if (frame.msaa > 1) {
    const VariantKey msaa = msaa_frame_variant(frame_key);
    list.msaa_keys.resize(frame.draws.size());
    for (std::size_t i = 0; i < frame.draws.size(); ++i)
      list.msaa_keys[i] = (material_variant(frame.draws[i]) | msaa).filtered_for(Pass::forward);
  }
  if (!frame.probes.empty()) {
    const VariantKey capture = capture_frame_variant(frame_key);
    list.capture_keys.resize(frame.draws.size());
    for (std::size_t i = 0; i < frame.draws.size(); ++i)
      list.capture_keys[i] = material_variant(frame.draws[i]) | capture;
    list.capture_order = sorted_by(frame, Pass::forward, list.capture_keys, material_rank);
    if (!list.blend_draws.empty()) std::erase_if(list.capture_order, blended);
  }
  return list;
}

std::vector<std::uint32_t> back_to_front(const FrameInput& frame,
                                         std::span<const std::uint32_t> draws,
                                         const glm::vec4& depth_plane) {
  std::vector<std::pair<float, std::uint32_t>> by_distance;
  by_distance.reserve(draws.size());
  for (std::uint32_t i : draws) {
    const DrawItem& d = frame.draws[i];
    const glm::vec3 centre = d.bounds.empty() ? glm::vec3(d.model[3]) : d.bounds.center();
    by_distance.emplace_back(glm::dot(depth_plane, glm::vec4(centre, 1.0f)), i);
  }
  // Stable: equal distances keep draw order (and a NaN distance, which breaks the ordering,
  // cannot make it run out of bounds).
  std::stable_sort(by_distance.begin(), by_distance.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::uint32_t> out;
  out.reserve(by_distance.size());
  for (const auto& [distance, i] : by_distance) out.push_back(i);
  return out;
}

std::vector<std::uint32_t> visible_draws(const FrameInput& frame,
                                         std::span<const std::uint32_t> order,
                                         const glm::mat4& view_proj, const ProbeJob* capture,
                                         int& culled) {
  std::vector<std::uint32_t> out;
  out.reserve(order.size());
  for (std::uint32_t i : order) {
    const DrawItem& d = frame.draws[i];
    if (capture && (d.probe == capture->handle ||
                    (capture->exclude_layers & (1u << (d.layer & 31)))))
      continue;  // the reflector itself and excluded layers are not in its probe
    if (outside_clip_volume(view_proj, d.bounds)) {
      ++culled;
      continue;
    }
    out.push_back(i);
  }
  return out;
}

}  // namespace kaskad::render
