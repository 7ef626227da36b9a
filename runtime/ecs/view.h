// Views over the ECS world's pools (runtime/ecs/world.h is the whole picture): which entities
// match, how iteration finds them, and the iterators range-for uses.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstring>
#include <iterator>
#include <tuple>
#include <type_traits>
#include <utility>

#include "runtime/ecs/pool.h"

namespace kaskad::ecs {

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
/// arrays besides the components, and at 10^6 entities that is well over the target
/// (tests/bench/ecs_bench.cpp; measured: docs/design/ecs.md, "Views over several components");
/// memcmp over blocks reads the same bytes much faster, and a remembered prefix reads none.
/// Views of a non-const World refresh the remembered prefix; views of a const World only read
/// it, so concurrent const views never write shared state.
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

}  // namespace kaskad::ecs
