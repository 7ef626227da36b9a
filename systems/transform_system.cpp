#include "systems/transform_system.h"

#include <glm/gtc/matrix_transform.hpp>
#include <vector>

#include "components/mesh_renderer.h"
#include "components/name.h"
#include "components/transform.h"
#include "runtime/core/log.h"

namespace kaskad {
namespace {

// "entity 'name' (7)", or "entity 7" without a Name: how warnings name an entity.
std::string entity_label(const ecs::World& world, ecs::Entity e) {
  if (const auto* n = world.try_get<Name>(e))
    return "entity '" + n->value + "' (" + std::to_string(e.index) + ")";
  return "entity " + std::to_string(e.index);
}

// Resolves one entity's world matrix, walking up the parent chain; `state` marks entities as
// 0 = unvisited, 1 = on the current chain (cycle detection), 2 = done.
glm::mat4 resolve(ecs::World& world, ecs::Entity e, std::vector<std::uint8_t>& state) {
  if (e.index >= state.size()) state.resize(e.index + 1, 0);
  if (state[e.index] == 2) return world.get<WorldTransform>(e).matrix;
  const Transform& t = world.get<Transform>(e);
  glm::mat4 parent_matrix(1.0f);
  if (t.parent.valid()) {
    if (!world.alive(t.parent) || !world.has<Transform>(t.parent)) {
      log::warn_once("%s: parent (entity %u) is gone; treating it as a root",
                     entity_label(world, e).c_str(), t.parent.index);
    } else if (t.parent.index < state.size() && state[t.parent.index] == 1) {
      log::warn_once("%s: parent cycle through %s; treating it as a root",
                     entity_label(world, e).c_str(), entity_label(world, t.parent).c_str());
    } else {
      state[e.index] = 1;
      parent_matrix = resolve(world, t.parent, state);
    }
  }
  state[e.index] = 2;
  auto& out = world.get<WorldTransform>(e);
  out.matrix = parent_matrix * local_matrix(t);
  return out.matrix;
}

}  // namespace

glm::mat4 local_matrix(const Transform& t) {
  return glm::translate(glm::mat4(1.0f), t.translation) * glm::mat4_cast(t.rotation) *
         glm::scale(glm::mat4(1.0f), t.scale);
}

void update_transforms(ecs::World& world, const AssetStore& assets) {
  // Structural step first (adding WorldTransform where missing), then values: the view over
  // Transform is not iterated while WorldTransform components are being added.
  std::vector<ecs::Entity> entities;
  world.view<Transform>().each([&](ecs::Entity e, Transform&) { entities.push_back(e); });
  for (ecs::Entity e : entities)
    if (!world.has<WorldTransform>(e)) world.emplace<WorldTransform>(e);
  std::vector<std::uint8_t> state;
  for (ecs::Entity e : entities) resolve(world, e, state);

  std::vector<ecs::Entity> drawn;
  world.view<MeshRenderer, WorldTransform>().each(
      [&](ecs::Entity e, MeshRenderer&, WorldTransform&) { drawn.push_back(e); });
  for (ecs::Entity e : drawn) {
    const MeshRenderer& mr = world.get<MeshRenderer>(e);
    Aabb box;
    if (mr.mesh < assets.meshes.size())
      box = assets.meshes[mr.mesh].bounds.transformed(world.get<WorldTransform>(e).matrix);
    world.emplace<WorldBounds>(e, WorldBounds{box});
  }
}

Aabb scene_bounds(const ecs::World& world) {
  Aabb all;
  world.view<WorldBounds>().each([&](ecs::Entity, const WorldBounds& b) { all.expand(b.box); });
  return all;
}

}  // namespace kaskad
