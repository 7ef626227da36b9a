// Living content: glTF animation clips played on a model, morph weights, and meshes deformed by
// skins and morph targets. The glTF importer creates these; the AnimationSystem
// (systems/animation_system.h) plays clips into Transform and MorphWeights, the DeformSystem
// poses Deformer entities (joint matrices, conservative bounds) for the deform pass.
#pragma once

#include <cstdint>
#include <string>
#include <tuple>
#include <vector>

#include <glm/glm.hpp>

#include "components/bounds.h"
#include "components/mesh_renderer.h"
#include "runtime/ecs/entity.h"
#include "runtime/fields/fields.h"

namespace kaskad {

/// How one clip of a model plays. Time is in the clip's seconds; a frame advances it by the
/// frame's dt times `speed` (a deterministic clock: nothing reads the wall clock).
struct AnimationState {
  bool playing = false;  ///< advanced every frame; a stopped clip holds its pose
  bool loop = true;      ///< past the end, time wraps to the start (else it stops at the end)
  float speed = 1.0f;    ///< clip seconds per frame second
  float time = 0.0f;     ///< seconds into the clip
};

/// The fields of AnimationState, once (runtime/fields/fields.h): a scene file's
/// `"animation": {"CLIP": {...}}` block and --set ENTITY.animation.CLIP.FIELD.
constexpr auto field_table(fields::Of<AnimationState>) {
  using A = AnimationState;
  using namespace fields;
  return std::tuple{
      flag("playing", &A::playing, "Advanced every frame; a stopped clip holds its pose"),
      flag("loop", &A::loop, "Past the end, time wraps to the start (else it stops at the end)"),
      number("speed", &A::speed, -100, 100, "Clip seconds per frame second"),
      number("time", &A::time, 0, 1.0e6, "Seconds into the clip"),
  };
}

/// On a model entity whose glTF file has animations: one state per clip of the file
/// (AssetStore::animations[first_clip + k]), and the entities of the file's nodes that channels
/// drive (by glTF node index; null for nodes outside the imported scene). The first clip plays,
/// looping, unless the scene says otherwise.
struct Animator {
  std::uint32_t first_clip = 0;
  std::vector<AnimationState> clips;
  std::vector<std::string> names;  ///< each clip's name (unique: AnimationClip::name)
  std::vector<ecs::Entity> nodes;
  /// Per clip, what a scene file or --set last gave it: the time it was set to, which a save
  /// writes for a playing clip (its clock is not authored: save, load, save is the same file),
  /// and whether that pose is still to be shown once (a stopped clip posed where it was set).
  struct Cue {
    float time = 0.0f;
    bool pending = false;
  };
  std::vector<Cue> cues;
};

/// Morph-target weights of a glTF node (node.weights, else its mesh's weights); animations
/// write them. The node's primitive entities read them through their parent.
struct MorphWeights {
  std::vector<float> weights;
};

/// On a primitive entity whose mesh is skinned or morphed: the inputs of its pose, and the mesh
/// it is drawn with, its own copy of MeshRenderer::mesh that the deform pass writes each frame.
/// Skinned poses are in world space (glTF: the skinned node's own transform is ignored), morphed
/// ones in mesh space.
struct Deformer {
  static constexpr std::uint32_t kNoSkin = ~0u;
  std::uint32_t skin = kNoSkin;    ///< AssetStore::skins index
  std::vector<ecs::Entity> joints;  ///< one per skin joint
  MeshId posed = kNoMesh;           ///< allocated by the DeformSystem on first use
  /// Per joint, the box of the vertices it moves in the joint's bind space (computed once):
  /// a pose's bounds are the union of these boxes through the joint matrices.
  std::vector<Aabb> joint_boxes;
  /// This frame's pose (update_deformers()): the skin matrices (joint world x inverse bind),
  /// the morph weights, and their hash (DrawItem::pose; never 0).
  std::vector<glm::mat4> skin_matrices;
  std::vector<float> weights;
  std::uint64_t pose = 0;
};

}  // namespace kaskad
