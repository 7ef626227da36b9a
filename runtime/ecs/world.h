// The ECS world: entities, per-type component pools, views and deferred structural changes.
//
// The parts: pool.h (storage: one sparse set per type), view.h (views and their iteration) and
// this file (World and CommandBuffer).
//
// Storage model: one sparse set per component type (EnTT's `basic_sparse_set` + `basic_storage`).
// Each pool holds
//   - a paged sparse array  entity index -> dense position (kNpos where the entity lacks T),
//   - a dense array of the entities that have T,
//   - a dense array of T, parallel to the entities.
// Why sparse sets rather than archetype tables (Flecs, Bevy's default table storage, Unity DOTS):
//   + adding or removing one component is O(1) and touches one pool. The editor toggles components
//     and systems add/remove state components (STYLE.md 5) all the time; an archetype move copies
//     every other component of the entity into another table.
//   + every type lives in one stable, contiguous array: single-type loops are plain array walks
//     and pools can be reordered independently (sort_like below).
//   + the code is short: no archetype graph, no table migration, no query cache.
//   - archetypes win for queries over many components: all matches sit in the same rows, with no
//     per-entity membership test. Here a view walks the smallest pool and probes the others: no
//     probe over a remembered aligned prefix, one compare while pools stay aligned, a sparse
//     lookup otherwise (see View). sort_like restores alignment after churn.
//
// Structural change rules (what may be done while a view is iterated, by `each` or range-for):
//   allowed   - modify component values through the references the view hands out, or get();
//             - emplace/remove components of types the view does not include (exclusion types
//               count as "not included": adding an excluded type to a not-yet-visited entity makes
//               the view skip it, which is the usual `view<Enemy>(exclude<Dead>)` pattern);
//             - emplace on an entity that already has an included type: that is a replacement of
//               the value in place, nothing moves;
//             - create(): a new entity has no components, so no pool changes.
//   deferred  - destroying entities and adding/removing components of included types reorder the
//               pools being walked. Record them in a CommandBuffer and flush() after the loop.
//   checked   - in builds without NDEBUG every live iteration locks the view's included pools
//               (a counter per pool); a structural change to a locked pool, including destroy() of
//               an entity that has a locked component, fails KASKAD_CHECK. Release builds do not
//               check: breaking the rules there is undefined behaviour (dangling references).
// Lock scope: `each` holds the lock for the call. Range-for holds it for as long as an iterator
// obtained from begin() is alive, i.e. exactly the loop: leaving it by break, return or an
// exception destroys the iterator and releases the lock. Keeping a view object around locks
// nothing.
//
// References returned by get/try_get/emplace and handed out by views stay valid until a component
// of the same type is added to or removed from any entity (the dense array may reallocate/move).
// Threads: the standard library convention. Any number of threads may use a const World at once
// (const views, get, has, ...); anything through a non-const World needs exclusive access.
#pragma once

#include <algorithm>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "runtime/ecs/entity.h"
#include "runtime/ecs/pool.h"
#include "runtime/ecs/view.h"
#include "runtime/result/result.h"

namespace kaskad::ecs {

class World {
 public:
  /// Slot indices at or above this are reserved for CommandBuffer placeholders.
  static constexpr std::uint32_t kMaxEntities = 0x80000000u;

  World() = default;
  World(const World&) = delete;
  World& operator=(const World&) = delete;
  World(World&&) noexcept = default;
  World& operator=(World&&) noexcept = default;
  ~World() = default;

  /// A new entity with no components. Reuses the most recently freed slot first (its generation was
  /// bumped on destroy, so old handles to the slot stay stale). Safe during iteration.
  Entity create() {
    if (!free_.empty()) {
      const std::uint32_t index = free_.back();
      free_.pop_back();
      slots_[index].alive = true;
      ++alive_count_;
      return Entity{index, slots_[index].generation};
    }
    KASKAD_CHECK(slots_.size() < kMaxEntities,
                 "more than " + std::to_string(kMaxEntities) + " entity slots");
    slots_.push_back(Slot{0, true});
    ++alive_count_;
    return Entity{static_cast<std::uint32_t>(slots_.size() - 1), 0};
  }

