// Where an entity's geometry comes from. Authored scenes name built-in primitives or glTF files;
// the scene loader turns them into meshes in the AssetStore and MeshRenderer components.
#pragma once

#include <string>
#include <vector>

#include "runtime/ecs/entity.h"

namespace kaskad {

/// Built-in unit primitives, centred at the origin; size them with Transform::scale.
/// plane: 1 x 1 in XZ facing +Y; box: 1 x 1 x 1; sphere: diameter 1; cylinder and cone: diameter 1,
/// height 1 along Y; terrain: a 1 x 1 heightfield in XZ with heights in [0, 1] (deterministic
/// fractal noise; `segments` x `segments` cells, 2 triangles each).
enum class PrimitiveShape { plane, box, sphere, cylinder, cone, terrain };

struct PrimitiveMesh {
  PrimitiveShape shape = PrimitiveShape::box;
  int segments = 32;  ///< tessellation around the axis for sphere / cylinder / cone, in [3, 1024]
  /// terrain only: split into tiles x tiles meshes (child entities of this one), so that view and
  /// cascade culling can keep parts of it; segments must be a multiple. 1 = one mesh.
  int tiles = 1;
};

/// Fields of one section of one imported glTF node set over what the file gives (scene files:
/// the model's `nodes` block; the editor and --set on the node's name). Saved from the node's
/// live component, so the values have one home: the entity.
struct NodeOverride {
  std::string node;                 ///< the imported entity's name (unique among the model's nodes)
  std::string section;              ///< transform, light, shadow, camera or renderer
  std::vector<std::string> fields;  ///< the section's fields that were set, in a stable order
  /// The block as the scene file gave it (JSON text: components do not depend on the JSON
  /// library), applied when the model is imported; saved as it is while no node has the name.
  std::string block;
  /// Where the block was read ("/entities/3/model/nodes/Wheels/transform"), for messages; empty
  /// for a node set live (messages then name "/MODEL/model/nodes/NODE/SECTION").
  std::string where;
};

/// A glTF file (.gltf or .glb) instanced under this entity; path relative to the scene file.
struct ModelRef {
  std::string path;
  std::vector<NodeOverride> nodes;  ///< by (node, section), in the order first set
};

/// A material file (content/materials/*.json) used by this entity; path relative to the scene.
/// The scene loader fills the entity's Material from it.
struct MaterialRef {
  std::string path;
};

/// Marks entities created from a ModelRef (or a built-in default); they are not written back
/// to scene files, since loading the reference recreates them.
struct Imported {
  ecs::Entity source = ecs::kNullEntity;
};

}  // namespace kaskad
