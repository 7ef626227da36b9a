// Where an entity's geometry comes from. Authored scenes name built-in primitives or glTF files;
// the scene loader turns them into meshes in the AssetStore and MeshRenderer components.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "runtime/ecs/entity.h"
#include "runtime/fields/fields.h"

namespace kaskad {

/// Built-in unit primitives, centred at the origin; size them with Transform::scale.
/// plane: 1 x 1 in XZ facing +Y; box: 1 x 1 x 1; sphere: diameter 1; cylinder and cone: diameter 1,
/// height 1 along Y; terrain: a 1 x 1 heightfield in XZ with heights in [0, 1] (deterministic
/// fractal noise; `segments` x `segments` cells, 2 triangles each).
enum class PrimitiveShape { plane, box, sphere, cylinder, cone, terrain };
constexpr std::array<std::string_view, 6> enum_names(PrimitiveShape) {
  return {"plane", "box", "sphere", "cylinder", "cone", "terrain"};
}
static_assert(enum_names(PrimitiveShape{}).size() == std::size_t(PrimitiveShape::terrain) + 1);

struct PrimitiveMesh {
  PrimitiveShape shape = PrimitiveShape::box;
  int segments = 32;  ///< tessellation around the axis for sphere / cylinder / cone, in [3, 1024]
  /// terrain only: split into tiles x tiles meshes (child entities of this one), so that view and
  /// cascade culling can keep parts of it; segments must be a multiple. 1 = one mesh.
  int tiles = 1;
};

/// The fields of PrimitiveMesh, once (runtime/fields/fields.h); tiles' rules across fields are
/// the scene reader's.
constexpr auto field_table(fields::Of<PrimitiveMesh>) {
  using P = PrimitiveMesh;
  using namespace fields;
  return std::tuple{
      choice("shape", &P::shape, "The built-in unit primitive"),
      integer("segments", &P::segments, 3, 1024, "Tessellation (around the axis; terrain: cells a side)"),
      integer("tiles", &P::tiles, 1, 64, "Terrain: split into tiles x tiles meshes; segments a multiple"),
  };
}

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
  /// The entity's `animation` block as the scene file gave it (JSON text), applied to the
  /// model's Animator once it is imported, and where it was read; empty: none.
  std::string animation;
  std::string animation_where;
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
