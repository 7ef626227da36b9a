// glTF 2.0 import (.gltf and .glb) through tinygltf, with KHR_draco_mesh_compression,
// KHR_lights_punctual and cameras. Textures are decoded through OpenImageIO.
#pragma once

#include <filesystem>

#include "runtime/assets/asset_store.h"
#include "runtime/result/result.h"
#include "runtime/ecs/world.h"

namespace kaskad {

struct GltfImportReport {
  int nodes = 0;          ///< node entities created
  int mesh_entities = 0;  ///< one entity per glTF primitive instance (triangles only)
  int lights = 0;
  int cameras = 0;
  int skins = 0;       ///< skins bound to a mesh
  int animations = 0;  ///< clips imported
  int morphed = 0;     ///< primitive entities with morph targets
  /// Triangles of the meshes added to the AssetStore; a mesh used by several nodes counts once.
  std::size_t triangles = 0;
  /// Skipped primitives (points, lines), unsupported features, textures that failed to load.
  std::vector<std::string> warnings;
};

/// Imports the default scene of a glTF file (or all root nodes when there is no default) into
/// `world` and `assets`. Every node becomes an entity with Name, Transform (parent = the node's
/// parent entity, or `parent` for root nodes) and Imported{source}; each triangle primitive becomes
/// a child entity with MeshRenderer, Material and Imported; KHR_lights_punctual lights become
/// Light (+ ShadowSettings for directional lights, cast_shadows = true) and cameras Camera
/// components on their node's entity. The first imported camera is marked active when
/// `activate_first_camera` is set.
/// Conversions: spot cone angles and yfov become degrees; an infinite perspective zfar becomes
/// far = 1000 * near; missing normals are generated flat (glTF 3.7.2.1), missing uvs and tangents
/// stay empty; strips and fans become triangle lists. Everything read from the file is validated;
/// a texture that cannot be loaded is a warning, not an error.
/// On error the entities created so far stay in `world` (there is no rollback): callers discard
/// the world.
Result<GltfImportReport> import_gltf(const std::filesystem::path& path, ecs::World& world,
                                     AssetStore& assets, ecs::Entity parent, ecs::Entity source,
                                     bool activate_first_camera);

}  // namespace kaskad
