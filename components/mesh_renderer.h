// Draws one mesh of the scene's AssetStore with the entity's Material.
#pragma once

#include <cstdint>

namespace kaskad {

/// Index into AssetStore::meshes; kNoMesh when unset.
using MeshId = std::uint32_t;
/// Index into AssetStore::textures; kNoTexture when unset.
using TextureId = std::uint32_t;
inline constexpr MeshId kNoMesh = 0xffffffffu;
inline constexpr TextureId kNoTexture = 0xffffffffu;

struct MeshRenderer {
  MeshId mesh = kNoMesh;
  bool cast_shadows = true;     ///< drawn into shadow maps
  bool receive_shadows = true;  ///< shadow maps are sampled when shading it
  int layer = 0;                ///< render layer in [0, 31]; Reflector::exclude_layers masks it
};

}  // namespace kaskad
