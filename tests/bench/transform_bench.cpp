// update_transforms over 10k entities (every one with a mesh; one in four a child of an earlier
// one): a still scene, one root moved per call, every root moved per call. Items processed =
// entities in the scene. Run with --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cstddef>
#include <vector>

#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "runtime/assets/primitives.h"
#include "systems/transform_system.h"

namespace {

using namespace kaskad;

constexpr std::size_t kEntities = 10'000;

struct Scene {
  ecs::World world;
  AssetStore assets;
  std::vector<ecs::Entity> roots;

  Scene() {
    const MeshId box = assets.add_mesh(make_primitive(PrimitiveShape::box, 4));
    std::vector<ecs::Entity> all;
    for (std::size_t i = 0; i < kEntities; ++i) {
      const ecs::Entity e = world.create();
      Transform t;
      t.translation = glm::vec3(float(i % 100), 0.0f, float(i / 100));
      if (i % 4 == 3) t.parent = all[i / 2];
      world.emplace<Transform>(e, t);
      MeshRenderer mr;
      mr.mesh = box;
      world.emplace<MeshRenderer>(e, mr);
      all.push_back(e);
      if (!t.parent.valid()) roots.push_back(e);
    }
    update_transforms(world, assets);
  }
};

void BM_StillScene(benchmark::State& state) {
  Scene s;
  for (auto _ : state) update_transforms(s.world, s.assets);
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kEntities));
}
BENCHMARK(BM_StillScene);

void BM_OneRootMoved(benchmark::State& state) {
  Scene s;
  std::size_t next = 0;
  for (auto _ : state) {
    s.world.get<Transform>(s.roots[next++ % s.roots.size()]).translation.y += 0.01f;
    update_transforms(s.world, s.assets);
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kEntities));
}
BENCHMARK(BM_OneRootMoved);

void BM_AllRootsMoved(benchmark::State& state) {
  Scene s;
  for (auto _ : state) {
    for (ecs::Entity e : s.roots) s.world.get<Transform>(e).translation.y += 0.01f;
    update_transforms(s.world, s.assets);
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kEntities));
}
BENCHMARK(BM_AllRootsMoved);

}  // namespace
