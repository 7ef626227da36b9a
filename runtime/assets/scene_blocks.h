// Internal to runtime/assets: what the parts of scene I/O share. The scene file's block readers
// and writers (scene_blocks.cpp), `--set` and node overrides (scene_overrides.cpp), glTF model
// import (model_import.cpp), instantiation (scene_instantiate.cpp) and the scene file itself
// (scene_io.cpp) each keep the rest to themselves. The public API is scene_io.h.
#pragma once

#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "components/animation.h"
#include "components/camera.h"
#include "components/light.h"
#include "components/limits.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "runtime/assets/scene.h"
#include "runtime/core/json_reader.h"
#include "runtime/result/result.h"

namespace kaskad::scene_blocks {

using json = nlohmann::json;
using json_reader::ObjectReader;

inline constexpr int kFormatVersion = 1;

/// The scene-wide setting blocks: `--set` reads a key's first part as one of them before it
/// looks for an entity, so no entity may take their names.
inline constexpr std::array<const char*, 2> kSettingSections = {"render", "shadow"};

/// The ways of giving a transform's rotation; a block takes any one of them.
inline constexpr std::array<const char*, 4> kRotationKeys = {"rotation", "euler_deg", "look_at",
                                                            "direction"};
/// The sections a model's node block may hold (a glTF node has no reflector).
inline constexpr std::array<const char*, 5> kNodeSections = {"transform", "light", "shadow",
                                                             "camera", "renderer"};

// --- Block readers and writers (scene_blocks.cpp): one per component block, shared by scene
// files, `--set` and node overrides. Readers validate (table ranges, then cross-field rules).
void read_shadow(ObjectReader& r, ShadowSettings& s);
/// Every field, or with `defaults` only those that differ.
json write_shadow(const ShadowSettings& s, const ShadowSettings* defaults);
void read_transform(ObjectReader& r, Transform& t);
void read_render(ObjectReader& r, RenderSettings& s);
void read_renderer(ObjectReader& r, MeshRenderer& m);
/// Returns whether the block says cast_shadows.
bool read_light(ObjectReader& r, Light& l);
void read_camera(ObjectReader& r, Camera& c);
/// An inline material block: the built-in parameters, features derived from the values.
Material read_inline_material(ObjectReader& r);

/// An entity's `transform.parent`, resolved once every entity of the file is read.
struct Pending {
  ecs::Entity entity;
  std::string parent;
  std::string where;
};
/// The first directional light of a file, and whether its block says cast_shadows.
struct FirstSun {
  ecs::Entity entity = ecs::kNullEntity;
  bool cast_shadows_given = false;
};
/// Reads entity block `j` (at JSON pointer `path`) into a new entity of scene.world.
void parse_entity(const json& j, const std::string& path, Scene& scene,
                  std::map<std::string, ecs::Entity>& by_name, std::vector<Pending>& parents,
                  FirstSun& first_sun);
/// Entity e as a scene file's entity block; paths relative to `base` (empty: as they are).
json entity_to_json(const Scene& scene, ecs::Entity e, const std::filesystem::path& base);
/// A path relative to the scene file, rebased to `base` (a scene written somewhere else).
std::string rebase_path(const Scene& scene, const std::filesystem::path& base,
                        const std::string& path);
/// Creation order.
inline bool entity_less(ecs::Entity a, ecs::Entity b) { return a.index < b.index; }

// --- Overrides (scene_overrides.cpp).
/// Whether the first part of `key` names a settings section or an entity of the document.
bool document_holds(const json& doc, const std::string& key);
/// Reads `block` over entity e's `section` with the scene file's reader for it (validated, the
/// fields it does not name kept). False for a section a loaded entity does not take.
bool read_section(ecs::World& w, ecs::Entity e, const std::string& section, const json& block,
                  const std::string& where);
/// The entities imported for model entity `model` that are named `node`.
std::vector<ecs::Entity> nodes_named(const ecs::World& w, ecs::Entity model,
                                     const std::string& node);
/// A model entity's `animation` block: clip name -> AnimationState fields (those given set;
/// a clip given is posed at its time next frame). Errors name an unknown clip with the valid ones.
void read_animation(ObjectReader& r, Animator& a);
/// Which time write_animation() gives a playing clip: its clock now (the editor's timeline,
/// --set acting on the live state) or the time it was last set to (a saved file).
enum class ClipTime { now, as_set };
/// Every clip with every field.
json write_animation(const Animator& a, ClipTime time);
/// A model's `nodes` block: node name -> section -> fields, checked for shape; the values are
/// read when the model is imported, over what its file gives.
std::vector<NodeOverride> read_node_overrides(const json& nodes, const std::string& where);
/// The `nodes` block written for model entity `model`.
json write_node_overrides(const Scene& scene, ecs::Entity model);

// --- glTF model import (model_import.cpp).
/// A model file's first import: the model entity and the entities imported under it
/// (Imported{first}), in entity order.
struct FirstImport {
  ecs::Entity first;
  std::vector<ecs::Entity> made;
};
/// Imports entity e's glTF model (ModelRef): the meshes take e's renderer flags and layer, the
/// lights the scene's shadow settings. `imported` (file -> the first entity that imported it):
/// a file imported before is copied from that entity's import instead of read again. Returns
/// the entities it made. `blame` (file and place) is named first when the model cannot be
/// imported; by default the scene file's entity.
Result<std::vector<ecs::Entity>> import_model(Scene& scene, ecs::Entity e,
                                              bool activate_first_camera,
                                              std::map<std::string, FirstImport>* imported = nullptr,
                                              const std::optional<Error>& blame = std::nullopt);
/// The scene's own settings of model entity e's nodes (model.nodes; `made`: what its import
/// made), over what the file gives.
Status apply_node_overrides(Scene& scene, ecs::Entity e, const std::vector<ecs::Entity>& made);

}  // namespace kaskad::scene_blocks
