// Instantiation: the environment map, materials, primitive meshes, imported models and the
// ground of a parsed scene; adding and removing entities of a loaded scene.
#include "runtime/assets/scene_io.h"

#include <algorithm>

#include "components/name.h"
#include "components/probe_state.h"
#include "components/reflector.h"
#include "runtime/assets/env_lighting.h"
#include "runtime/assets/material_file.h"
#include "runtime/assets/primitives.h"
#include "runtime/assets/reflector_io.h"
#include "runtime/assets/scene_blocks.h"
#include "runtime/core/log.h"

namespace kaskad {

using namespace scene_blocks;

namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;
using json_reader::ContentError;
using json_reader::fail;

}  // namespace

Status load_environment(Scene& scene) {
  const std::string& file = scene.render.environment;
  if (file == scene.environment_loaded && (file.empty() || scene.environment_map != Scene::kNoEnvironment))
    return {};
  static std::uint64_t serial = 0;
  if (file.empty()) {
    scene.environment_map = Scene::kNoEnvironment;
  } else {
    EnvLoadOptions options;
    options.face_size = kEnvironmentFaceSize;
    auto cube = load_cube_map(scene.file.parent_path() / file, options);
    if (!cube) return Error{scene.file.string(), "/render/environment", cube.error().to_string()};
    // A reloaded map reuses its slot (the store keeps earlier ids valid otherwise).
    if (scene.environment_map != Scene::kNoEnvironment &&
        scene.environment_map < scene.assets.env_maps.size()) {
      scene.assets.env_maps[scene.environment_map] = std::move(cube.value());
    } else {
      scene.assets.env_maps.push_back(std::move(cube.value()));
      scene.environment_map = std::uint32_t(scene.assets.env_maps.size() - 1);
    }
    scene.environment_sh = project_sh9(scene.assets.env_maps[scene.environment_map]);
  }
  scene.environment_loaded = file;
  scene.environment_serial = ++serial;
  return {};
}

Status instantiate_scene(Scene& scene, const render::FeatureManifest* manifest) {
  ecs::World& w = scene.world;
  std::vector<std::pair<ecs::Entity, MaterialRef>> material_refs;
  w.view<MaterialRef>().each([&](ecs::Entity e, MaterialRef& r) { material_refs.emplace_back(e, r); });
  // Each material file is read once: the entities that name it share its textures (and so
  // can share draws), where reading it per entity made a copy of every texture for each.
  std::map<std::filesystem::path, Material> loaded;
  for (auto& [e, ref] : material_refs) {
    if (!manifest)
      return Error{scene.file.string(), "", "material files need the feature manifest"};
    const std::filesystem::path file = scene.file.parent_path() / ref.path;
    std::error_code ec;
    const std::filesystem::path key = std::filesystem::weakly_canonical(file, ec);
    auto it = loaded.find(ec ? file : key);
    if (it == loaded.end()) {
      auto m = load_material_file(file, *manifest, scene.assets);
      if (!m) return m.error();
      it = loaded.emplace(ec ? file : key, *m).first;
    }
    w.emplace<Material>(e, it->second);
  }
  KASKAD_TRY(load_environment(scene));
  // Static reflection maps (S3 (a)): loaded once here; the probe system uploads them once.
  std::vector<std::pair<ecs::Entity, Reflector>> static_probes;
  w.view<Reflector>().each([&](ecs::Entity e, Reflector& r) {
    if (r.update == ProbeUpdate::static_file) static_probes.emplace_back(e, r);
  });
  for (auto& [e, r] : static_probes) {
    auto cube = load_static_env_map(scene.file.parent_path() / r.file, r);
    if (!cube) return cube.error();
    scene.assets.env_maps.push_back(std::move(cube.value()));
    w.emplace<StaticEnvMap>(e, StaticEnvMap{std::uint32_t(scene.assets.env_maps.size() - 1)});
  }
  std::vector<std::pair<ecs::Entity, PrimitiveMesh>> prims;
  std::vector<std::pair<ecs::Entity, ModelRef>> models;
  w.view<PrimitiveMesh>().each([&](ecs::Entity e, PrimitiveMesh& p) { prims.emplace_back(e, p); });
  w.view<ModelRef>().each([&](ecs::Entity e, ModelRef& m) { models.emplace_back(e, m); });
  // One mesh per distinct (shape, segments): instances share it.
  std::map<std::pair<int, int>, MeshId> shared;
  for (auto& [e, p] : prims) {
    if (p.tiles > 1) {
      // Tile (0, 0) on the entity itself, the others on imported children with its renderer
      // flags and material (not written back: the primitive recreates them).
      const MeshRenderer flags = w.get<MeshRenderer>(e);
      // A copy: emplacing into the Material pool may move the entity's own component.
      const std::optional<Material> material =
          w.has<Material>(e) ? std::optional<Material>(w.get<Material>(e)) : std::nullopt;
      for (int tz = 0; tz < p.tiles; ++tz)
        for (int tx = 0; tx < p.tiles; ++tx) {
          const MeshId mesh = scene.assets.add_mesh(make_terrain_tile(p.segments, p.tiles, tx, tz));
          if (tx == 0 && tz == 0) {
            w.get<MeshRenderer>(e).mesh = mesh;
            continue;
          }
          const ecs::Entity tile = w.create();
          Transform t;
          t.parent = e;
          w.emplace<Transform>(tile, t);
          MeshRenderer mr = flags;
          mr.mesh = mesh;
          w.emplace<MeshRenderer>(tile, mr);
          if (material) w.emplace<Material>(tile, *material);
          w.emplace<Imported>(tile, Imported{e});
        }
      continue;
    }
    auto key = std::make_pair(int(p.shape), p.segments);
    auto it = shared.find(key);
    if (it == shared.end())
      it = shared.emplace(key, scene.assets.add_mesh(make_primitive(p.shape, p.segments))).first;
    w.get<MeshRenderer>(e).mesh = it->second;
  }
  std::map<std::string, FirstImport> imported;  // each file is read once (copy_import)
  std::vector<std::vector<ecs::Entity>> made;
  for (auto& model : models) {
    auto m = import_model(scene, model.first, /*activate_first_camera=*/true, &imported);
    if (!m) return m.error();
    made.push_back(std::move(m.value()));
  }
  for (std::size_t i = 0; i < models.size(); ++i)
    KASKAD_TRY(apply_node_overrides(scene, models[i].first, made[i]));
  return {};
}

