// glTF model import for scene entities: a file's first import, copies for later instances, and
// the scene's own settings of the imported nodes.
#include <system_error>

#include "components/name.h"
#include "runtime/assets/gltf_loader.h"
#include "runtime/assets/scene_blocks.h"
#include "runtime/core/log.h"

namespace kaskad::scene_blocks {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;
using json_reader::ContentError;

// Gives entity e a copy of `originals`, the entities an earlier import made under `first`: the
// same meshes, textures and materials, so N instances of one model load and upload it once and
// draw it instanced. Parents are remapped into the copy; copied cameras are not active. Returns
// the copies. (Scanning every Imported entity per copy made loading N instances O(N^2);
// docs/design/large_scenes.md, "Loading many instances".)
std::vector<ecs::Entity> copy_import(ecs::World& w, const FirstImport& from, ecs::Entity e) {
  const ecs::Entity first = from.first;
  const std::vector<ecs::Entity>& originals = from.made;
  auto key = [](ecs::Entity x) { return (std::uint64_t(x.generation) << 32) | x.index; };
  std::map<std::uint64_t, ecs::Entity> copy_of;  // every copy first, so any parent maps
  std::vector<ecs::Entity> copies;
  for (ecs::Entity original : originals) copies.push_back(copy_of[key(original)] = w.create());
  // An entity of the first import as its copy here (others, and null, as they are).
  auto remap = [&](ecs::Entity x) {
    const auto it = copy_of.find(key(x));
    return it == copy_of.end() ? x : it->second;
  };
  for (ecs::Entity original : originals) {
    const ecs::Entity c = copy_of[key(original)];
    w.emplace<Imported>(c, Imported{e});
    if (const auto* n = w.try_get<Name>(original)) w.emplace<Name>(c, *n);
    if (const auto* t = w.try_get<Transform>(original)) {
      Transform copy = *t;
      if (copy.parent == first) {
        copy.parent = e;
      } else if (auto it = copy_of.find(key(copy.parent)); it != copy_of.end()) {
        copy.parent = it->second;
      }
      w.emplace<Transform>(c, copy);
    }
    if (const auto* m = w.try_get<MeshRenderer>(original)) w.emplace<MeshRenderer>(c, *m);
    if (const auto* m = w.try_get<Material>(original)) w.emplace<Material>(c, *m);
    if (const auto* l = w.try_get<Light>(original)) w.emplace<Light>(c, *l);
    if (const auto* sh = w.try_get<ShadowSettings>(original)) w.emplace<ShadowSettings>(c, *sh);
    if (const auto* cam = w.try_get<Camera>(original)) {
      Camera copy = *cam;
      copy.active = false;
      w.emplace<Camera>(c, copy);
    }
    if (const auto* mw = w.try_get<MorphWeights>(original)) w.emplace<MorphWeights>(c, *mw);
    if (const auto* d = w.try_get<Deformer>(original)) {
      Deformer copy = *d;
      for (ecs::Entity& j : copy.joints) j = remap(j);
      copy.posed = kNoMesh;  // each instance poses its own copy
      w.emplace<Deformer>(c, std::move(copy));
    }
  }
  // The model's clips play on each instance's own nodes.
  if (const auto* a = w.try_get<Animator>(first)) {
    Animator copy = *a;
    for (ecs::Entity& n : copy.nodes) n = remap(n);
    w.emplace<Animator>(e, std::move(copy));
  }
  return copies;
}

}  // namespace

