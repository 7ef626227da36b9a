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

// A stamp unique in the process (like CommandBuffer's serials), taken once per update_transforms
// call: every WorldTransform recomputed in that call gets it as its TransformCache::version. A
// child compares its parent's handle and version, so a parent recomputed in a later call always
// shows a version the child has not recorded. Starts at 1: 0 means "never computed". (One atomic
// per call, not per entity: an atomic add per recompute was measurably slower when everything
// moves; docs/design/ecs.md, "Transforms".)
std::uint64_t next_stamp() {
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

// local_matrix(): T * R * S written out (the rotation's columns scaled, the translation as the
// last column) instead of two 4x4 products, inlined into both resolvers.
[[gnu::always_inline]] inline glm::mat4 compose(const Transform& t) {
  const glm::mat3 r = glm::mat3_cast(t.rotation);
  return glm::mat4(glm::vec4(r[0] * t.scale.x, 0.0f), glm::vec4(r[1] * t.scale.y, 0.0f),
                   glm::vec4(r[2] * t.scale.z, 0.0f), glm::vec4(t.translation, 1.0f));
}

// One entity of a parent chain being brought up to date, with the parent decided for it.
struct ChainLink {
  ecs::Entity entity;
  ecs::Entity parent;  ///< kNullEntity: a root (also a gone parent or one that closes a cycle)
  const Transform* transform;
  TransformCache* cache;
  WorldTransform* world;
};

// Why an entity's parent is not applied, said once; off the hot path.
[[gnu::cold, gnu::noinline]] void warn_root(const ecs::World& world, ecs::Entity at,
                                            ecs::Entity parent, bool cycle) {
  if (cycle)
    log::warn_once("%s: parent cycle through %s; treating it as a root",
                   entity_label(world, at).c_str(), entity_label(world, parent).c_str());
  else
    log::warn_once("%s: parent (entity %u) is gone; treating it as a root",
                   entity_label(world, at).c_str(), parent.index);
}

// The parent `at` is placed under: t.parent, or none (a root) when that parent is gone or
// already on the chain being resolved (a cycle).
[[gnu::always_inline]] inline ecs::Entity decide_parent(const ecs::World& world, ecs::Entity at,
                                                        const Transform& t,
                                                        const std::vector<std::uint8_t>& state) {
  const ecs::Entity p = t.parent;
  if (!p.valid()) return ecs::kNullEntity;
  const bool gone = !world.alive(p) || !world.has<Transform>(p);
  if (gone || (p.index < state.size() && state[p.index] == 1)) {
    warn_root(world, at, p, !gone);
    return ecs::kNullEntity;
  }
  return p;
}

// Recomputes l's WorldTransform when its parent, the parent's version or its Transform bits
// differ from its TransformCache; `parent_*` are l.parent's (null for a root), already current.
void update_link(const ChainLink& l, const TransformCache* parent_cache,
                 const WorldTransform* parent_world, std::uint64_t stamp, TransformStats& stats) {
  const std::uint64_t parent_version = parent_cache ? parent_cache->version : 0;
  TransformCache& cache = *l.cache;
  if (cache.version != 0 && cache.parent == l.parent && cache.parent_version == parent_version &&
      same_bits(cache.local, *l.transform))
    return;
  const glm::mat4 parent_matrix = parent_world ? parent_world->matrix : glm::mat4(1.0f);
  l.world->matrix = parent_matrix * compose(*l.transform);
  cache = TransformCache{*l.transform, l.parent, parent_version, stamp};
  ++stats.transforms;
}

// resolve() for a chain too deep to recurse along: the chain is walked up into `chain` and
// computed from its top down, without recursion, so a chain as long as the scene is fine; the
// same decisions and `state` marks as resolve(). `link` is the entity's.
[[gnu::noinline]] void resolve_chain(ecs::World& world, ChainLink link, std::uint64_t stamp,
                   std::vector<std::uint8_t>& state, std::vector<ChainLink>& chain,
                   TransformStats& stats) {
  auto done = [&](ecs::Entity x) { return x.index < state.size() && state[x.index] == 2; };
  if (done(link.entity)) return;
  // Up the chain while parents are not done; the last link reached (usually the entity itself:
  // a root, or a child of an entity done before it) is not stored.
  chain.clear();
  for (;;) {
    const ecs::Entity at = link.entity;
    if (at.index >= state.size()) state.resize(std::size_t{at.index} + 1, 0);
    link.parent = decide_parent(world, at, *link.transform, state);
    state[at.index] = 1;
    if (!link.parent.valid() || done(link.parent)) break;
    chain.push_back(link);
    link = {link.parent, ecs::kNullEntity, &world.get<Transform>(link.parent),
            &world.get<TransformCache>(link.parent), &world.get<WorldTransform>(link.parent)};
  }
  // Top down: the top link's parent is done (or none); each stored link's parent is the link
  // computed just before it.
  state[link.entity.index] = 2;
  if (link.parent.valid())
    update_link(link, &world.get<TransformCache>(link.parent),
                &world.get<WorldTransform>(link.parent), stamp, stats);
  else
    update_link(link, nullptr, nullptr, stamp, stats);
  const ChainLink* above = &link;
  for (std::size_t i = chain.size(); i-- > 0;) {
    state[chain[i].entity.index] = 2;
    update_link(chain[i], above->cache, above->world, stamp, stats);
    above = &chain[i];
  }
}

// Brings one entity's WorldTransform up to date, parent chain first, and returns its version;
// `state` marks entities as 0 = unvisited, 1 = on the current chain (cycle detection), 2 = done.
// The parent applied is decided exactly as when everything was recomputed each call (same order,
// same cycle breaking); the matrix is recomputed only when that parent, its version or this
// entity's Transform bits differ from the TransformCache. `t`, `cache` and `out` are e's.
// Recursion (the fast way for the usual shallow hierarchies) stops at kMaxRecursion levels, where
// resolve_chain() takes the rest of the chain without recursing.
constexpr int kMaxRecursion = 256;

std::uint64_t resolve(ecs::World& world, ecs::Entity e, const Transform& t, TransformCache& cache,
                      WorldTransform& out, std::uint64_t stamp, std::vector<std::uint8_t>& state,
                      std::vector<ChainLink>& chain, TransformStats& stats, int depth = 0) {
  if (e.index >= state.size()) state.resize(std::size_t{e.index} + 1, 0);
  if (state[e.index] == 2) return cache.version;
  if (depth >= kMaxRecursion) {
    resolve_chain(world, {e, ecs::kNullEntity, &t, &cache, &out}, stamp, state, chain, stats);
    return cache.version;
  }
  const ecs::Entity parent = decide_parent(world, e, t, state);
  std::uint64_t parent_version = 0;
  if (parent.valid()) {
    state[e.index] = 1;
    parent_version = resolve(world, parent, world.get<Transform>(parent),
                             world.get<TransformCache>(parent), world.get<WorldTransform>(parent),
                             stamp, state, chain, stats, depth + 1);
  }
  state[e.index] = 2;
  if (cache.version != 0 && cache.parent == parent && cache.parent_version == parent_version &&
      same_bits(cache.local, t))
    return cache.version;
  const glm::mat4 parent_matrix =
      parent.valid() ? world.get<WorldTransform>(parent).matrix : glm::mat4(1.0f);
  out.matrix = parent_matrix * compose(t);
  cache = TransformCache{t, parent, parent_version, stamp};
  ++stats.transforms;
  return cache.version;
}

// Recomputes e's WorldBounds when its inputs differ from the BoundsCache; world_version 0: no
// version to compare (a WorldTransform without a Transform), always.
void update_bounds(const AssetStore& assets, const MeshRenderer& mr, const WorldTransform& wt,
                   std::uint64_t world_version, BoundsCache& cache, WorldBounds& out,
                   TransformStats& stats) {
  const Aabb local =
      index(mr.mesh) < assets.meshes.size() ? assets.meshes[index(mr.mesh)].bounds : Aabb{};
  if (world_version != 0 && cache.world_version == world_version && cache.mesh == mr.mesh &&
      same_bits(cache.local, local))
    return;
  cache = BoundsCache{mr.mesh, local, world_version};
  out.box = local.transformed(wt.matrix);
  ++stats.bounds;
}

}  // namespace

