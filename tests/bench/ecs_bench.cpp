// View iteration cost against the physical limit (a plain loop over two arrays).
//
// Target: dense views (every entity has both components, pools filled in the same order or
// re-aligned with sort_like) stay within 1.5x of the plain loop in ns/entity. They get there
// through the aligned prefix (runtime/ecs/world.h, View step 2): once a view has seen that both
// pools hold the same entity at every position, later iterations read only the component arrays.
// The per-entity fast-path compare alone streams two extra 8-byte entity arrays and misses the
// target at 10^6 entities (the plain loop's 24 MB fit in L3; 40 MB do not; measured:
// docs/design/ecs.md, "Views over several components"). Sparse and churned-but-
// unsorted views pay a sparse lookup (two dependent loads) per entity and are reported for
// comparison, not held to the target.
//
// Every case does p += v * dt; items processed = entities updated, so the reported
// items_per_second inverts to ns/entity. Run with
//   --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cstddef>
#include <random>
#include <vector>

#include "runtime/ecs/world.h"

namespace {

using kaskad::ecs::Entity;
using kaskad::ecs::World;

struct Position {
  float x = 0, y = 0, z = 0;
};
struct Velocity {
  float x = 0, y = 0, z = 0;
};

constexpr std::size_t kEntities = 1'000'000;
constexpr float kDt = 1.0f / 60.0f;

inline void integrate(Position& p, const Velocity& v) {
  p.x += v.x * kDt;
  p.y += v.y * kDt;
  p.z += v.z * kDt;
}

Velocity velocity_for(std::size_t i) {
  return Velocity{float(i % 7), float(i % 11) * 0.5f, -float(i % 13)};
}

/// kEntities entities; every `velocity_every`-th one also gets a Velocity. Both pools are filled in
/// creation order, so with velocity_every == 1 they are aligned.
void populate(World& w, std::size_t velocity_every) {
  for (std::size_t i = 0; i < kEntities; ++i) {
    const Entity e = w.create();
    w.emplace<Position>(e, float(i), 0.0f, 0.0f);
    if (i % velocity_every == 0) w.emplace<Velocity>(e, velocity_for(i));
  }
}

/// Random churn: destroys and recreates 10% of the entities, then removes and re-adds Velocity on
/// 30%. Both pools end up holding every entity, but in unrelated orders.
void churn(World& w) {
  std::mt19937 rng(1234);
  std::vector<Entity> all(w.entities<Position>().begin(), w.entities<Position>().end());
  std::uniform_int_distribution<std::size_t> pick(0, all.size() - 1);
  for (std::size_t k = 0; k < kEntities / 10; ++k) {
    Entity& e = all[pick(rng)];
    w.destroy(e);
    e = w.create();
    w.emplace<Position>(e, float(k), 0.0f, 0.0f);
    w.emplace<Velocity>(e, velocity_for(k));
  }
  for (std::size_t k = 0; k < kEntities * 3 / 10; ++k) {
    const Entity e = all[pick(rng)];
    w.remove<Velocity>(e);
  }
  for (const Entity e : all)
    if (!w.has<Velocity>(e)) w.emplace<Velocity>(e, velocity_for(e.index));
}

void BM_ViewEach(benchmark::State& state) {
  World w;
  populate(w, 1);
  for (auto _ : state) {
    w.view<Position, const Velocity>().each(
        [](Position& p, const Velocity& v) { integrate(p, v); });
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kEntities));
}
BENCHMARK(BM_ViewEach)->Unit(benchmark::kMicrosecond);

void BM_ViewRangeFor(benchmark::State& state) {
  World w;
  populate(w, 1);
  for (auto _ : state) {
    for (auto [e, p, v] : w.view<Position, const Velocity>()) integrate(p, v);
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kEntities));
}
BENCHMARK(BM_ViewRangeFor)->Unit(benchmark::kMicrosecond);

