// The ECS world: entities, per-type component pools, views and deferred structural changes.
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
#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "runtime/result/result.h"
#include "runtime/ecs/entity.h"

namespace kaskad::ecs {

/// Tag listing component types a view must NOT have: `world.view<A, B>(exclude<C, D>)`.
template <class...>
struct Exclude {};
template <class... T>
inline constexpr Exclude<T...> exclude{};

class World;
class CommandBuffer;

namespace detail {

template <class...>
struct TypeList {};

/// Dense position meaning "absent" in sparse arrays and lookups.
inline constexpr std::uint32_t kNpos = 0xffffffffu;

/// Per-process component type ids: a counter, handed out on first use of each type. Ids are dense
/// small integers, so a World finds a pool with one array index instead of a hash lookup, and no
/// RTTI is needed. Caveat: with -fvisibility=hidden across shared libraries each library would
/// number types on its own; Kaskad links the runtime statically.
inline std::size_t next_type_id() {
  static std::atomic<std::size_t> counter{0};
  return counter.fetch_add(1, std::memory_order_relaxed);
}
template <class T>
std::size_t type_id() {
  static const std::size_t id = next_type_id();
  return id;
}

/// Readable type name for precondition messages, taken from the compiler's function signature.
template <class T>
std::string_view type_name() {
#if defined(__clang__) || defined(__GNUC__)
  // GCC: "... type_name() [with T = Pos; std::string_view = ...]", Clang: "... [T = Pos]".
  const std::string_view s = __PRETTY_FUNCTION__;
  const std::size_t begin = s.find("T = ");
  if (begin == std::string_view::npos) return "component";
  const std::size_t end = s.find_first_of(";]", begin + 4);
  return s.substr(begin + 4, end - (begin + 4));
#else
  return "component";
#endif
}

inline std::string describe(Entity e) {
  if (!e.valid()) return "null entity";
  return "entity " + std::to_string(e.index) + " (generation " + std::to_string(e.generation) + ")";
}

/// Builds a component: T(args...) where that is valid, else T{args...} (aggregates on compilers
/// without C++20 parenthesised aggregate init).
template <class T, class... A>
T construct(A&&... args) {
  if constexpr (std::is_constructible_v<T, A...>) {
    return T(std::forward<A>(args)...);
  } else {
    return T{std::forward<A>(args)...};
  }
}

/// Both halves compared as one 64-bit word: the fast-path probe in views is this one compare.
inline bool same(Entity a, Entity b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

/// The type-independent half of a pool: the sparse set of entities and the iteration lock.
/// Membership tests are non-virtual (views call them per entity); only operations that touch the
/// component array (remove, clear) go through the vtable, and only World's type-erased paths
/// (destroy, clear) use them.
class PoolBase {
 public:
  explicit PoolBase(std::string_view name) : name_(name) {}
  virtual ~PoolBase() = default;
  PoolBase(const PoolBase&) = delete;
  PoolBase& operator=(const PoolBase&) = delete;

  /// Removes e's component; no-op when e has none (or is stale).
  virtual void remove(Entity e) = 0;
  /// Removes every component; the pool stays registered.
  virtual void clear() = 0;

  /// Dense position of e's component, or kNpos. Stale handles miss: the dense entry carries the
  /// generation, and pools only ever hold live entities (World::destroy empties them first).
  std::uint32_t index_of(Entity e) const {
    const std::size_t page = e.index >> kPageBits;
    if (page >= pages_.size() || !pages_[page]) return kNpos;
    const std::uint32_t pos = pages_[page][e.index & kPageMask];
    return (pos != kNpos && same(dense_[pos], e)) ? pos : kNpos;
  }
  bool contains(Entity e) const { return index_of(e) != kNpos; }
  std::size_t size() const { return dense_.size(); }
  /// Entities that have this component, in storage (= iteration) order.
  const Entity* entities() const { return dense_.data(); }
  std::string_view name() const { return name_; }
  /// Bumped whenever an element moves or goes (see the aligned-prefix cache below).
  std::uint64_t layout_version() const { return layout_version_; }

  // Iteration lock (see the file comment). Counted so nested views over the same pool compose;
  // atomic so that concurrent const views of one World stay race-free in debug builds. The
  // counter exists in every build so that the layout does not depend on NDEBUG.
  bool locked() const { return iteration_locks_.load(std::memory_order_relaxed) != 0; }
  void lock() const { iteration_locks_.fetch_add(1, std::memory_order_relaxed); }
  void unlock() const { iteration_locks_.fetch_sub(1, std::memory_order_relaxed); }

  // Aligned-prefix cache (see View). "Layout" = which entity sits at which dense position. It
  // changes when elements move or go (remove, clear, reorder) and the version is bumped; appends
  // leave every existing position as it was, so they keep it.
  static constexpr std::size_t kUnknown = ~std::size_t{0};

  /// Length of the prefix over which this pool and `leader` hold the same entities position by
  /// position, if remembered since neither layout changed; else kUnknown.
  std::size_t aligned_prefix(const PoolBase& leader) const {
    const bool valid = alignment_.leader == &leader &&
                       alignment_.leader_version == leader.layout_version_ &&
                       alignment_.own_version == layout_version_;
    return valid ? alignment_.prefix : kUnknown;
  }
  /// Records an aligned prefix with `leader`. One slot per pool: the last leader wins. Writes
  /// through const because views call it; only views of a non-const World do (exclusive access),
  /// so concurrent const views never write.
  void remember_alignment(const PoolBase& leader, std::size_t prefix) const {
    alignment_ = Alignment{&leader, leader.layout_version_, layout_version_, prefix};
  }
  /// Length of the common prefix of the two pools' dense entity arrays, by memcmp over blocks
  /// (Entity has no padding, so equal bytes mean equal handles), then one block entry by entry.
  std::size_t common_prefix(const PoolBase& other) const {
    constexpr std::size_t kBlock = 256;
    const std::size_t n = std::min(size(), other.size());
    const Entity* a = dense_.data();
    const Entity* b = other.dense_.data();
    std::size_t i = 0;
    while (i + kBlock <= n && std::memcmp(a + i, b + i, kBlock * sizeof(Entity)) == 0) i += kBlock;
    while (i < n && same(a[i], b[i])) ++i;
    return i;
  }

 protected:
  // 4096 entries (16 KiB) per page: dense entity ranges share pages, sparse ones (entity indices
  // far apart) do not allocate the gaps.
  static constexpr unsigned kPageBits = 12;
  static constexpr std::uint32_t kPageSize = 1u << kPageBits;
  static constexpr std::uint32_t kPageMask = kPageSize - 1;

  std::uint32_t& sparse(std::uint32_t index) {
    return pages_[index >> kPageBits][index & kPageMask];
  }
  /// Allocates the page holding `index` if needed (may throw; called before anything changes).
  void ensure_page(std::uint32_t index) {
    const std::size_t page = index >> kPageBits;
    if (page >= pages_.size()) pages_.resize(page + 1);
    if (!pages_[page]) {
      pages_[page] = std::make_unique<std::uint32_t[]>(kPageSize);
      std::fill_n(pages_[page].get(), kPageSize, kNpos);
    }
  }

  std::vector<std::unique_ptr<std::uint32_t[]>> pages_;
  std::vector<Entity> dense_;
  std::uint64_t layout_version_ = 0;

 private:
  struct Alignment {
    const PoolBase* leader = nullptr;
    std::uint64_t leader_version = 0;
    std::uint64_t own_version = 0;
    std::size_t prefix = 0;
  };

  std::string_view name_;
  mutable std::atomic<int> iteration_locks_{0};
  mutable Alignment alignment_;
};

/// Storage for one component type. Removal swaps the last element into the hole (O(1), order is
/// not preserved); sort_like restores a chosen order.
template <class T>
class Pool final : public PoolBase {
  static_assert(std::is_same_v<T, std::remove_cvref_t<T>>, "components are plain object types");
  static_assert(std::is_move_constructible_v<T> && std::is_move_assignable_v<T>,
                "components must be movable (pools move them when they reorder)");

 public:
  Pool() : PoolBase(type_name<T>()) {}

  /// Adds T to e, or replaces e's existing value. Strong guarantee if constructing T throws.
  template <class... A>
  T& emplace(Entity e, A&&... args) {
    if (const std::uint32_t pos = index_of(e); pos != kNpos) {
      if constexpr (sizeof...(A) == 1 && (std::is_same_v<std::remove_cvref_t<A>, T> && ...)) {
        data_[pos] = (std::forward<A>(args), ...);  // a whole T: assign it, no temporary
      } else {
        data_[pos] = construct<T>(std::forward<A>(args)...);
      }
      return data_[pos];
    }
    ensure_page(e.index);
    dense_.push_back(e);
    try {
      if constexpr (std::is_constructible_v<T, A...>) {
        data_.emplace_back(std::forward<A>(args)...);
      } else {
        data_.push_back(T{std::forward<A>(args)...});
      }
    } catch (...) {
      dense_.pop_back();
      throw;
    }
    sparse(e.index) = static_cast<std::uint32_t>(dense_.size() - 1);
    return data_.back();
  }

  void remove(Entity e) override {
    const std::uint32_t pos = index_of(e);
    if (pos == kNpos) return;
    const std::uint32_t last = static_cast<std::uint32_t>(dense_.size() - 1);
    if (pos != last) {  // no self-move: a moved-from std::string would be left unspecified
      dense_[pos] = dense_[last];
      data_[pos] = std::move(data_[last]);
      sparse(dense_[pos].index) = pos;
    }
    sparse(e.index) = kNpos;
    dense_.pop_back();
    data_.pop_back();
    ++layout_version_;
  }

  void clear() override {
    ++layout_version_;
    pages_.clear();
    dense_.clear();
    data_.clear();
  }

  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  T& at(std::uint32_t pos) { return data_[pos]; }
  const T& at(std::uint32_t pos) const { return data_[pos]; }

  /// Reorders this pool so that the entities it shares with `leader` come first, in the leader's
  /// order; the others follow in unspecified order. O(leader.size()) probes, at most one swap each.
  void follow(const PoolBase& leader) {
    const Entity* lead = leader.entities();
    std::uint32_t next = 0;          // [0, next) is final: shared entities, in leader order
    std::size_t aligned = kUnknown;  // first leader position whose entity this pool lacks
    for (std::size_t i = 0, n = leader.size(); i < n; ++i) {
      const std::uint32_t pos = index_of(lead[i]);
      if (pos == kNpos) {
        aligned = std::min(aligned, i);
        continue;
      }
      if (pos != next) swap_positions(pos, next);  // pos > next: placed entities sit below next
      ++next;
    }
    ++layout_version_;
    remember_alignment(leader, std::min(aligned, std::size_t{next}));
  }

 private:
  void swap_positions(std::uint32_t a, std::uint32_t b) {
    using std::swap;
    swap(dense_[a], dense_[b]);
    swap(data_[a], data_[b]);
    sparse(dense_[a].index) = a;
    sparse(dense_[b].index) = b;
  }

  std::vector<T> data_;
};

/// Pool pointer for a view's component type: const-qualified types get read-only pools.
template <class I>
using PoolPtr =
    std::conditional_t<std::is_const_v<I>, const Pool<std::remove_const_t<I>>*, Pool<I>*>;

/// RAII iteration lock over a view's included pools; compiled to nothing with NDEBUG. Copies lock
/// again, so every live iterator holds the lock independently.
template <std::size_t N>
class IterationLock {
 public:
  IterationLock() = default;
#ifndef NDEBUG
  explicit IterationLock(const std::array<const PoolBase*, N>& pools) : pools_(pools) {
    acquire();
  }
  IterationLock(const IterationLock& other) : pools_(other.pools_) {
    acquire();
  }
  IterationLock& operator=(const IterationLock& other) {
    if (this != &other) {
      release();
      pools_ = other.pools_;
      acquire();
    }
    return *this;
  }
  ~IterationLock() {
    release();
  }

 private:
  void acquire() {
    for (const PoolBase* p : pools_)
      if (p) p->lock();
  }
  void release() {
    for (const PoolBase* p : pools_)
      if (p) p->unlock();
  }
  std::array<const PoolBase*, N> pools_{};
#else
  explicit IterationLock(const std::array<const PoolBase*, N>&) {}
#endif
};

/// Hoisted per-pool state for the membership probe.
struct Column {
  const Entity* entities = nullptr;
  std::size_t size = 0;
  const PoolBase* pool = nullptr;

  /// Position of e in this pool, given that the driving pool holds e at position i. Fast path:
  /// pools filled in the same order (or aligned with sort_like) hold e at i too, so one compare of
  /// an entry we stream through anyway replaces the sparse lookup (two dependent random loads).
  std::uint32_t find(std::size_t i, Entity e) const {
    if (i < size && same(entities[i], e)) return static_cast<std::uint32_t>(i);
    return pool->index_of(e);
  }
};

template <class... T>
constexpr bool distinct_types() {
  if constexpr (sizeof...(T) < 2) {
    return true;
  } else {
    return []<class H, class... R>(TypeList<H, R...>) {
      return (!std::is_same_v<std::remove_const_t<H>, std::remove_const_t<R>> && ...) &&
             distinct_types<R...>();
    }(TypeList<T...>{});
  }
}

}  // namespace detail

template <class Include, class Excluded>
class View;

/// Entities that have every type in I... and none in X...; `const` in I... gives read-only access.
/// A view is a cheap handle (pool pointers) made by World::view; make it where you iterate it.
///   view.each([](Entity e, A& a, B& b) { ... });   // or without the Entity parameter
///   for (auto [e, a, b] : view) { ... }             // a, b are references (A&, B&)
/// Range-for yields std::tuple<Entity, I&...> by value: bind with `auto` or `auto&&`, not `auto&`.
///
/// How iteration finds matches (why views over aligned pools run at nearly plain-loop speed):
///  1. The smallest included pool drives (chosen when the view is made); its storage order is the
///     visiting order.
///  2. Aligned prefix: the longest prefix over which every other included pool holds the same
///     entity at the same dense position as the driver. Each pool remembers it for the last pool
///     that drove it (PoolBase::aligned_prefix) until either layout changes. Inside the prefix the
///     loop reads only component arrays (and probes exclusion pools), like a plain loop. When no
///     prefix is remembered, range-for measures it first (one memcmp pass over the entity
///     arrays) and `each` measures it while it runs (step 3's block compares).
///  3. Past the prefix, `each` goes by blocks of 64 entities: a block where every other pool holds
///     the same entities (memcmp) runs like step 2; in other blocks, and in range-for, each other
///     pool is probed per entity: first the fast path (does it hold the entity at the same
///     position? one compare), then the sparse lookup.
/// Why steps 2 and 3 avoid the per-entity compare where they can: it streams two 8-byte entity
/// arrays besides the components, and at 10^6 entities that measured 1.9-2.6x the plain loop,
/// over the 1.5x target (tests/bench/ecs_bench.cpp); memcmp over blocks reads the same bytes
/// several times faster, and a remembered prefix reads none. Views of a non-const World refresh
/// the remembered prefix; views of a const World only read it, so concurrent const views never
/// write shared state.
template <class... I, class... X>
class View<detail::TypeList<I...>, detail::TypeList<X...>> {
  static constexpr std::size_t N = sizeof...(I);
  static_assert(N > 0, "a view needs at least one component type");
  static_assert(detail::distinct_types<I..., X...>(), "a view lists each component type once");

