// Draws one mesh of the scene's AssetStore with the entity's Material.
#pragma once

#include <cstddef>
#include <cstdint>
#include <tuple>
#include <type_traits>

#include "runtime/fields/fields.h"

namespace kaskad {

/// Index into AssetStore::meshes; kNoMesh when unset. Distinct types, so a TextureId passed where
/// a MeshId belongs does not compile; `MeshId{3}` makes one, index() turns one back into an
/// index. Enums: comparisons, std::hash and map keys come for free.
enum class MeshId : std::uint32_t {};
/// Index into AssetStore::textures; kNoTexture when unset.
enum class TextureId : std::uint32_t {};
inline constexpr MeshId kNoMesh{0xffffffffu};
inline constexpr TextureId kNoTexture{0xffffffffu};

/// The position of the entry an id names (kNo*: 0xffffffff, beyond every store).
constexpr std::size_t index(MeshId id) { return static_cast<std::size_t>(id); }
constexpr std::size_t index(TextureId id) { return static_cast<std::size_t>(id); }
static_assert(!std::is_convertible_v<MeshId, TextureId> && !std::is_convertible_v<TextureId, MeshId>);
static_assert(!std::is_convertible_v<std::uint32_t, MeshId> && !std::is_convertible_v<MeshId, std::size_t>);

struct MeshRenderer {
  MeshId mesh = kNoMesh;
  bool cast_shadows = true;     ///< drawn into shadow maps
  bool receive_shadows = true;  ///< shadow maps are sampled when shading it
  int layer = 0;                ///< render layer in [0, 31]; Reflector::exclude_layers masks it
};

/// The authored fields of MeshRenderer, once (runtime/fields/fields.h).
constexpr auto field_table(fields::Of<MeshRenderer>) {
  using M = MeshRenderer;
  using namespace fields;
  return std::tuple{
      flag("cast_shadows", &M::cast_shadows, "Drawn into shadow maps"),
      flag("receive_shadows", &M::receive_shadows, "Shadow maps are sampled when shading it"),
      integer("layer", &M::layer, 0, 31, "Render layer; a reflector's exclude_layers masks it"),
  };
}

}  // namespace kaskad