  /// Removes all of e's components and frees its slot (generation + 1). No-op for a stale or null
  /// handle. Structural: see the file comment. A slot's 32-bit generation wraps after 2^32 reuses.
  void destroy(Entity e) {
    if (!alive(e)) return;
#ifndef NDEBUG
    for (const auto& p : pools_) {
      KASKAD_CHECK(!p || !p->locked() || !p->contains(e),
                   "cannot destroy " + detail::describe(e) + " while a view iterates its '" +
                       std::string(p->name()) + "' components; use a CommandBuffer");
    }
#endif
    for (const auto& p : pools_)
      if (p && p->contains(e)) p->remove(e);
    Slot& slot = slots_[e.index];
    slot.alive = false;
    ++slot.generation;
    free_.push_back(e.index);
    --alive_count_;
  }

  /// True for a handle to a live entity; false for null, stale and CommandBuffer placeholders.
  bool alive(Entity e) const {
    return e.index < slots_.size() && slots_[e.index].alive &&
           slots_[e.index].generation == e.generation;
  }

  /// Number of live entities.
  std::size_t size() const {
    return alive_count_;
  }

  /// Adds T to e built from args (T(args...), or T{args...} for aggregates), or, if e already has a
  /// T, replaces its value (assignment; nothing moves, so that is allowed during iteration).
  /// Returns the stored component. Precondition: e is alive.
  template <class T, class... A>
  T& emplace(Entity e, A&&... args) {
    KASKAD_CHECK(alive(e), "cannot add '" + std::string(detail::type_name<T>()) + "' to " +
                               detail::describe(e) + ": not alive (stale, null or placeholder)");
    detail::Pool<T>& p = assure<T>();
#ifndef NDEBUG
    KASKAD_CHECK(!p.locked() || p.contains(e),
                 "cannot add '" + std::string(p.name()) + "' to " + detail::describe(e) +
                     " while a view iterates '" + std::string(p.name()) +
                     "' components; use a CommandBuffer");
#endif
    return p.emplace(e, std::forward<A>(args)...);
  }

  /// Removes e's T. No-op if e has none or the handle is stale.
  template <class T>
  void remove(Entity e) {
    detail::Pool<T>* p = find_pool<T>();
    if (!p || !p->contains(e)) return;
#ifndef NDEBUG
    KASKAD_CHECK(!p->locked(), "cannot remove '" + std::string(p->name()) + "' from " +
                                   detail::describe(e) + " while a view iterates '" +
                                   std::string(p->name()) + "' components; use a CommandBuffer");
#endif
    p->remove(e);
  }

  /// False for stale handles (pool entries carry the generation, see PoolBase::index_of).
  template <class T>
  bool has(Entity e) const {
    const detail::Pool<T>* p = find_pool<T>();
    return p && p->contains(e);
  }

  /// e's T. Precondition: e is alive and has T.
  template <class T>
  T& get(Entity e) {
    T* c = try_get<T>(e);
    KASKAD_CHECK(c, missing<T>(e));
    return *c;
  }
  template <class T>
  const T& get(Entity e) const {
    const T* c = try_get<T>(e);
    KASKAD_CHECK(c, missing<T>(e));
    return *c;
  }

  /// e's T, or nullptr when e lacks T or the handle is stale.
  template <class T>
  T* try_get(Entity e) {
    detail::Pool<T>* p = find_pool<T>();
    if (!p) return nullptr;
    const std::uint32_t pos = p->index_of(e);
    return pos == detail::kNpos ? nullptr : &p->at(pos);
  }
  template <class T>
  const T* try_get(Entity e) const {
    const detail::Pool<T>* p = find_pool<T>();
    if (!p) return nullptr;
    const std::uint32_t pos = p->index_of(e);
    return pos == detail::kNpos ? nullptr : &p->at(pos);
  }

  /// Number of entities that have T.
  template <class T>
  std::size_t count() const {
    const detail::Pool<T>* p = find_pool<T>();
    return p ? p->size() : 0;
  }

  /// Entities that have T, in storage (= view iteration) order. Invalidated like references.
  template <class T>
  std::span<const Entity> entities() const {
    const detail::Pool<T>* p = find_pool<T>();
    return p ? std::span<const Entity>(p->entities(), p->size()) : std::span<const Entity>();
  }