  using Positions = std::array<std::uint32_t, N>;

  /// Everything the loop needs, copied out of the pools once so the loop body keeps it in
  /// registers instead of chasing pool pointers (and no virtual call happens per entity).
  /// Valid while the structural change rules hold (no included pool moves its arrays).
  struct Cursor {
    const Entity* entities = nullptr;  // the driving pool's dense entities
    std::size_t size = 0;
    std::size_t aligned = 0;  // [0, aligned): every included pool holds entities[i] at i
    std::array<detail::Column, N> columns{};
    std::tuple<I*...> data{};
    std::array<const detail::PoolBase*, sizeof...(X)> excluded{};

    bool excludes(Entity e) const {
      for (const detail::PoolBase* x : excluded)
        if (x && x->contains(e)) return true;
      return false;
    }
    /// Step 3, block test: whether every other included pool holds entities[begin, end) at the
    /// same positions (one memcmp per pool; Entity has no padding).
    bool aligned_block(std::size_t begin, std::size_t end) const {
      for (const detail::Column& col : columns) {
        if (col.entities == entities) continue;  // the driver itself
        if (end > col.size ||
            std::memcmp(col.entities + begin, entities + begin, (end - begin) * sizeof(Entity)))
          return false;
      }
      return true;
    }
    /// Step 3: positions of e (= entities[i]) in every included pool; false if one lacks it.
    template <std::size_t... K>
    bool probe(std::size_t i, Entity e, Positions& pos, std::index_sequence<K...>) const {
      return (((pos[K] = columns[K].find(i, e)) != detail::kNpos) && ...);
    }
    /// Whether entities[i] matches the view, with its positions in pos.
    bool match(std::size_t i, Positions& pos) const {
      const Entity e = entities[i];
      if (i < aligned) {
        pos.fill(static_cast<std::uint32_t>(i));
      } else if (!probe(i, e, pos, std::index_sequence_for<I...>{})) {
        return false;
      }
      return !excludes(e);
    }
  };