Result<std::vector<ecs::Entity>> import_model(
    Scene& scene, ecs::Entity e, bool activate_first_camera,
    std::map<std::string, FirstImport>* imported, const std::optional<Error>& blame) {
  ecs::World& w = scene.world;
  const fs::path path = scene.file.parent_path() / w.get<ModelRef>(e).path;
  std::error_code ec;
  const std::string file_key = fs::weakly_canonical(path, ec).string();
  const auto earlier = imported ? imported->find(file_key) : std::map<std::string, FirstImport>::iterator{};
  std::vector<ecs::Entity> made;  // the entities imported under e
  if (imported && earlier != imported->end()) {
    made = copy_import(w, earlier->second, e);
  } else {
    auto report = import_gltf(path, w, scene.assets, e, e, activate_first_camera);
    if (!report) {
      if (blame) return Error{blame->file, blame->where, report.error().to_string()};
      // A scene file's model: the scene and the entity come first, then the model's own error.
      if (lowercase_extension(scene.file) != ".json")
        return report.error();  // a glTF opened directly: its own error says it all
      const std::string name = w.has<Name>(e) ? w.get<Name>(e).value : std::string("?");
      return Error{scene.file.string(), "/" + name + "/model/path", report.error().to_string()};
    }
    // Once each: the editor reloads the scene on every undo.
    for (const auto& warning : report->warnings)
      log::warn_once("%s: %s", path.string().c_str(), warning.c_str());
    w.view<Imported>().each([&](ecs::Entity x, const Imported& imp) {
      if (imp.source == e) made.push_back(x);
    });
    std::sort(made.begin(), made.end(), entity_less);
    if (imported) imported->emplace(file_key, FirstImport{e, made});
  }
  // The model entity's renderer flags apply to everything imported under it; the scene's shadow
  // settings to the model's own lights as to any other (a glTF has none of its own); --set
  // ENTITY.shadow.* on the imported light refines them afterwards.
  const MeshRenderer flags = w.get<MeshRenderer>(e);
  std::vector<ecs::Entity> lights;
  for (ecs::Entity x : made) {
    if (auto* mr = w.try_get<MeshRenderer>(x)) {
      mr->cast_shadows = flags.cast_shadows;
      mr->receive_shadows = flags.receive_shadows;
      mr->layer = flags.layer;
    }
    if (w.has<Light>(x)) lights.push_back(x);
  }
  for (ecs::Entity l : lights) {
    if (w.has<ShadowSettings>(l))
      w.get<ShadowSettings>(l) = scene.shadow_defaults;
    else
      w.emplace<ShadowSettings>(l, scene.shadow_defaults);
  }
  return made;
}

// The scene's own settings of model entity e's nodes (model.nodes; `made`: what its import
// made), over what the file gives. After every import of a load: a later instance of the file
// is copied from the first one's entities, which must not carry the first one's settings yet. A
// name no node has is kept as it is for saving: the file may have changed since.
Status apply_node_overrides(Scene& scene, ecs::Entity e, const std::vector<ecs::Entity>& made) {
  ecs::World& w = scene.world;
  if (const ModelRef& ref = w.get<ModelRef>(e); !ref.animation.empty()) {
    const std::string where = ref.animation_where;
    if (!w.has<Animator>(e))
      return Error{scene.file.string(), where, ref.path + " has no animations"};
    const json block = json::parse(ref.animation, nullptr, /*allow_exceptions=*/false);
    try {
      Animator a = w.get<Animator>(e);
      ObjectReader r(block, where);
      read_animation(r, a);
      w.get<Animator>(e) = std::move(a);
    } catch (const ContentError& err) {
      return Error{scene.file.string(), err.where, err.message};
    }
  }
  const fs::path path = scene.file.parent_path() / w.get<ModelRef>(e).path;
  const std::string model_name = w.has<Name>(e) ? w.get<Name>(e).value : std::string();
  const std::vector<NodeOverride> overrides = w.get<ModelRef>(e).nodes;  // a copy: pools move
  for (const NodeOverride& o : overrides) {
    const std::string where =
        o.where.empty() ? "/" + model_name + "/model/nodes/" + o.node + "/" + o.section : o.where;
    std::vector<ecs::Entity> found;
    for (ecs::Entity x : made)
      if (const auto* n = w.try_get<Name>(x); n && n->value == o.node) found.push_back(x);
    if (found.empty()) {
      log::warn_once("%s: %s: %s has no node named '%s'; its settings are kept for saving",
                     scene.file.string().c_str(), where.c_str(), path.string().c_str(),
                     o.node.c_str());
      continue;
    }
    if (found.size() > 1)
      return Error{scene.file.string(), where,
                   std::to_string(found.size()) + " nodes of " + path.string() + " are named '" +
                       o.node + "'; only a unique name can be set"};
    const json block = json::parse(o.block, nullptr, /*allow_exceptions=*/false);
    try {
      if (!read_section(w, found.front(), o.section, block, where))
        return Error{scene.file.string(), where,
                     "node '" + o.node + "' has no " + o.section + " in " + path.string()};
    } catch (const ContentError& err) {
      return Error{scene.file.string(), err.where, err.message};
    }
  }
  return {};
}

}  // namespace kaskad::scene_blocks
