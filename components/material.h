// Surface description, glTF 2.0 metallic-roughness inputs mapped onto the engine's lighting model
// (see content/shaders/forward.frag for the mapping). Linear colour values.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "components/mesh_renderer.h"

namespace kaskad {

struct Material {
  glm::vec4 base_color{1.0f};                  ///< linear RGBA factor (glTF baseColorFactor)
  TextureId base_color_texture = kNoTexture;   ///< sRGB texture, multiplied by base_color
  float metallic = 0.0f;                       ///< [0,1] (glTF metallicFactor)
  float roughness = 0.5f;                      ///< [0,1] (glTF roughnessFactor)
  TextureId normal_texture = kNoTexture;       ///< tangent-space normal map (optional)
  float normal_scale = 1.0f;                   ///< glTF normalTexture.scale
  glm::vec3 emissive{0.0f};                    ///< linear emitted radiance
  bool double_sided = false;                   ///< glTF doubleSided: light both faces
  bool alpha_mask = false;                     ///< glTF alphaMode MASK: discard below alpha_cutoff
  float alpha_cutoff = 0.5f;                   ///< glTF alphaCutoff
  /// S3's k_s, the specular level that scales a reflection map's colour (eq. (3)), in [0, 1].
  /// Used only on entities with a Reflector. 1: a mirror.
  float k_s = 1.0f;
  /// Shader features this material uses, as VariantKey material bits (runtime/render/
  /// variant_key.h). Material files list them; other loaders call derive_material_features()
  /// (runtime/assets/material_file.h).
  std::uint32_t features = 0;

  bool operator==(const Material&) const = default;
};

}  // namespace kaskad