 public:
  using value_type = std::tuple<Entity, I&...>;

  struct Sentinel {};

  /// Input iterator yielding std::tuple<Entity, I&...>. Holds the iteration lock (debug builds)
  /// while it lives; see the file comment.
  class Iterator {
   public:
    using value_type = View::value_type;
    using reference = value_type;
    using difference_type = std::ptrdiff_t;
    using iterator_category = std::input_iterator_tag;

    Iterator() = default;

    value_type operator*() const { return deref(std::index_sequence_for<I...>{}); }
    Iterator& operator++() {
      // Inside the aligned prefix with no exclusions every entity matches at its own position:
      // keep that path branch-light, it is the range-for equivalent of step 2.
      ++index_;
      if constexpr (sizeof...(X) == 0) {
        if (index_ < cursor_.aligned) return *this;  // deref uses index_ itself there
      }
      settle();
      return *this;
    }
    void operator++(int) { ++*this; }
    friend bool operator==(const Iterator& it, Sentinel) { return it.index_ >= it.cursor_.size; }

   private:
    friend class View;
    Iterator(const Cursor& cursor, const std::array<const detail::PoolBase*, N>& pools)
        : cursor_(cursor), lock_(pools) {
      settle();
    }
    /// Advances index_ to the next matching entity (or the end).
    void settle() {
      while (index_ < cursor_.size && !cursor_.match(index_, pos_)) ++index_;
    }
    template <std::size_t... K>
    value_type deref(std::index_sequence<K...>) const {
      // Inside the aligned prefix every pool holds the entity at index_: no position look-up
      // (pos_ is not even written there, see operator++).
      if (index_ < cursor_.aligned)
        return value_type(cursor_.entities[index_], std::get<K>(cursor_.data)[index_]...);
      return value_type(cursor_.entities[index_], std::get<K>(cursor_.data)[pos_[K]]...);
    }

