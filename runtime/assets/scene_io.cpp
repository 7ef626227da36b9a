// Scene files: reading a document (a .gltf/.glb wrapped into a scene), parsing it into the
// authored entities, writing the canonical form and saving it.
#include "runtime/assets/scene_io.h"

#include <algorithm>
#include <cstdint>
#include <map>
#include <vector>

#include "components/name.h"
#include "runtime/assets/gltf_loader.h"
#include "runtime/assets/scene_blocks.h"
#include "runtime/core/field_io.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"

namespace kaskad {

using namespace scene_blocks;

namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;
using field_io::write_fields;
using json_reader::ContentError;
using json_reader::fail;
using json_reader::parse_json_file;
using json_reader::type_name;

}  // namespace

Result<json> read_scene_document(const fs::path& file) {
  const std::string ext = lowercase_extension(file);
  if (ext == ".gltf" || ext == ".glb") {
    // Inspect the file for its own lights and cameras; the real import happens in instantiate.
    Scene probe;
    auto report = import_gltf(file, probe.world, probe.assets, ecs::kNullEntity, ecs::kNullEntity,
                              false);
    if (!report) return report.error();
    // A bare model gets a ground to catch its shadow; saved as "on", so the saved scene file
    // renders the same.
    json doc = {{"kaskad_scene", kFormatVersion},
                {"render", {{"ground", "on"}}},
                {"entities", json::array()}};
    doc["entities"].push_back({{"name", "model"}, {"model", {{"path", file.filename().string()}}}});
    if (report->cameras == 0) {
      // Default camera: looks at the model from the front, slightly above; auto_frame backs it
      // off until the bounds fit.
      doc["entities"].push_back(
          {{"name", "camera"},
           {"transform", {{"direction", {-0.45, -0.35, -0.82}}}},
           {"camera", {{"auto_frame", true}, {"active", true}}}});
    }
    if (report->lights == 0) {
      doc["entities"].push_back(
          {{"name", "sun"},
           {"transform", {{"direction", {0.3, -0.75, -0.6}}}},
           {"light", {{"type", "directional"}, {"intensity", 2.5}, {"cast_shadows", true}}}});
    }
    return doc;
  }
  if (ext != ".json")
    return Error{file.string(), "", "unknown scene file type '" + ext + "' (expected .json, .gltf or .glb)"};
  return parse_json_file(file);
}

