// CPU-side geometry and textures of a scene. Components refer to entries by index (MeshId,
// TextureId); the renderer uploads them to the GPU on first use.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "components/bounds.h"
#include "components/mesh_renderer.h"
#include "runtime/assets/env_map.h"

namespace kaskad {

/// Indexed triangle list. positions, normals and uvs have one entry per vertex (uvs may be empty);
/// tangents are optional (xyz tangent, w handedness, glTF convention).
struct MeshData {
  std::string name;
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;
  std::vector<glm::vec2> uvs;
  std::vector<glm::vec4> tangents;
  std::vector<std::uint32_t> indices;  ///< 3 per triangle, each < positions.size()
  Aabb bounds;                         ///< of positions (computed, never taken from accessor min/max)

  std::size_t triangle_count() const { return indices.size() / 3; }
  void compute_bounds() {
    bounds = Aabb{};
    for (const auto& p : positions) bounds.expand(p);
  }
};

/// 8-bit RGBA texture. srgb: colour data (base colour, emissive) vs linear data (normal maps).
struct TextureData {
  std::string name;
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba8;  ///< width * height * 4 bytes, rows top to bottom
  bool srgb = true;
};

struct AssetStore {
  std::vector<MeshData> meshes;
  std::vector<TextureData> textures;
  /// Static reflection-probe cube maps (Reflector update static_file), loaded by
  /// instantiate_scene; an entity's StaticEnvMap names its entry.
  std::vector<CubeMap> env_maps;
  /// Identifies this store's contents for GPU caches (MeshId 0 of another scene is another
  /// mesh): unique per constructed store, kept when the store is moved.
  std::uint64_t uid = next_uid();

  MeshId add_mesh(MeshData mesh) {
    meshes.push_back(std::move(mesh));
    return MeshId(static_cast<std::uint32_t>(meshes.size() - 1));
  }
  TextureId add_texture(TextureData texture) {
    textures.push_back(std::move(texture));
    return TextureId(static_cast<std::uint32_t>(textures.size() - 1));
  }

 private:
  static std::uint64_t next_uid() {
    static std::atomic<std::uint64_t> counter{1};
    return counter.fetch_add(1, std::memory_order_relaxed);
  }
};

}  // namespace kaskad