  /// Destroys every entity. Generations are bumped, so handles from before clear() stay stale.
  void clear() {
#ifndef NDEBUG
    for (const auto& p : pools_) {
      KASKAD_CHECK(!p || !p->locked(), "cannot clear the world while a view iterates '" +
                                           std::string(p->name()) + "' components");
    }
#endif
    for (const auto& p : pools_)
      if (p) p->clear();
    free_.clear();
    for (std::size_t i = slots_.size(); i-- > 0;) {  // reversed: slot 0 is handed out first
      if (slots_[i].alive) ++slots_[i].generation;
      slots_[i].alive = false;
      free_.push_back(static_cast<std::uint32_t>(i));
    }
    alive_count_ = 0;
  }

  /// Entities with all of I... and none of X...: `view<A, const B>(exclude<C>)`. Registers the
  /// pools of types not seen before, so the view also sees components added after it was made.
  template <class... I, class... X>
  View<detail::TypeList<I...>, detail::TypeList<X...>> view(Exclude<X...> = {}) {
    return {true, &assure<std::remove_const_t<I>>()..., {&assure<X>()...}};
  }
  /// Read-only view: every component is handed out as const.
  template <class... I, class... X>
  View<detail::TypeList<const I...>, detail::TypeList<X...>> view(Exclude<X...> = {}) const {
    return {false, find_pool<std::remove_const_t<I>>()..., {find_pool<X>()...}};
  }

  /// Reorders Follower's pool so that entities having both components come first, in Leader's
  /// order. Afterwards, if every Leader entity also has Follower, both pools hold the same entity
  /// at every position of the Leader pool, and views over {Leader, Follower} take the fast path
  /// for every entity. Use after churn (removals swap elements around). Structural for Follower.
  template <class Leader, class Follower>
  void sort_like() {
    const detail::Pool<Leader>* leader = find_pool<Leader>();
    detail::Pool<Follower>* follower = find_pool<Follower>();
    if (!leader || !follower) return;
#ifndef NDEBUG
    KASKAD_CHECK(!follower->locked(),
                 "cannot reorder '" + std::string(follower->name()) + "' while a view iterates it");
#endif
    follower->follow(*leader);
  }

 private:
  struct Slot {
    std::uint32_t generation = 0;
    bool alive = false;
  };

  template <class T>
  detail::Pool<T>* find_pool() const {
    const std::size_t id = detail::type_id<T>();
    return id < pools_.size() ? static_cast<detail::Pool<T>*>(pools_[id].get()) : nullptr;
  }
  template <class T>
  detail::Pool<T>& assure() {
    const std::size_t id = detail::type_id<T>();
    if (id >= pools_.size()) pools_.resize(id + 1);
    if (!pools_[id]) pools_[id] = std::make_unique<detail::Pool<T>>();
    return static_cast<detail::Pool<T>&>(*pools_[id]);
  }
  template <class T>
  std::string missing(Entity e) const {
    if (!alive(e)) return detail::describe(e) + " is not alive (stale, null or placeholder)";
    return detail::describe(e) + " has no '" + std::string(detail::type_name<T>()) + "' component";
  }

  std::vector<Slot> slots_;
  std::vector<std::uint32_t> free_;  // LIFO
  std::size_t alive_count_ = 0;
  std::vector<std::unique_ptr<detail::PoolBase>> pools_;  // indexed by detail::type_id<T>()
};

/// Structural changes recorded now and applied later, in recording order, by flush(). Use it
/// inside view iteration (see the file comment); flush after the loop, never inside it.
///
/// create() returns a placeholder handle that later commands of the same buffer may target; it is
/// resolved to the real entity at flush. Placeholders are not alive in any World and are invalid
/// after flush()/clear(). Commands whose target is no longer alive at flush are skipped, so
/// destroying the same entity twice, or emplacing on an entity destroyed meanwhile, is harmless.
///
/// Each emplace stores its value in a heap-allocated, type-erased closure (one allocation per
/// command; a bump arena would avoid it if command buffers ever show up in profiles).
class CommandBuffer {
 public:
  CommandBuffer() = default;
  CommandBuffer(const CommandBuffer&) = delete;
  CommandBuffer& operator=(const CommandBuffer&) = delete;
  CommandBuffer(CommandBuffer&&) noexcept = default;
  CommandBuffer& operator=(CommandBuffer&&) noexcept = default;