Result<Scene> parse_scene(const json& doc, const fs::path& file) {
  Scene scene;
  scene.file = file;
  try {
    ObjectReader root(doc, "");
    int version = kFormatVersion;
    if (root.has("kaskad_scene") && root.raw("kaskad_scene").is_number_integer()) {
      const long long written = root.raw("kaskad_scene").get<long long>();
      if (written > kFormatVersion)
        fail(root.at("kaskad_scene"),
             "format version " + std::to_string(written) + " is newer than this build reads (" +
                 std::to_string(kFormatVersion) + "): written by a later Kaskad?");
    }
    root.integer("kaskad_scene", version, 1, kFormatVersion);
    std::string schema;  // "$schema": the file's JSON Schema, for editors (`kaskad schema`)
    root.string("$schema", schema);
    if (root.has("render")) {
      ObjectReader r(root.raw("render"), "/render");
      read_render(r, scene.render);
    }
    if (root.has("shadow")) {
      ObjectReader r(root.raw("shadow"), "/shadow");
      read_shadow(r, scene.shadow_defaults);
    }
    std::map<std::string, ecs::Entity> by_name;
    std::vector<Pending> parents;
    FirstSun first_sun;
    if (root.has("entities")) {
      const json& ents = root.raw("entities");
      if (!ents.is_array()) fail("/entities", "expected an array, got " + type_name(ents));
      for (std::size_t i = 0; i < ents.size(); ++i)
        parse_entity(ents[i], "/entities/" + std::to_string(i), scene, by_name, parents,
                     first_sun);
    }
    // A scene's first directional light casts shadows unless its block says false: a new
    // scene shows shadows before its author has found the field.
    if (first_sun.entity.valid() && !first_sun.cast_shadows_given)
      scene.world.get<Light>(first_sun.entity).cast_shadows = true;
    root.finish();
    for (const Pending& p : parents) {
      auto it = by_name.find(p.parent);
      if (it == by_name.end()) fail(p.where, "no entity named '" + p.parent + "'");
      if (it->second == p.entity) fail(p.where, "an entity cannot be its own parent");
      scene.world.get<Transform>(p.entity).parent = it->second;
    }
    // Parent cycles (a -> b -> a) are content errors here, with the names, rather than a
    // warning from the transform system every frame. Each entity is walked once (a chain as
    // long as the scene stays linear): 1 = on the walk now, 2 = reaches a root, 3 = on a cycle.
    std::vector<std::uint8_t> state;
    auto parent_of = [&](ecs::Entity e) {
      const Transform* t = scene.world.try_get<Transform>(e);
      return t ? t->parent : ecs::kNullEntity;
    };
    auto state_of = [&](ecs::Entity e) -> std::uint8_t& {
      if (e.index >= state.size()) state.resize(std::size_t{e.index} + 1, 0);
      return state[e.index];
    };
    std::vector<ecs::Entity> walk;
    for (const Pending& p : parents) {
      walk.clear();
      ecs::Entity at = p.entity;
      for (; at.valid() && state_of(at) == 0; at = parent_of(at)) {
        state_of(at) = 1;
        walk.push_back(at);
      }
      const bool closes = at.valid() && state_of(at) == 1;
      for (ecs::Entity e : walk) state_of(e) = 2;
      if (closes)  // the walk from `at` on is the cycle
        for (ecs::Entity e = at; state_of(e) != 3; e = parent_of(e)) state_of(e) = 3;
    }
    // The first entity on a cycle, in file order, names it (from itself round to itself; a long
    // one by its first and last few entities).
    for (const Pending& p : parents) {
      if (state_of(p.entity) != 3) continue;
      std::map<ecs::Entity, std::string, bool (*)(ecs::Entity, ecs::Entity)> names(entity_less);
      for (const auto& [n, e] : by_name) names[e] = n;
      std::vector<ecs::Entity> cycle{p.entity};
      for (ecs::Entity at = parent_of(p.entity); at != p.entity; at = parent_of(at))
        cycle.push_back(at);
      cycle.push_back(p.entity);
      constexpr std::size_t kShown = 4;  // at each end
      std::string chain;
      for (std::size_t i = 0; i < cycle.size(); ++i) {
        if (cycle.size() > 2 * kShown + 1 && i == kShown) {
          chain += " -> ... (" + std::to_string(cycle.size() - 2 * kShown) + " more)";
          i = cycle.size() - kShown - 1;
          continue;
        }
        chain += (i ? " -> " : "") + names[cycle[i]];
      }
      fail(p.where, "parent cycle: " + chain);
    }
  } catch (const ContentError& e) {
    return Error{file.string(), e.where, e.message};
  } catch (const json::exception& e) {
    return Error{file.string(), "", e.what()};
  }
  return scene;
}

json scene_to_json(const Scene& scene, const fs::path& base_dir) {
  json doc;
  doc["kaskad_scene"] = kFormatVersion;
  const RenderSettings& r = scene.render;
  doc["render"] = write_fields(r);
  doc["render"]["environment"] = rebase_path(scene, base_dir, r.environment);
  doc["shadow"] = write_shadow(scene.shadow_defaults, nullptr);
  std::vector<ecs::Entity> authored;
  scene.world.view<Transform>().each([&](ecs::Entity e, const Transform&) {
    if (!scene.world.has<Imported>(e)) authored.push_back(e);
  });
  std::sort(authored.begin(), authored.end(), entity_less);  // creation order
  json ents = json::array();
  for (ecs::Entity e : authored) ents.push_back(entity_to_json(scene, e, base_dir));
  doc["entities"] = ents;
  return doc;
}

Status save_scene(const fs::path& file, const Scene& scene) {
  KASKAD_TRY(check_output_path(file));  // before the work, and with a clear word for a folder
  const fs::path dir = folder_of(file);
  return write_file_atomic(file, scene_to_json(scene, dir).dump(2) + "\n");
}

Result<Scene> read_scene(const fs::path& file, const std::vector<std::string>& overrides,
                         std::vector<std::string>* deferred) {
  auto doc = read_scene_document(file);
  if (!doc) return doc.error();
  if (!overrides.empty()) {
    // Overrides act on the canonical form, where every field is present with its value.
    auto first = parse_scene(*doc, file);
    if (!first) return first.error();
    json canonical = scene_to_json(*first);
    for (const auto& o : overrides) {
      if (deferred && !document_holds(canonical, o.substr(0, o.find('='))))
        deferred->push_back(o);  // an imported entity, perhaps: apply_entity_override
      else
        KASKAD_TRY(apply_override(canonical, o));
    }
    doc = std::move(canonical);
  }
  auto scene = parse_scene(*doc, file);
  if (!scene) {
    Error e = scene.error();
    if (!overrides.empty()) e.message += " (after --set overrides)";
    return e;
  }
  return scene;
}

}  // namespace kaskad