    Cursor cursor_{};
    std::size_t index_ = 0;
    Positions pos_{};
    detail::IterationLock<N> lock_{};
  };

  /// `remember`: whether iteration may refresh the pools' aligned-prefix caches (non-const World).
  View(bool remember, detail::PoolPtr<I>... pools,
       std::array<const detail::PoolBase*, sizeof...(X)> excluded)
      : pools_(pools...), excluded_(excluded), remember_(remember) {
    const std::array<const detail::PoolBase*, N> all{pools...};
    for (const detail::PoolBase* p : all) {
      if (!p) {  // a type no entity ever had (const World): the view is empty
        driver_ = nullptr;
        return;
      }
      if (!driver_ || p->size() < driver_->size()) driver_ = p;
    }
  }

  /// Calls f(e, i...) or f(i...) for every matching entity; I& references are A& or const A&.
  template <class F>
  void each(F&& f) const {
    static_assert(std::is_invocable_v<F&, Entity, I&...> || std::is_invocable_v<F&, I&...>,
                  "each() takes a callable (Entity, I&...) or (I&...)");
    if (!driver_) return;
    const detail::IterationLock<N> lock(pool_bases());
    // A cold prefix is not measured up front: step 3's block compares measure it in the same pass.
    const Cursor c = cursor(/*measure=*/false);
    const std::uint64_t layout = layout_stamp();
    const std::size_t aligned = run(f, c, std::index_sequence_for<I...>{});
    if (remember_ && aligned > c.aligned && layout_stamp() == layout) remember(aligned);
  }