/// The physical limit: the same update over two plain arrays.
void BM_PlainLoop(benchmark::State& state) {
  std::vector<Position> positions(kEntities);
  std::vector<Velocity> velocities(kEntities);
  for (std::size_t i = 0; i < kEntities; ++i) {
    positions[i] = Position{float(i), 0.0f, 0.0f};
    velocities[i] = velocity_for(i);
  }
  for (auto _ : state) {
    Position* p = positions.data();
    const Velocity* v = velocities.data();
    benchmark::DoNotOptimize(p);  // opaque pointers: the loop cannot be folded across iterations
    benchmark::DoNotOptimize(v);
    for (std::size_t i = 0; i < kEntities; ++i) integrate(p[i], v[i]);
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kEntities));
}
BENCHMARK(BM_PlainLoop)->Unit(benchmark::kMicrosecond);

/// A structural change before every iteration (remove and re-add the last Velocity: the layout
/// version changes, the arrays do not), so every iteration starts with the remembered aligned
/// prefix invalid and measures it again: the cost of the first view after a change.
void BM_ViewEachColdPrefix(benchmark::State& state) {
  World w;
  populate(w, 1);
  const Entity last = w.entities<Velocity>().back();
  for (auto _ : state) {
    w.remove<Velocity>(last);
    w.emplace<Velocity>(last, velocity_for(0));
    w.view<Position, const Velocity>().each(
        [](Position& p, const Velocity& v) { integrate(p, v); });
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kEntities));
}
BENCHMARK(BM_ViewEachColdPrefix)->Unit(benchmark::kMicrosecond);

/// Aligned everywhere but at position 0, so the aligned prefix is empty and every entity goes
/// through the per-entity fast-path compare (View step 3) instead.
void BM_ViewEachFastPathOnly(benchmark::State& state) {
  World w;
  const Entity only_position = w.create();
  w.emplace<Position>(only_position);
  const Entity only_velocity = w.create();
  w.emplace<Velocity>(only_velocity);
  for (std::size_t i = 2; i < kEntities; ++i) {
    const Entity e = w.create();
    w.emplace<Position>(e, float(i), 0.0f, 0.0f);
    w.emplace<Velocity>(e, velocity_for(i));
  }
  for (auto _ : state) {
    w.view<Position, const Velocity>().each(
        [](Position& p, const Velocity& v) { integrate(p, v); });
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kEntities - 2));
}
BENCHMARK(BM_ViewEachFastPathOnly)->Unit(benchmark::kMicrosecond);

/// Only every other entity has Velocity: the view drives over Velocity (the smaller pool) and
/// finds Position by sparse lookup. Items = entities updated (500,000).
void BM_ViewEachSparse(benchmark::State& state) {
  World w;
  populate(w, 2);
  for (auto _ : state) {
    w.view<Position, const Velocity>().each(
        [](Position& p, const Velocity& v) { integrate(p, v); });
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(w.count<Velocity>()));
}
BENCHMARK(BM_ViewEachSparse)->Unit(benchmark::kMicrosecond);

/// After churn, before sort_like: every probe misses the fast path.
void BM_ViewEachChurned(benchmark::State& state) {
  World w;
  populate(w, 1);
  churn(w);
  for (auto _ : state) {
    w.view<Position, const Velocity>().each(
        [](Position& p, const Velocity& v) { integrate(p, v); });
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kEntities));
}
BENCHMARK(BM_ViewEachChurned)->Unit(benchmark::kMicrosecond);

/// After churn and sort_like<Position, Velocity>(): aligned again, back on the fast path.
void BM_ViewEachChurnedSorted(benchmark::State& state) {
  World w;
  populate(w, 1);
  churn(w);
  w.sort_like<Position, Velocity>();
  for (auto _ : state) {
    w.view<Position, const Velocity>().each(
        [](Position& p, const Velocity& v) { integrate(p, v); });
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kEntities));
}
BENCHMARK(BM_ViewEachChurnedSorted)->Unit(benchmark::kMicrosecond);

}  // namespace
