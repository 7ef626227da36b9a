// Material files (JSON, content/materials/): features, typed parameters and textures, validated
// against the feature manifest (kFeatureTable and content/shaders/features.json). Format:
// docs/guide/materials.md.
#pragma once

#include <cstdint>
#include <filesystem>

#include "components/material.h"
#include "runtime/assets/asset_store.h"
#include "runtime/result/result.h"
#include "runtime/features/feature_manifest.h"

namespace kaskad {

/// Reads a material file; textures (paths relative to the file) are loaded into `assets` through
/// OpenImageIO. Errors name the file and key: unknown feature or parameter, wrong type, value out
/// of range, contradictory features (excludes / requires), a parameter or texture whose feature is
/// not listed, a listed texture feature without its texture, unreadable texture images.
Result<Material> load_material_file(const std::filesystem::path& file,
                                    const render::FeatureManifest& manifest, AssetStore& assets);

/// VariantKey material bits implied by a material's data (loaders without a material file: glTF,
/// inline scene materials): textures present, alpha mode (mask or blend), non-zero emission; the emissive
/// texture only with emission (it multiplies the factor); the texture transform when a texture
/// in use has a non-identity one.
inline std::uint32_t derive_material_features(const Material& m) {
  using render::VariantKey;
  std::uint32_t bits = 0;
  bool transformed = false;
  auto uses = [&](TextureId texture, const TextureTransform& t) {
    if (texture == kNoTexture) return false;
    transformed = transformed || !(t == TextureTransform{});
    return true;
  };
  if (uses(m.base_color_texture, m.base_color_transform))
    bits |= VariantKey::kBaseColorTexture.mask();
  if (uses(m.normal_texture, m.normal_transform)) bits |= VariantKey::kNormalMap.mask();
  if (uses(m.occlusion_texture, m.occlusion_transform))
    bits |= VariantKey::kOcclusionTexture.mask();
  if (uses(m.metallic_roughness_texture, m.metallic_roughness_transform))
    bits |= VariantKey::kMetallicRoughnessTexture.mask();
  if (m.alpha_mode == AlphaMode::mask) bits |= VariantKey::kAlphaMask.mask();
  if (m.alpha_mode == AlphaMode::blend) bits |= VariantKey::kAlphaBlend.mask();
  if (m.emissive.r > 0.0f || m.emissive.g > 0.0f || m.emissive.b > 0.0f) {
    bits |= VariantKey::kEmissive.mask();
    if (uses(m.emissive_texture, m.emissive_transform)) bits |= VariantKey::kEmissiveTexture.mask();
  }
  if (transformed) bits |= VariantKey::kTextureTransform.mask();
  return bits;
}

}  // namespace kaskad