  Iterator begin() const {
    return driver_ ? Iterator(cursor(/*measure=*/true), pool_bases()) : Iterator();
  }
  Sentinel end() const { return {}; }

  /// Upper bound on the number of matches: the driving pool's size.
  std::size_t size_hint() const { return driver_ ? driver_->size() : 0; }

 private:
  /// The loop of `each`. Returns how far the pools were seen to be aligned (a lower bound).
  template <class F, std::size_t... K>
  static std::size_t run(F& f, const Cursor c, std::index_sequence<K...> seq) {
    std::size_t i = 0;
    for (; i < c.aligned; ++i) {  // step 2: no probes; the entity load folds away if unused
      const Entity e = c.entities[i];
      if (c.excludes(e)) continue;
      call(f, e, std::get<K>(c.data)[i]...);
    }
    // Step 3, a block at a time: pools that were aligned once and then lost a few elements
    // (a removal swaps the last element into the hole) are still aligned almost everywhere, so a
    // block that compares equal runs like step 2; only other blocks probe entity by entity.
    constexpr std::size_t kBlock = 64;
    std::size_t aligned = c.size;  // start of the first block that did not compare equal
    Positions pos;
    while (i < c.size) {
      const std::size_t end = std::min(i + kBlock, c.size);
      if (c.aligned_block(i, end)) {
        for (; i < end; ++i) {
          const Entity e = c.entities[i];
          if (c.excludes(e)) continue;
          call(f, e, std::get<K>(c.data)[i]...);
        }
        continue;
      }
      aligned = std::min(aligned, i);
      for (; i < end; ++i) {
        const Entity e = c.entities[i];
        if (!c.probe(i, e, pos, seq) || c.excludes(e)) continue;
        call(f, e, std::get<K>(c.data)[pos[K]]...);
      }
    }
    return aligned;
  }
  template <class F, class... R>
  static void call(F& f, Entity e, R&... components) {
    if constexpr (std::is_invocable_v<F&, Entity, R&...>) {
      f(e, components...);
    } else {
      f(components...);
    }
  }

