// Internal to runtime/assets: what the parts of the glTF import share. gltf_parse.cpp reads and
// parses the file (limits, GLB container, tinygltf, images given by URI); gltf_geometry.cpp
// reads accessors, decodes Draco and converts primitives to meshes; gltf_materials.cpp converts
// materials and textures; gltf_loader.cpp walks the node hierarchy into entities. The public API
// is gltf_loader.h.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "components/material.h"
#include "components/mesh_renderer.h"
#include "runtime/assets/gltf_loader.h"
#include "runtime/assets/tinygltf_config.h"
#include "runtime/result/result.h"

namespace kaskad::gltf_detail {

/// Limits on what a file may ask for (guards against absurd or hostile values).
/// tinygltf takes sizes as unsigned int; 1 GiB is far above any model we expect.
inline constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t(1) << 30;
/// Elements per accessor (vertices or indices): 2^26 = 67M; a buffer view also has to hold them.
inline constexpr std::uint64_t kMaxAccessorElements = std::uint64_t(1) << 26;
/// Accessors without a buffer view are implicitly zero (plus sparse values): nothing in the file
/// backs their count, so a few bytes of JSON could ask for gigabytes. 2^20 elements.
inline constexpr std::uint64_t kMaxImplicitElements = std::uint64_t(1) << 20;
/// glTF's infinite perspective projection (zfar absent) becomes far = near * this ratio, which
/// keeps depth precision usable and gives cascaded shadows a finite range to split.
inline constexpr float kInfiniteFarOverNear = 1000.0f;

// --- gltf_parse.cpp
/// "meshes[3] \"name\"": a place in the file, for messages.
std::string label(const char* array, int index, const std::string& name = {});
/// A non-negative integer that fits an int (JSON numbers may arrive as reals).
bool as_index(const tinygltf::Value& v, int& out);
/// object[key], or null when object is not an object or lacks the key (tinygltf asserts on
/// Get() of a wrongly typed Value).
const tinygltf::Value* member(const tinygltf::Value& object, const char* key);
bool all_finite(const std::vector<double>& values);
/// Whether Kaskad implements extension `name` (a file that requires another is refused).
bool supported_extension(std::string_view name);

/// Shared with tinygltf's image callback through its user pointer.
struct ImageLoadState {
  std::map<int, std::string> failures;  ///< image index -> why it has no pixels
};

/// Parses .gltf or .glb (told apart by the "glTF" magic, not the extension).
Result<tinygltf::Model> parse_file(const std::filesystem::path& path, ImageLoadState& images,
                                   std::vector<std::string>& warnings);

// --- gltf_geometry.cpp
/// Address of `count` elements of `element_size` bytes, `stride` bytes apart, starting `offset`
/// bytes into buffer view `view_index`, after checking the whole range lies inside the view and
/// the view inside its buffer. Null when count is 0.
Result<const std::uint8_t*> locate(const tinygltf::Model& model, const std::string& file,
                                   int view_index, std::uint64_t offset, std::uint64_t count,
                                   std::uint64_t element_size, std::uint64_t stride,
                                   const std::string& where);
/// Accessor `index` as `components` floats per element (normalised integers mapped, sparse
/// values substituted), every range checked; `where` names the use in errors.
Result<std::vector<float>> read_float_accessor(const tinygltf::Model& model,
                                               const std::string& file, int index,
                                               int components, const std::string& where);
/// Converts one primitive. nullopt (with a warning) for primitives that are skipped: points,
/// lines, or no triangles at all.
Result<std::optional<MeshData>> read_primitive(const tinygltf::Model& model,
                                               const std::string& file, int mesh_index,
                                               int prim_index, std::vector<std::string>& warnings);

// --- gltf_loader.cpp
/// A converted primitive: its mesh in the AssetStore and its glTF material index.
struct ImportedPrimitive {
  MeshId mesh = kNoMesh;
  int material = -1;
  int primitive = 0;
};

/// State of one import; meshes, materials and textures are converted once, on first use.
struct Importer {
  const tinygltf::Model& model;
  std::string file;
  ecs::World& world;
  AssetStore& assets;
  ecs::Entity source;
  bool activate_first_camera = false;
  GltfImportReport report;
  ImageLoadState images;

  std::map<int, std::vector<ImportedPrimitive>> meshes;
  std::map<int, Material> materials;
  std::map<std::pair<int, bool>, TextureId> textures;  ///< (image, srgb) -> texture
  std::set<int> failed_images;                         ///< warned about once
  bool camera_activated = false;
  /// Entity of each glTF node (null for nodes outside the imported scene): skin joints and
  /// animation channels name nodes.
  std::vector<ecs::Entity> node_entities;
  /// Primitive entities of skinned nodes, bound to their skin once every node exists.
  struct SkinnedPrimitive {
    ecs::Entity entity;
    int node = -1;
    MeshId mesh = kNoMesh;
  };
  std::vector<SkinnedPrimitive> skinned;
};

// --- gltf_animation.cpp
/// Binds the skinned primitives to their skins (AssetStore::skins, converted once each) and
/// imports the file's animations into AssetStore::animations with an Animator on the model
/// entity. After every node has its entity.
Status import_skins_and_animations(Importer& im);

// --- gltf_materials.cpp
/// glTF metallic-roughness material -> Material. -1 gives glTF's default material (3.9.6).
Result<Material> read_material(Importer& im, int index);

}  // namespace kaskad::gltf_detail
