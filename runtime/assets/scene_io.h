// Scene files (JSON, content/scenes/) and direct glTF scenes.
//
// Loading is three steps so that `--set` overrides act on the same canonical document that
// save_scene() writes:
//   read_scene_document  file -> JSON (a .gltf/.glb is wrapped into a one-entity scene)
//   parse_scene          JSON -> Scene with the authored entities only (validated, no file I/O)
//   instantiate_scene    primitives -> meshes, glTF references -> imported entities
// load_scene (runtime/app/player.h) runs all three plus the load phase (transforms, auto cameras).
// The format is documented in docs/guide/scenes.md; the fields in docs/reference/settings.md.
// The implementation is split by job: scene_io.cpp (the file), scene_blocks.cpp (block readers
// and writers), scene_overrides.cpp (--set), model_import.cpp, scene_instantiate.cpp.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "components/bounds.h"
#include "runtime/assets/scene.h"
#include "runtime/result/result.h"
#include "runtime/features/feature_manifest.h"

namespace kaskad {

/// Reads a .json scene, or wraps a .gltf/.glb file: its entity plus, when the file has none of its
/// own, a camera named "camera" (auto_frame) and a directional light named "sun".
Result<nlohmann::json> read_scene_document(const std::filesystem::path& file);

/// Applies one "key=value" override to a canonical document. Keys: "render.FIELD",
/// "shadow.FIELD", or "ENTITY.SECTION.FIELD" (e.g. "sun.light.intensity"); array elements by
/// index ("box.transform.translation.1"). The value is JSON, or a bare string. Unknown keys are
/// errors that list the valid keys at that level.
Status apply_override(nlohmann::json& document, const std::string& assignment);

/// Builds the authored part of a scene from a document. Errors name `file` and the JSON path.
Result<Scene> parse_scene(const nlohmann::json& document, const std::filesystem::path& file);

/// read_scene_document, then (when there are overrides) canonicalise and apply them in order,
/// then parse_scene. Errors after overrides say so. With `deferred`, overrides whose first part
/// names no section or entity of the document are put there instead of failing: they may name
/// an entity made later (a glTF node, the ground), for apply_entity_override().
Result<Scene> read_scene(const std::filesystem::path& file,
                         const std::vector<std::string>& overrides = {},
                         std::vector<std::string>* deferred = nullptr);

/// The entity an "ENTITY.SECTION.FIELD" key names: the longest entity name followed by '.' that
/// starts the key (glTF names may hold dots), which only one entity may have. Errors list the
/// names (or say how many share it).
Result<ecs::Entity> entity_for_key(const Scene& scene, const std::string& key);

/// Applies one "ENTITY.SECTION.FIELD=value" override to an entity of an instantiated scene by its
/// Name (the longest name that starts the key, so glTF names with dots work): sections transform
/// (rotation also as euler_deg, look_at or direction), light, shadow, camera and renderer, read
/// and validated as in scene files. Unknown or ambiguous names are errors that list the names.
Status apply_entity_override(Scene& scene, const std::string& assignment);

/// The model entity that imported e, when e is one of a glTF model's nodes; else the null entity
/// (authored entities, and what the load makes on its own: the ground, a terrain's tiles).
ecs::Entity model_of(const ecs::World& world, ecs::Entity e);

/// Records that `fields` of `section` were set on entity e, when e is a node a glTF model entity
/// imported: scene_to_json() then writes their values, as e has them, in that model's
/// `nodes` block (apply_entity_override() records its own edits; the editor's fly camera, which
/// moves the active camera directly, calls this). Does nothing for other entities.
void note_node_override(Scene& scene, ecs::Entity e, const std::string& section,
                        const std::vector<std::string>& fields);

/// Entity e's sections as apply_entity_override() sets them: transform (without its parent),
/// light, shadow (every field), camera, renderer, reflector, as scene files write them; with
/// the other sections it has (material, primitive, model), which only a document edit changes.
nlohmann::json live_entity_sections(const Scene& scene, ecs::Entity e);

/// Loads material files (validated against `manifest`; required when the scene has any), creates
/// meshes for primitives and imports glTF references (paths relative to scene.file). Cameras with
/// auto_frame are framed by the load phase (load_scene in runtime/app/player.h).
Status instantiate_scene(Scene& scene, const render::FeatureManifest* manifest = nullptr);

/// render.environment's faces, texels a side (any layout is resampled to this).
inline constexpr int kEnvironmentFaceSize = 256;
/// Loads render.environment (relative to scene.file) into scene.assets.env_maps when it is not
/// the map loaded last (instantiate_scene and render overrides call it). Errors name the file
/// and the problem, at /render/environment; the scene is unchanged on error.
Status load_environment(Scene& scene);

/// One --set assignment on a loaded scene, between frames (playback timelines, the editor):
/// "render.FIELD" and "shadow.FIELD" (every light takes a new scene-wide shadow value unless it
/// overrides that field, as at load) by a round trip through the canonical document, entity
/// keys by apply_entity_override(). Validated as in scene files; the scene is unchanged on error.
/// render.width/height change the setting only (the player's targets keep their size).
Status apply_live_override(Scene& scene, const std::string& assignment);

/// Adds an entity from a scene file's entity block (`where` is its JSON path for messages) to a
/// loaded scene between frames: validated as in scene files (a bad block leaves the scene
/// unchanged), its primitive meshed, its model imported. It needs a unique name; material files
/// and tiled terrains are not taken (inline materials are). `source` is the file the block comes
/// from (a playback file): errors name it, and a model path is relative to its folder; empty
/// means the scene file.
Result<ecs::Entity> add_entity(Scene& scene, const nlohmann::json& block, const std::string& where,
                               const std::filesystem::path& source = {});

/// Removes the entity named `name`, everything parented below it and everything imported for it.
Status remove_entity(Scene& scene, const std::string& name);

/// Where a ground for `models` (their world bounds) goes: a flat box at min.y (a hair below)
/// covering their footprint and the shadow their bounds cast along `light_direction` (lights
/// below about 14 degrees of elevation count as 14), with a margin of a quarter of their size.
Aabb ground_extent(const Aabb& models, const glm::vec3& light_direction);

/// Adds a receive-only, non-casting plane in neutral grey over `extent`, named "ground" (or
/// "kaskad_ground" when that name is taken), not written by scene_to_json (it is remade from
/// render.ground at load).
ecs::Entity add_ground(Scene& scene, const Aabb& extent);

/// The canonical document of the authored entities and settings (imported entities excluded).
/// With a `base_dir`, model paths are rewritten relative to it (for a file written there);
/// without, they stay relative to scene.file.
nlohmann::json scene_to_json(const Scene& scene, const std::filesystem::path& base_dir = {});

/// Writes scene_to_json() with two-space indentation. Written to a temporary file first and then
/// renamed, so a failure never leaves a half-written scene behind.
Status save_scene(const std::filesystem::path& file, const Scene& scene);

}  // namespace kaskad