  /// `measure`: whether to measure a prefix that no pool remembers (else it starts at 0).
  Cursor cursor(bool measure) const {
    Cursor c;
    c.entities = driver_->entities();
    c.size = driver_->size();
    c.aligned = aligned_prefix(measure);
    fill(c, std::index_sequence_for<I...>{});
    c.excluded = excluded_;
    return c;
  }
  template <std::size_t... K>
  void fill(Cursor& c, std::index_sequence<K...>) const {
    ((c.columns[K] = detail::Column{std::get<K>(pools_)->entities(), std::get<K>(pools_)->size(),
                                    std::get<K>(pools_)}),
     ...);
    c.data = std::tuple<I*...>(std::get<K>(pools_)->data()...);
  }
  /// Step 2: the prefix aligned across all included pools, from the caches or measured.
  std::size_t aligned_prefix(bool measure) const {
    std::size_t prefix = driver_->size();
    for (const detail::PoolBase* p : pool_bases()) {
      if (p == driver_) continue;
      std::size_t k = p->aligned_prefix(*driver_);
      if (k == detail::PoolBase::kUnknown) {
        if (!measure) return 0;
        k = driver_->common_prefix(*p);
        if (remember_) p->remember_alignment(*driver_, k);
      }
      prefix = std::min(prefix, k);
    }
    return prefix;
  }
  /// Records `aligned` for the pools that remember less (or nothing) for this driver.
  void remember(std::size_t aligned) const {
    for (const detail::PoolBase* p : pool_bases()) {
      const std::size_t known = p->aligned_prefix(*driver_);
      if (p != driver_ && (known == detail::PoolBase::kUnknown || known < aligned))
        p->remember_alignment(*driver_, aligned);
    }
  }
  /// Changes whenever an included pool's layout does (versions only grow). A layout change
  /// during iteration breaks the rules; this keeps it from also poisoning the cache.
  std::uint64_t layout_stamp() const {
    std::uint64_t sum = 0;
    for (const detail::PoolBase* p : pool_bases()) sum += p->layout_version();
    return sum;
  }
  std::array<const detail::PoolBase*, N> pool_bases() const {
    return std::apply([](auto*... p) { return std::array<const detail::PoolBase*, N>{p...}; },
                      pools_);
  }

  std::tuple<detail::PoolPtr<I>...> pools_;
  std::array<const detail::PoolBase*, sizeof...(X)> excluded_;
  const detail::PoolBase* driver_ = nullptr;  // null: empty view
  bool remember_ = false;
};

/// Entities and their components. Move-only (pools are owned).
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
