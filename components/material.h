// Surface description, glTF 2.0 metallic-roughness inputs mapped onto the engine's lighting model
// (see content/shaders/forward.frag for the mapping). Linear colour values.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string_view>
#include <tuple>


#include <glm/glm.hpp>

#include "components/mesh_renderer.h"
#include "runtime/fields/fields.h"

namespace kaskad {

/// Which uvs one texture slot reads: the mesh's uv set `tex_coord` (glTF texCoord: TEXCOORD_0 or
/// TEXCOORD_1), through KHR_texture_transform's uv' = T(offset) R(rotation) S(scale) uv, i.e.
/// u' = s.x cos(r) u + s.y sin(r) v + offset.x, v' = -s.x sin(r) u + s.y cos(r) v + offset.y.
struct TextureTransform {
  glm::vec2 offset{0.0f};  ///< uv units
  float rotation = 0.0f;   ///< radians, counter-clockwise in uv space
  glm::vec2 scale{1.0f};
  std::uint8_t tex_coord = 0;  ///< the uv set (MeshData::uv_set())

  bool operator==(const TextureTransform&) const = default;
};

/// The two rows (a, b) of t's affine map: u' = dot(a, (u, v, 1)), v' = dot(b, (u, v, 1)).
inline std::array<glm::vec3, 2> uv_transform_rows(const TextureTransform& t) {
  const float c = std::cos(t.rotation), s = std::sin(t.rotation);
  return {glm::vec3(c * t.scale.x, s * t.scale.y, t.offset.x),
          glm::vec3(-s * t.scale.x, c * t.scale.y, t.offset.y)};
}

/// t's affine map applied to uv (of the set t.tex_coord), as the shaders' slot_uv() does.
inline glm::vec2 transform_uv(const TextureTransform& t, glm::vec2 uv) {
  const auto r = uv_transform_rows(t);
  return {glm::dot(r[0], glm::vec3(uv, 1.0f)), glm::dot(r[1], glm::vec3(uv, 1.0f))};
}

/// How a reflector's probe map reaches the surface (docs/guide/materials.md, "What a material's
/// inputs do"). s3: S3 eq. (3), the
/// surface's own shading plus k_s p_r times the mirror-direction lookup (exact, compared with the
/// ray-traced reference). pbr: the probe lights the glTF BRDF like an environment map (its SH
/// irradiance and GGX-prefiltered radiance, components/ibl.h), blended with the scene's
/// environment by p_r; k_s is not used.
enum class ReflectionModel : std::uint8_t { s3, pbr };
constexpr std::array<std::string_view, 2> enum_names(ReflectionModel) { return {"s3", "pbr"}; }
static_assert(enum_names(ReflectionModel{}).size() == std::size_t(ReflectionModel::pbr) + 1);

/// glTF alphaMode: what the base colour's alpha (factor x texture) does (docs/guide/materials.md,
/// "Transparency"). opaque: nothing. mask: a cut-out, discarded where alpha < alpha_cutoff.
/// blend: drawn after the opaque draws, back to front, over what is behind it (premultiplied:
/// colour x alpha + behind x (1 - alpha)); it casts shadows where alpha >= alpha_cutoff, in the
/// shadow maps and the ray-traced reference alike.
enum class AlphaMode : std::uint8_t { opaque, mask, blend };
constexpr std::array<std::string_view, 3> enum_names(AlphaMode) { return {"opaque", "mask", "blend"}; }
static_assert(enum_names(AlphaMode{}).size() == std::size_t(AlphaMode::blend) + 1);

/// KHR_materials_transmission drawn as blending (there is no refraction): the opacity of a
/// surface with base colour alpha `base_alpha` and transmissionFactor `transmission`, which
/// falls linearly from base_alpha at no transmission to kTransmissionOpacityFloor x base_alpha
/// at full transmission. The floor keeps a fully transmissive surface (glass) visible: blending
/// scales the whole shading, highlights and reflections included, by the opacity, so at 0 the
/// surface would vanish.
inline constexpr float kTransmissionOpacityFloor = 0.2f;
constexpr float transmission_opacity(float base_alpha, float transmission) {
  return base_alpha * (1.0f - transmission * (1.0f - kTransmissionOpacityFloor));
}

struct Material {
  glm::vec4 base_color{1.0f};                  ///< linear RGBA factor (glTF baseColorFactor)
  TextureId base_color_texture = kNoTexture;   ///< sRGB texture, multiplied by base_color
  float metallic = 0.0f;                       ///< [0,1] (glTF metallicFactor)
  float roughness = 0.5f;                      ///< [0,1] (glTF roughnessFactor)
  TextureId normal_texture = kNoTexture;       ///< tangent-space normal map (optional)
  float normal_scale = 1.0f;                   ///< glTF normalTexture.scale
  glm::vec3 emissive{0.0f};                    ///< linear emitted radiance (x emissive strength)
  TextureId emissive_texture = kNoTexture;     ///< sRGB texture, multiplied by emissive
  TextureId occlusion_texture = kNoTexture;    ///< linear; R is the ambient occlusion
  float occlusion_strength = 1.0f;             ///< glTF occlusionTexture.strength, [0,1]
  /// glTF metallicRoughnessTexture: linear; B times `metallic`, G times `roughness`.
  TextureId metallic_roughness_texture = kNoTexture;
  /// KHR_texture_transform per texture slot (identity: none).
  TextureTransform base_color_transform, normal_transform, occlusion_transform, emissive_transform,
      metallic_roughness_transform;
  bool double_sided = false;                   ///< glTF doubleSided: light both faces
  AlphaMode alpha_mode = AlphaMode::opaque;    ///< glTF alphaMode
  /// glTF alphaCutoff of a mask; a blended material casts shadows where alpha >= it (glTF
  /// ignores alphaCutoff outside MASK: imported blended materials keep 0.5).
  float alpha_cutoff = 0.5f;
  /// S3's k_s, the specular level that scales a reflection map's colour (eq. (3)), in [0, 1].
  /// Used only on entities with a Reflector. 1: a mirror.
  float k_s = 1.0f;
  ReflectionModel reflection_model = ReflectionModel::s3;
  /// Shader features this material uses, as VariantKey material bits (runtime/render/
  /// variant_key.h). Material files list them; other loaders call derive_material_features()
  /// (runtime/assets/material_file.h).
  std::uint32_t features = 0;

  bool operator==(const Material&) const = default;
};

/// The fields of Material a scene file's inline material block gives, once
/// (runtime/fields/fields.h); textures come from glTF and material files.
constexpr auto field_table(fields::Of<Material>) {
  using M = Material;
  using namespace fields;
  return std::tuple{
      vector("base_color", &M::base_color, 0, 1.0e4, "Linear RGBA factor"),
      number("metallic", &M::metallic, 0, 1, "Metallic factor"),
      number("roughness", &M::roughness, 0, 1, "Perceptual roughness"),
      vector("emissive", &M::emissive, 0, 1.0e6, "Linear emitted radiance"),
      flag("double_sided", &M::double_sided, "Lights both faces"),
      choice("alpha_mode", &M::alpha_mode,
             "What the base colour's alpha does: nothing, a cut-out at alpha_cutoff, or blending"),
      number("alpha_cutoff", &M::alpha_cutoff, 0, 1,
             "Mask: alpha below it is cut away; blend: alpha at or above it casts shadows"),
      number("k_s", &M::k_s, 0, 1, "Specular level scaling a reflection map's colour (S3's k_s)"),
      choice("reflection_model", &M::reflection_model,
             "How a reflector's probe reaches the surface: S3's mirror term or the PBR BRDF"),
  };
}

}  // namespace kaskad