Aabb ground_extent(const Aabb& models, const glm::vec3& light_direction) {
  KASKAD_CHECK(!models.empty(), "needs non-empty bounds");
  const float y = models.min.y;
  const float size = std::max(glm::length(models.extent()), 1e-6f);
  // Where the corners' shadows land on the plane y = min.y; lights lower than about 14 degrees
  // above the horizon are taken as 14 degrees (a shadow 4x the model's height long).
  const glm::vec3 l = glm::length(light_direction) > 0.0f ? glm::normalize(light_direction)
                                                           : glm::vec3(0, -1, 0);
  const float down = std::max(-l.y, 0.25f);
  const glm::vec2 along = glm::length(glm::vec2(l.x, l.z)) > 0.0f
                              ? glm::normalize(glm::vec2(l.x, l.z)) * std::sqrt(1.0f - down * down)
                              : glm::vec2(0.0f);
  Aabb out;
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 c{(i & 1) ? models.max.x : models.min.x, (i & 2) ? models.max.y : models.min.y,
                      (i & 4) ? models.max.z : models.min.z};
    const glm::vec2 hit = glm::vec2(c.x, c.z) + along * ((c.y - y) / down);
    out.expand(glm::vec3(c.x, y, c.z));
    out.expand(glm::vec3(hit.x, y, hit.y));
  }
  // A margin of a quarter of the model's size around footprint and shadow.
  out.min -= glm::vec3(0.25f * size, 0.0f, 0.25f * size);
  out.max += glm::vec3(0.25f * size, 0.0f, 0.25f * size);
  // Just under the lowest point, so that a flat bottom does not fight with the ground.
  out.min.y = out.max.y = y - 1e-4f * size;
  return out;
}

ecs::Entity add_ground(Scene& scene, const Aabb& extent) {
  ecs::World& w = scene.world;
  bool taken = false;
  w.view<Name>().each([&](ecs::Entity, const Name& n) { taken = taken || n.value == "ground"; });
  const ecs::Entity e = w.create();
  w.emplace<Name>(e, Name{taken ? "kaskad_ground" : "ground"});
  Transform t;
  t.translation = extent.center();
  t.scale = {std::max(extent.max.x - extent.min.x, 1e-6f), 1.0f,
             std::max(extent.max.z - extent.min.z, 1e-6f)};
  w.emplace<Transform>(e, t);
  MeshRenderer mr;
  mr.mesh = scene.assets.add_mesh(make_primitive(PrimitiveShape::plane, PrimitiveMesh{}.segments));
  mr.cast_shadows = false;  // nothing lies below it
  mr.receive_shadows = true;
  w.emplace<MeshRenderer>(e, mr);
  Material m;
  // Neutral grey, dark enough that the default glTF sun (2.5) does not clip it to white.
  m.base_color = glm::vec4(0.25f, 0.25f, 0.25f, 1.0f);
  m.roughness = 0.9f;
  w.emplace<Material>(e, m);
  w.emplace<Imported>(e, Imported{ecs::kNullEntity});  // made by the load, not saved
  return e;
}