glm::mat4 local_matrix(const Transform& t) { return compose(t); }

TransformStats update_transforms(ecs::World& world, const AssetStore& assets) {
  TransformStats stats;
  // 1. Structural step (adding TransformCache and WorldTransform where missing) before values:
  //    pools are not changed while views over them run. A new WorldTransform (first call, or one
  //    someone removed) means version 0: recompute. Skipped when every Transform already has
  //    both: counting the full view is a plain walk while the pools stay aligned.
  std::size_t complete = 0;
  world.view<Transform, TransformCache, WorldTransform>().each(
      [&](ecs::Entity, Transform&, TransformCache&, WorldTransform&) { ++complete; });
  if (complete != world.count<Transform>()) {
    std::vector<ecs::Entity> entities;
    world.view<Transform>().each([&](ecs::Entity e, Transform&) { entities.push_back(e); });
    for (ecs::Entity e : entities) {
      if (!world.has<TransformCache>(e)) world.emplace<TransformCache>(e);
      if (!world.has<WorldTransform>(e)) {
        world.emplace<WorldTransform>(e);
        world.get<TransformCache>(e).version = 0;
      }
    }
  }

  // 2. World matrices, in Transform storage order (the Transform pool drives the view: it is
  //    never larger than the other two now, and ties go to the first type), so parent cycles
  //    break where they always did.
  std::vector<std::uint8_t> state;
  std::vector<ChainLink> chain;
  const std::uint64_t stamp = next_stamp();
  world.view<Transform, TransformCache, WorldTransform>().each(
      [&](ecs::Entity e, Transform& t, TransformCache& cache, WorldTransform& out) {
        resolve(world, e, t, cache, out, stamp, state, chain, stats);
      });

  // 3. Bounds, for every MeshRenderer with a WorldTransform: structural step as in 1, then values.
  //    Entities with a Transform compare its TransformCache version; the rest (a WorldTransform
  //    written by someone else: no version) are recomputed every call.
  std::size_t drawn = 0, drawn_complete = 0;
  world.view<MeshRenderer, WorldTransform>().each(
      [&](ecs::Entity, MeshRenderer&, WorldTransform&) { ++drawn; });
  world.view<MeshRenderer, WorldTransform, BoundsCache, WorldBounds>().each(
      [&](ecs::Entity, MeshRenderer&, WorldTransform&, BoundsCache&, WorldBounds&) {
        ++drawn_complete;
      });
  if (drawn_complete != drawn) {
    std::vector<ecs::Entity> entities;
    world.view<MeshRenderer, WorldTransform>().each(
        [&](ecs::Entity e, MeshRenderer&, WorldTransform&) { entities.push_back(e); });
    for (ecs::Entity e : entities) {
      if (!world.has<BoundsCache>(e)) world.emplace<BoundsCache>(e);
      if (!world.has<WorldBounds>(e)) {
        world.emplace<WorldBounds>(e);
        world.get<BoundsCache>(e).world_version = 0;
      }
    }
  }
  std::size_t versioned = 0;
  world.view<MeshRenderer, WorldTransform, BoundsCache, WorldBounds, Transform, TransformCache>()
      .each([&](ecs::Entity, MeshRenderer& mr, WorldTransform& wt, BoundsCache& cache,
                WorldBounds& out, Transform&, TransformCache& tc) {
        update_bounds(assets, mr, wt, tc.version, cache, out, stats);
        ++versioned;
      });
  if (versioned != drawn) {
    world.view<MeshRenderer, WorldTransform, BoundsCache, WorldBounds>(ecs::exclude<Transform>)
        .each([&](ecs::Entity, MeshRenderer& mr, WorldTransform& wt, BoundsCache& cache,
                  WorldBounds& out) { update_bounds(assets, mr, wt, 0, cache, out, stats); });
  }
  return stats;
}

Aabb scene_bounds(const ecs::World& world) {
  Aabb all;
  world.view<WorldBounds>().each([&](ecs::Entity, const WorldBounds& b) { all.expand(b.box); });
  return all;
}

}  // namespace kaskad