  /// Records the creation of an entity; returns its placeholder.
  Entity create() {
    KASKAD_CHECK(creates_ < kPlaceholderBit - 1, "too many creates in one CommandBuffer");
    commands_.push_back(Command{Op::kCreate, kNullEntity, nullptr, nullptr});
    return Entity{kPlaceholderBit | creates_++, serial_};
  }

  void destroy(Entity e) {
    KASKAD_CHECK(own_placeholder_or_real(e), foreign_placeholder(e));
    commands_.push_back(Command{Op::kDestroy, e, nullptr, nullptr});
  }

  /// Records World::emplace<T>(e, T(args...)); the value is built now and moved in at flush.
  template <class T, class... A>
  void emplace(Entity e, A&&... args) {
    KASKAD_CHECK(own_placeholder_or_real(e), foreign_placeholder(e));
    auto value = std::make_unique<EmplaceValue<T>>(std::forward<A>(args)...);
    commands_.push_back(Command{Op::kEmplace, e, nullptr, std::move(value)});
  }

  template <class T>
  void remove(Entity e) {
    KASKAD_CHECK(own_placeholder_or_real(e), foreign_placeholder(e));
    commands_.push_back(Command{Op::kRemove, e, &remove_from<T>, nullptr});
  }

  /// Applies every command to `world` in recording order and empties the buffer. Must not be
  /// called while a view of `world` is iterated (checked in debug builds by World itself).
  void flush(World& world) {
    std::vector<Command> commands = std::move(commands_);
    clear();  // new serial: placeholders handed out so far are now invalid
    std::vector<Entity> created;
    for (Command& c : commands) {
      if (c.op == Op::kCreate) {
        created.push_back(world.create());
        continue;
      }
      const Entity e =
          is_placeholder(c.entity) ? created[c.entity.index & ~kPlaceholderBit] : c.entity;
      if (!world.alive(e)) continue;  // died (or never lived) since recording: stale-safe skip
      switch (c.op) {
        case Op::kDestroy:
          world.destroy(e);
          break;
        case Op::kEmplace:
          c.value->apply(world, e);
          break;
        case Op::kRemove:
          c.remove(world, e);
          break;
        case Op::kCreate:
          break;
      }
    }
  }

  /// Drops all recorded commands.
  void clear() {
    commands_.clear();
    creates_ = 0;
    serial_ = next_serial();
  }
  std::size_t size() const { return commands_.size(); }
  bool empty() const { return commands_.empty(); }

 private:
  static constexpr std::uint32_t kPlaceholderBit = World::kMaxEntities;  // index bit 31

  enum class Op : std::uint8_t { kCreate, kDestroy, kEmplace, kRemove };

  struct ErasedValue {
    virtual ~ErasedValue() = default;
    virtual void apply(World& world, Entity e) = 0;
  };
  template <class T>
  struct EmplaceValue final : ErasedValue {
    template <class... A>
    explicit EmplaceValue(A&&... args) : value(detail::construct<T>(std::forward<A>(args)...)) {}
    void apply(World& world, Entity e) override { world.emplace<T>(e, std::move(value)); }
    T value;
  };
  template <class T>
  static void remove_from(World& world, Entity e) {
    world.remove<T>(e);
  }

  struct Command {
    Op op;
    Entity entity;
    void (*remove)(World&, Entity);
    std::unique_ptr<ErasedValue> value;
  };

  static std::uint32_t next_serial() {
    static std::atomic<std::uint32_t> counter{0};
    return counter.fetch_add(1, std::memory_order_relaxed);
  }
  static bool is_placeholder(Entity e) { return e.valid() && (e.index & kPlaceholderBit) != 0; }
  bool own_placeholder_or_real(Entity e) const {
    return !is_placeholder(e) ||
           (e.generation == serial_ && (e.index & ~kPlaceholderBit) < creates_);
  }
  static std::string foreign_placeholder(Entity e) {
    return "placeholder " + detail::describe(e) +
           " comes from another CommandBuffer or from before the last flush()";
  }

  std::vector<Command> commands_;
  std::uint32_t creates_ = 0;
  std::uint32_t serial_ = next_serial();
};

}  // namespace kaskad::ecs