Result<ecs::Entity> add_entity(Scene& scene, const json& given, const std::string& where,
                               const fs::path& source_file) {
  ecs::World& w = scene.world;
  const fs::path source = source_file.empty() ? scene.file : source_file;
  // A model path is relative to the file the block comes from; the entity keeps it relative
  // to the scene's folder, as a scene file's own models are.
  json block = given;
  if (source != scene.file && block.is_object() && block.contains("model") &&
      block["model"].is_object() && block["model"].contains("path") &&
      block["model"]["path"].is_string()) {
    const fs::path model =
        fs::absolute(source.parent_path() / block["model"]["path"].get<std::string>());
    const fs::path rel =
        model.lexically_normal().lexically_relative(fs::absolute(scene.file.parent_path()));
    block["model"]["path"] = (rel.empty() ? model.lexically_normal() : rel).generic_string();
  }
  std::map<std::string, ecs::Entity> by_name;
  w.view<Name>().each([&](ecs::Entity e, const Name& n) { by_name.emplace(n.value, e); });
  try {
    // Checked on a scratch scene first, so a bad block leaves the live one untouched.
    Scene scratch;
    scratch.file = scene.file;
    scratch.shadow_defaults = scene.shadow_defaults;
    std::map<std::string, ecs::Entity> scratch_names = by_name;
    std::vector<Pending> parents;
    FirstSun sun;
    parse_entity(block, where, scratch, scratch_names, parents, sun);
    for (const Pending& p : parents)
      if (!by_name.count(p.parent)) fail(p.where, "no entity named '" + p.parent + "'");
    if (!block.is_object() || !block.contains("name") || !block["name"].is_string())
      fail(where + "/name", "an added entity needs a name");
    bool material_file = false;
    scratch.world.view<MaterialRef>().each([&](ecs::Entity, const MaterialRef&) { material_file = true; });
    if (material_file)
      fail(where + "/material", "an added entity takes an inline material, not a material file");
    bool tiled = false;
    scratch.world.view<PrimitiveMesh>().each(
        [&](ecs::Entity, const PrimitiveMesh& pm) { tiled = tiled || pm.tiles > 1; });
    if (tiled) fail(where + "/primitive/tiles", "an added terrain cannot be tiled");
  } catch (const ContentError& e) {
    return Error{source.string(), e.where, e.message};
  }
  std::vector<Pending> parents;
  FirstSun sun;
  parse_entity(block, where, scene, by_name, parents, sun);  // checked above: cannot fail
  const ecs::Entity e = by_name.at(block.at("name").get<std::string>());
  for (const Pending& p : parents) w.get<Transform>(p.entity).parent = by_name.at(p.parent);
  if (const auto* pm = w.try_get<PrimitiveMesh>(e))
    w.get<MeshRenderer>(e).mesh = scene.assets.add_mesh(make_primitive(pm->shape, pm->segments));
  if (w.has<ModelRef>(e)) {
    // A model that cannot be imported, or a nodes block its file refuses, leaves no entity.
    auto made = import_model(scene, e, /*activate_first_camera=*/false, nullptr,
                             Error{source.string(), where + "/model/path", ""});
    Status st = made ? apply_node_overrides(scene, e, made.value()) : Status(made.error());
    if (!st) {
      (void)remove_entity(scene, block.at("name").get<std::string>());
      return st.error();
    }
  }
  return e;
}

Status remove_entity(Scene& scene, const std::string& name) {
  ecs::World& w = scene.world;
  ecs::Entity target = ecs::kNullEntity;
  w.view<Name>().each([&](ecs::Entity e, const Name& n) {
    if (n.value == name && !target.valid()) target = e;
  });
  if (!target.valid()) return Error{scene.file.string(), "", "no entity named '" + name + "' to remove"};
  // The entity, everything parented below it and everything imported for it.
  std::vector<ecs::Entity> doomed{target};
  for (std::size_t i = 0; i < doomed.size(); ++i) {
    const ecs::Entity root = doomed[i];
    w.view<Transform>().each([&](ecs::Entity e, const Transform& t) {
      const auto* imp = w.try_get<Imported>(e);
      if ((t.parent == root || (imp && imp->source == root)) &&
          std::find(doomed.begin(), doomed.end(), e) == doomed.end())
        doomed.push_back(e);
    });
  }
  for (ecs::Entity e : doomed) w.destroy(e);
  return {};
}

}  // namespace kaskad
