#include "systems/transform_system.h"

#include <atomic>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>
#include <vector>

#include "components/mesh_renderer.h"
#include "components/name.h"
#include "components/transform.h"
#include "components/transform_cache.h"
#include "runtime/core/log.h"

namespace kaskad {
namespace {

// "entity 'name' (7)", or "entity 7" without a Name: how warnings name an entity.
std::string entity_label(const ecs::World& world, ecs::Entity e) {
  if (const auto* n = world.try_get<Name>(e))
    return "entity '" + n->value + "' (" + std::to_string(e.index) + ")";
  return "entity " + std::to_string(e.index);
}

// A new TransformCache::version, unique in the process (like CommandBuffer's serials), so that a
// recomputed parent never shows a version its children already recorded, whatever world or slot
// it lives in. Starts at 1: 0 means "never computed".
std::uint64_t next_version() {
  static std::atomic<std::uint64_t> counter{1};
  return counter.fetch_add(1, std::memory_order_relaxed);
}

// Bitwise equality: the same bits in give the same matrix out (NaN included), and -0 vs +0 counts
// as a change, so a skipped entity keeps exactly what a recompute would have written.
template <class T>
bool same_bits(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}
static_assert(sizeof(Transform) == 3 * sizeof(glm::vec3) + sizeof(float) + sizeof(ecs::Entity),
              "Transform has padding: same_bits would compare indeterminate bytes");
static_assert(sizeof(Aabb) == 2 * sizeof(glm::vec3), "Aabb has padding");

// Brings one entity's WorldTransform up to date, parent chain first, and returns its version;
// `state` marks entities as 0 = unvisited, 1 = on the current chain (cycle detection), 2 = done.
// The parent applied is decided exactly as when everything was recomputed each call (same order,
// same cycle breaking); the matrix is recomputed only when that parent, its version or this
// entity's Transform bits differ from the TransformCache.
std::uint64_t resolve(ecs::World& world, ecs::Entity e, std::vector<std::uint8_t>& state,
                      TransformStats& stats) {
  if (state[e.index] == 2) return world.get<TransformCache>(e).version;
  const Transform& t = world.get<Transform>(e);
  ecs::Entity parent = ecs::kNullEntity;
  std::uint64_t parent_version = 0;
  if (t.parent.valid()) {
    if (!world.alive(t.parent) || !world.has<Transform>(t.parent)) {
      log::warn_once("%s: parent (entity %u) is gone; treating it as a root",
                     entity_label(world, e).c_str(), t.parent.index);
    } else if (state[t.parent.index] == 1) {
      log::warn_once("%s: parent cycle through %s; treating it as a root",
                     entity_label(world, e).c_str(), entity_label(world, t.parent).c_str());
    } else {
      state[e.index] = 1;
      parent_version = resolve(world, t.parent, state, stats);
      parent = t.parent;
    }
  }
  state[e.index] = 2;
  TransformCache& cache = world.get<TransformCache>(e);
  if (cache.version != 0 && cache.parent == parent && cache.parent_version == parent_version &&
      same_bits(cache.local, t))
    return cache.version;
  const glm::mat4 parent_matrix =
      parent.valid() ? world.get<WorldTransform>(parent).matrix : glm::mat4(1.0f);
  world.get<WorldTransform>(e).matrix = parent_matrix * local_matrix(t);
  cache = TransformCache{t, parent, parent_version, next_version()};
  ++stats.transforms;
  return cache.version;
}

}  // namespace

glm::mat4 local_matrix(const Transform& t) {
  return glm::translate(glm::mat4(1.0f), t.translation) * glm::mat4_cast(t.rotation) *
         glm::scale(glm::mat4(1.0f), t.scale);
}

TransformStats update_transforms(ecs::World& world, const AssetStore& assets) {
  TransformStats stats;
  // Structural step first (adding WorldTransform and TransformCache where missing), then values:
  // the view over Transform is not iterated while components are being added. An entity whose
  // WorldTransform is new (or was removed by someone) gets recomputed: version 0.
  std::vector<ecs::Entity> entities;
  std::uint32_t max_index = 0;
  world.view<Transform>().each([&](ecs::Entity e, Transform&) {
    entities.push_back(e);
    max_index = std::max(max_index, e.index);
  });
  for (ecs::Entity e : entities) {
    if (!world.has<TransformCache>(e)) world.emplace<TransformCache>(e);
    if (!world.has<WorldTransform>(e)) {
      world.emplace<WorldTransform>(e);
      world.get<TransformCache>(e).version = 0;
    }
  }
  std::vector<std::uint8_t> state(entities.empty() ? 0 : std::size_t{max_index} + 1, 0);
  for (ecs::Entity e : entities) resolve(world, e, state, stats);

  // Bounds: recomputed when the world matrix's version, the mesh id or the mesh's local bounds
  // differ from the BoundsCache. An entity with a WorldTransform but no Transform has a matrix
  // someone else writes (no version to compare): its bounds are recomputed every call.
  std::vector<ecs::Entity> drawn;
  world.view<MeshRenderer, WorldTransform>().each(
      [&](ecs::Entity e, MeshRenderer&, WorldTransform&) { drawn.push_back(e); });
  for (ecs::Entity e : drawn) {
    const MeshRenderer& mr = world.get<MeshRenderer>(e);
    const Aabb local =
        index(mr.mesh) < assets.meshes.size() ? assets.meshes[index(mr.mesh)].bounds : Aabb{};
    const TransformCache* tc = world.try_get<TransformCache>(e);
    const std::uint64_t world_version = tc && world.has<Transform>(e) ? tc->version : 0;
    if (!world.has<BoundsCache>(e)) world.emplace<BoundsCache>(e);
    const bool have_bounds = world.has<WorldBounds>(e);
    BoundsCache& cache = world.get<BoundsCache>(e);
    if (have_bounds && world_version != 0 && cache.world_version == world_version &&
        cache.mesh == mr.mesh && same_bits(cache.local, local))
      continue;
    cache = BoundsCache{mr.mesh, local, world_version};
    world.emplace<WorldBounds>(e, WorldBounds{local.transformed(world.get<WorldTransform>(e).matrix)});
    ++stats.bounds;
  }
  return stats;
}

Aabb scene_bounds(const ecs::World& world) {
  Aabb all;
  world.view<WorldBounds>().each([&](ecs::Entity, const WorldBounds& b) { all.expand(b.box); });
  return all;
}

}  // namespace kaskad
