// The ECS world's storage (runtime/ecs/world.h is the whole picture): one pool per component
// type, type ids and the iteration locks views hold.
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
#pragma once

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

}  // namespace kaskad::ecs
