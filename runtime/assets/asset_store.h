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
#include "runtime/math/keyframes.h"

namespace kaskad {

/// What deforms a mesh on the GPU (glTF 2.0, 3.7.3 "Skins" and 3.7.2.2 "Morph Targets"): the
/// deform pass (runtime/render/deform_pass.h) poses it into its entity's own copy every frame,
/// and pose_mesh() (runtime/math/skinning.h) does the same on the CPU for the references.
struct MeshDeform {
  /// Joint influences per vertex: 0 (not skinned), 4 (JOINTS_0 / WEIGHTS_0) or 8 (with
  /// JOINTS_1 / WEIGHTS_1). `joints` indexes the skin's joints; weights sum to 1 per vertex.
  int influences = 0;
  std::vector<std::uint32_t> joints;  ///< influences per vertex
  std::vector<float> weights;         ///< influences per vertex
  /// Morph targets: displacements per vertex (normals and tangents zero where the target gives
  /// none; tangents only when the mesh has tangents), and each target's box of position
  /// displacements (the origin included), for conservative bounds.
  struct Target {
    std::vector<glm::vec3> positions, normals, tangents;
    Aabb delta_bounds;
  };
  std::vector<Target> targets;
  std::vector<float> default_weights;  ///< glTF mesh.weights (one per target; zeros when absent)

  bool skinned() const { return influences > 0; }
  bool morphed() const { return !targets.empty(); }
  bool any() const { return skinned() || morphed(); }
};

/// Indexed triangle list. positions, normals and uvs have one entry per vertex (uvs and uvs1 may
/// be empty); tangents are optional (xyz tangent, w handedness, glTF convention).
struct MeshData {
  std::string name;
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;
  std::vector<glm::vec2> uvs;   ///< TEXCOORD_0
  std::vector<glm::vec2> uvs1;  ///< TEXCOORD_1
  std::vector<glm::vec4> tangents;
  std::vector<std::uint32_t> indices;  ///< 3 per triangle, each < positions.size()
  Aabb bounds;                         ///< of positions (computed, never taken from accessor min/max)
  MeshDeform deform;                   ///< skin weights and morph targets (none for most meshes)

  std::size_t triangle_count() const { return indices.size() / 3; }
  /// The uvs a texture slot of set `set` (TextureTransform::tex_coord) reads: set 1 is uvs1 when
  /// the mesh has them, else uvs (a mesh without TEXCOORD_1 gives every slot its first set).
  const std::vector<glm::vec2>& uv_set(int set) const {
    return set == 1 && uvs1.size() == positions.size() ? uvs1 : uvs;
  }
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

/// glTF skin: a joint's inverse bind matrix takes mesh space to the joint's space at bind time
/// (the joints themselves are entities: Deformer::joints).
struct SkinData {
  std::string name;
  std::vector<glm::mat4> inverse_bind;  ///< one per joint
};

/// What an animation channel drives on its node (glTF animation.channels[].target.path).
enum class AnimatedPath : std::uint8_t { translation, rotation, scale, weights };

/// One glTF animation: channels, each a keyframe track driving one path of one node. `node`
/// indexes the Animator's node entities (the file's node order).
struct AnimationClip {
  struct Channel {
    std::uint32_t node = 0;
    AnimatedPath path = AnimatedPath::translation;
    /// translation, rotation, scale: one track (xyz or a quaternion). weights: one scalar
    /// track (x) per morph target, since a node may have more targets than a vec4 holds.
    std::vector<KeyTrack> tracks;
  };
  std::string name;
  std::vector<Channel> channels;
  float duration = 0.0f;  ///< the last key time of any channel, seconds
};

struct AssetStore {
  std::vector<MeshData> meshes;
  std::vector<TextureData> textures;
  /// Static reflection-probe cube maps (Reflector update static_file), loaded by
  /// instantiate_scene; an entity's StaticEnvMap names its entry.
  std::vector<CubeMap> env_maps;
  std::vector<SkinData> skins;           ///< Deformer::skin indexes it
  std::vector<AnimationClip> animations; ///< AnimationState::clip indexes it
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
