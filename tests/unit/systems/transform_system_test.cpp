#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "components/camera.h"
#include "components/mesh_renderer.h"
#include "components/name.h"
#include "runtime/core/log.h"
#include "components/transform.h"
#include "runtime/assets/primitives.h"
#include "systems/camera_system.h"
#include "systems/transform_system.h"

namespace kaskad {
namespace {

TEST(TransformSystem, ParentChainsCompose) {
  ecs::World w;
  AssetStore assets;
  const ecs::Entity root = w.create(), child = w.create(), grandchild = w.create();
  w.emplace<Transform>(root, Transform{{1, 0, 0}, glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0)), glm::vec3(2.0f)});
  // Children created before their parent is resolved must still work: set parents afterwards.
  w.emplace<Transform>(grandchild, Transform{{0, 0, 1}, {1, 0, 0, 0}, glm::vec3(1.0f), child});
  w.emplace<Transform>(child, Transform{{0, 1, 0}, {1, 0, 0, 0}, glm::vec3(1.0f), root});
  update_transforms(w, assets);
  const glm::vec3 p = glm::vec3(w.get<WorldTransform>(grandchild).matrix * glm::vec4(0, 0, 0, 1));
  // root: scale 2, rotate +90 deg about Y (z -> x), translate (1,0,0). (0,1,1) -> (2,2,0) + (1,0,0).
  EXPECT_NEAR(p.x, 3.0f, 1e-5f);
  EXPECT_NEAR(p.y, 2.0f, 1e-5f);
  EXPECT_NEAR(p.z, 0.0f, 1e-5f);
}

// A chain as long as a big scene (each entity the parent of the next, created leaf first so the
// walk from the first entity climbs the whole chain) is resolved without recursion: the leaf
// sits at the sum of the steps, and a second call recomputes nothing.
TEST(TransformSystem, AChainAHundredThousandLongComposes) {
  ecs::World w;
  AssetStore assets;
  constexpr int kLength = 100000;
  std::vector<ecs::Entity> chain(kLength);
  for (ecs::Entity& e : chain) e = w.create();
  for (int i = 0; i < kLength; ++i)
    w.emplace<Transform>(chain[std::size_t(kLength - 1 - i)],
                         Transform{{0, 0.5f, 0}, {1, 0, 0, 0}, glm::vec3(1.0f),
                                   i + 1 < kLength ? chain[std::size_t(kLength - 2 - i)]
                                                   : ecs::kNullEntity});
  // chain[k]'s parent is chain[k - 1]; chain[0] is the root, created first, emplaced last.
  const TransformStats first = update_transforms(w, assets);
  EXPECT_EQ(first.transforms, std::size_t(kLength));
  const glm::vec3 leaf = glm::vec3(w.get<WorldTransform>(chain.back()).matrix[3]);
  EXPECT_NEAR(leaf.y, 0.5f * kLength, 1e-3f * kLength);
  EXPECT_EQ(update_transforms(w, assets).transforms, std::size_t(0));
}

// decompose() (components/transform.h): what the glTF loader makes of node matrices and the
// editor of a parented camera's pose. T * R * S recomposes to the matrix, a mirror goes into
// scale.x, a zero scale keeps the identity rotation.
TEST(TransformSystem, DecomposeRecomposesTranslationRotationAndScale) {
  auto compose = [](const Transform& t) {
    return glm::translate(glm::mat4(1.0f), t.translation) * glm::mat4_cast(t.rotation) *
           glm::scale(glm::mat4(1.0f), t.scale);
  };
  const glm::quat r = glm::normalize(glm::quat(0.8f, 0.1f, -0.5f, 0.3f));
  for (const glm::vec3 scale : {glm::vec3(2.0f, 0.5f, 3.0f), glm::vec3(-1.5f, 1.0f, 2.0f)}) {
    const glm::mat4 m = compose(Transform{{1, -2, 3}, r, scale});
    const Transform t = decompose(m);
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 4; ++k) EXPECT_NEAR(compose(t)[c][k], m[c][k], 1e-5f) << c << k;
    EXPECT_EQ(t.scale.x < 0.0f, scale.x < 0.0f);  // the mirror is in scale.x
    EXPECT_GT(t.scale.y, 0.0f);
  }
  const Transform flat = decompose(glm::scale(glm::mat4(1.0f), glm::vec3(1.0f, 0.0f, 1.0f)));
  EXPECT_EQ(flat.rotation, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  EXPECT_EQ(camera_world_scale(glm::scale(glm::mat4(1.0f), glm::vec3(8.0f))), 8.0f);
  EXPECT_EQ(camera_world_scale(glm::mat4(0.0f)), 1.0f);
}

TEST(TransformSystem, CyclesAndStaleParentsBecomeRoots) {
  ecs::World w;
  AssetStore assets;
  const ecs::Entity a = w.create(), b = w.create(), gone = w.create(), c = w.create();
  w.emplace<Transform>(a, Transform{{1, 0, 0}, {1, 0, 0, 0}, glm::vec3(1.0f), b});
  w.emplace<Transform>(b, Transform{{0, 1, 0}, {1, 0, 0, 0}, glm::vec3(1.0f), a});
  w.emplace<Transform>(c, Transform{{0, 0, 5}, {1, 0, 0, 0}, glm::vec3(1.0f), gone});
  w.destroy(gone);
  update_transforms(w, assets);  // must terminate
  EXPECT_TRUE(w.has<WorldTransform>(a));
  EXPECT_TRUE(w.has<WorldTransform>(b));
  EXPECT_FLOAT_EQ(w.get<WorldTransform>(c).matrix[3].z, 5.0f);
}

TEST(TransformSystem, ACycleIsReportedOnceWithTheNamesAndTheScene) {
  ecs::World w;
  AssetStore assets;
  const ecs::Entity a = w.create(), b = w.create();
  w.emplace<Transform>(a, Transform{{1, 0, 0}, {1, 0, 0, 0}, glm::vec3(1.0f), b});
  w.emplace<Transform>(b, Transform{{0, 1, 0}, {1, 0, 0, 0}, glm::vec3(1.0f), a});
  w.emplace<Name>(a, Name{"arm"});
  w.emplace<Name>(b, Name{"hand"});
  log::set_context("cycle_test.json");
  ::testing::internal::CaptureStderr();
  for (int frame = 0; frame < 5; ++frame) update_transforms(w, assets);
  const std::string err = ::testing::internal::GetCapturedStderr();
  log::set_context("");
  std::size_t count = 0;
  for (std::size_t at = err.find("parent cycle"); at != std::string::npos;
       at = err.find("parent cycle", at + 1))
    ++count;
  EXPECT_EQ(count, 1u) << err;
  EXPECT_NE(err.find("cycle_test.json: entity '"), std::string::npos) << err;
  EXPECT_NE(err.find("'arm'"), std::string::npos) << err;
  EXPECT_NE(err.find("'hand'"), std::string::npos) << err;
}

TEST(TransformSystem, WorldBoundsFollowTheMesh) {
  ecs::World w;
  AssetStore assets;
  const MeshId box = assets.add_mesh(make_primitive(PrimitiveShape::box, 8));
  const ecs::Entity e = w.create();
  w.emplace<Transform>(e, Transform{{0, 5, 0}, {1, 0, 0, 0}, glm::vec3(2, 4, 6)});
  w.emplace<MeshRenderer>(e, MeshRenderer{box});
  update_transforms(w, assets);
  const Aabb b = w.get<WorldBounds>(e).box;
  EXPECT_NEAR(b.min.y, 3.0f, 1e-5f);
  EXPECT_NEAR(b.max.y, 7.0f, 1e-5f);
  EXPECT_NEAR(b.max.z - b.min.z, 6.0f, 1e-5f);
  const Aabb all = scene_bounds(w);
  EXPECT_EQ(all.min, b.min);
}

// A still scene recomputes nothing after the first call; moving one leaf recomputes that leaf.
TEST(TransformSystem, OnlyWhatChangedIsRecomputed) {
  ecs::World w;
  AssetStore assets;
  const MeshId box = assets.add_mesh(make_primitive(PrimitiveShape::box, 8));
  std::vector<ecs::Entity> leaves;
  for (int i = 0; i < 10; ++i) {
    const ecs::Entity e = w.create();
    w.emplace<Transform>(e, Transform{{float(i), 0, 0}});
    w.emplace<MeshRenderer>(e, MeshRenderer{box});
    leaves.push_back(e);
  }
  const TransformStats first = update_transforms(w, assets);
  EXPECT_EQ(first.transforms, 10u);
  EXPECT_EQ(first.bounds, 10u);
  for (int frame = 0; frame < 3; ++frame) {
    const TransformStats still = update_transforms(w, assets);
    EXPECT_EQ(still.transforms, 0u) << frame;
    EXPECT_EQ(still.bounds, 0u) << frame;
  }
  // A write through get<>() with no setter and no flag is seen.
  w.get<Transform>(leaves[3]).translation.y = 2.0f;
  const TransformStats moved = update_transforms(w, assets);
  EXPECT_EQ(moved.transforms, 1u);
  EXPECT_EQ(moved.bounds, 1u);
  EXPECT_FLOAT_EQ(w.get<WorldTransform>(leaves[3]).matrix[3].y, 2.0f);
  EXPECT_NEAR(w.get<WorldBounds>(leaves[3]).box.min.y, 1.5f, 1e-5f);
  // Writing the same values again is no change.
  w.emplace<Transform>(leaves[3], w.get<Transform>(leaves[3]));
  EXPECT_EQ(update_transforms(w, assets).transforms, 0u);
}

// Moving a parent recomputes it and its descendants, nothing else; reparenting is seen.
TEST(TransformSystem, AMovedParentRecomputesItsDescendantsOnly) {
  ecs::World w;
  AssetStore assets;
  const ecs::Entity root = w.create(), child = w.create(), grandchild = w.create();
  const ecs::Entity other_root = w.create(), other_child = w.create();
  w.emplace<Transform>(grandchild, Transform{{0, 0, 1}, {1, 0, 0, 0}, glm::vec3(1.0f), child});
  w.emplace<Transform>(child, Transform{{0, 1, 0}, {1, 0, 0, 0}, glm::vec3(1.0f), root});
  w.emplace<Transform>(root, Transform{{1, 0, 0}});
  w.emplace<Transform>(other_root, Transform{{0, 0, 7}});
  w.emplace<Transform>(other_child, Transform{{0, 3, 0}, {1, 0, 0, 0}, glm::vec3(1.0f), other_root});
  EXPECT_EQ(update_transforms(w, assets).transforms, 5u);
  EXPECT_EQ(update_transforms(w, assets).transforms, 0u);

  w.get<Transform>(root).translation.x = 4.0f;
  EXPECT_EQ(update_transforms(w, assets).transforms, 3u);
  EXPECT_FLOAT_EQ(w.get<WorldTransform>(grandchild).matrix[3].x, 4.0f);

  w.get<Transform>(child).scale = glm::vec3(2.0f);
  EXPECT_EQ(update_transforms(w, assets).transforms, 2u);
  EXPECT_FLOAT_EQ(w.get<WorldTransform>(grandchild).matrix[3].z, 2.0f);

  // Reparent the child under the other root: the child and the grandchild follow.
  w.get<Transform>(child).parent = other_root;
  EXPECT_EQ(update_transforms(w, assets).transforms, 2u);
  EXPECT_FLOAT_EQ(w.get<WorldTransform>(grandchild).matrix[3].x, 0.0f);
  EXPECT_FLOAT_EQ(w.get<WorldTransform>(grandchild).matrix[3].z, 9.0f);
  EXPECT_EQ(update_transforms(w, assets).transforms, 0u);

  // The parent destroyed: the child becomes a root, once.
  log::set_context("");
  ::testing::internal::CaptureStderr();
  w.destroy(other_root);
  EXPECT_EQ(update_transforms(w, assets).transforms, 3u);  // child, grandchild, other_child
  EXPECT_EQ(update_transforms(w, assets).transforms, 0u);
  ::testing::internal::GetCapturedStderr();
  EXPECT_FLOAT_EQ(w.get<WorldTransform>(grandchild).matrix[3].z, 2.0f);
}

// A destroyed entity's slot reused by a new entity is recomputed, even with the same values, and
// a child still naming the old generation becomes a root.
TEST(TransformSystem, AReusedSlotIsRecomputed) {
  ecs::World w;
  AssetStore assets;
  const MeshId box = assets.add_mesh(make_primitive(PrimitiveShape::box, 8));
  const ecs::Entity old = w.create(), child = w.create();
  w.emplace<Transform>(old, Transform{{0, 5, 0}});
  w.emplace<MeshRenderer>(old, MeshRenderer{box});
  w.emplace<Transform>(child, Transform{{1, 0, 0}, {1, 0, 0, 0}, glm::vec3(1.0f), old});
  update_transforms(w, assets);
  EXPECT_FLOAT_EQ(w.get<WorldTransform>(child).matrix[3].y, 5.0f);
  w.destroy(old);
  const ecs::Entity reused = w.create();
  ASSERT_EQ(reused.index, old.index);
  ASSERT_NE(reused.generation, old.generation);
  w.emplace<Transform>(reused, Transform{{0, 5, 0}});
  w.emplace<MeshRenderer>(reused, MeshRenderer{box});
  ::testing::internal::CaptureStderr();
  const TransformStats s = update_transforms(w, assets);
  ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(s.transforms, 2u);  // the new entity and the orphaned child
  EXPECT_EQ(s.bounds, 1u);
  EXPECT_FLOAT_EQ(w.get<WorldTransform>(reused).matrix[3].y, 5.0f);
  EXPECT_FLOAT_EQ(w.get<WorldTransform>(child).matrix[3].y, 0.0f);
  EXPECT_NEAR(w.get<WorldBounds>(reused).box.min.y, 4.5f, 1e-5f);
}

// WorldBounds follow a changed mesh id and a changed mesh in the store, and removed derived
// components come back.
TEST(TransformSystem, BoundsFollowMeshChangesAndRemovedOutputsComeBack) {
  ecs::World w;
  AssetStore assets;
  const MeshId box = assets.add_mesh(make_primitive(PrimitiveShape::box, 8));
  const MeshId big = assets.add_mesh(make_primitive(PrimitiveShape::box, 8));
  assets.meshes[index(big)].bounds = Aabb::from_corners(glm::vec3(-3.0f), glm::vec3(3.0f));
  const ecs::Entity e = w.create();
  w.emplace<Transform>(e, Transform{{0, 5, 0}});
  w.emplace<MeshRenderer>(e, MeshRenderer{box});
  update_transforms(w, assets);
  w.get<MeshRenderer>(e).mesh = big;
  TransformStats s = update_transforms(w, assets);
  EXPECT_EQ(s.transforms, 0u);
  EXPECT_EQ(s.bounds, 1u);
  EXPECT_NEAR(w.get<WorldBounds>(e).box.min.y, 2.0f, 1e-5f);
  assets.meshes[index(big)].bounds = Aabb::from_corners(glm::vec3(-1.0f), glm::vec3(1.0f));
  EXPECT_EQ(update_transforms(w, assets).bounds, 1u);
  EXPECT_NEAR(w.get<WorldBounds>(e).box.min.y, 4.0f, 1e-5f);
  w.get<MeshRenderer>(e).mesh = kNoMesh;
  EXPECT_EQ(update_transforms(w, assets).bounds, 1u);
  EXPECT_TRUE(w.get<WorldBounds>(e).box.empty());

  w.get<MeshRenderer>(e).mesh = box;
  update_transforms(w, assets);
  w.remove<WorldTransform>(e);
  w.remove<WorldBounds>(e);
  s = update_transforms(w, assets);
  EXPECT_EQ(s.transforms, 1u);
  EXPECT_EQ(s.bounds, 1u);
  EXPECT_FLOAT_EQ(w.get<WorldTransform>(e).matrix[3].y, 5.0f);
  EXPECT_NEAR(w.get<WorldBounds>(e).box.min.y, 4.5f, 1e-5f);
}

// Incremental updates give bit for bit what recomputing everything gives, over random edits.
TEST(TransformSystem, IncrementalMatchesAFullRecompute) {
  ecs::World w;
  AssetStore assets;
  const MeshId box = assets.add_mesh(make_primitive(PrimitiveShape::box, 8));
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  std::vector<ecs::Entity> all;
  for (int i = 0; i < 40; ++i) {
    const ecs::Entity e = w.create();
    Transform t{{u(rng), u(rng), u(rng)}};
    if (i > 0 && rng() % 3 != 0) t.parent = all[rng() % all.size()];
    w.emplace<Transform>(e, t);
    if (rng() % 2) w.emplace<MeshRenderer>(e, MeshRenderer{box});
    all.push_back(e);
  }
  ::testing::internal::CaptureStderr();
  for (int frame = 0; frame < 30; ++frame) {
    for (int k = 0; k < 3; ++k) {
      const ecs::Entity e = all[rng() % all.size()];
      if (!w.alive(e)) continue;
      switch (rng() % 4) {
        case 0: w.get<Transform>(e).translation.x += u(rng); break;
        case 1: w.get<Transform>(e).parent = all[rng() % all.size()]; break;  // may form a cycle
        case 2: w.get<Transform>(e).rotation = glm::angleAxis(u(rng), glm::vec3(0, 1, 0)); break;
        default: {
          w.destroy(e);
          const ecs::Entity n = w.create();
          w.emplace<Transform>(n, Transform{{u(rng), 0, 0}});
          w.emplace<MeshRenderer>(n, MeshRenderer{box});
          all[rng() % all.size()] = n;
        }
      }
    }
    update_transforms(w, assets);
    // The reference: a copy of every Transform and MeshRenderer, in the same pool order, in a
    // fresh world, where everything is computed.
    ecs::World fresh;
    std::vector<std::pair<ecs::Entity, ecs::Entity>> pairs;
    w.view<Transform>().each([&](ecs::Entity e, Transform&) { pairs.push_back({e, ecs::kNullEntity}); });
    // Recreate with the same slots: create up to the largest index, keep only the used ones.
    std::uint32_t max_index = 0;
    for (auto& p : pairs) max_index = std::max(max_index, p.first.index);
    std::vector<ecs::Entity> slot(max_index + 1);
    for (auto& s : slot) s = fresh.create();
    for (auto& p : pairs) p.second = slot[p.first.index];
    for (auto& p : pairs) {
      Transform t = w.get<Transform>(p.first);
      if (t.parent.valid()) t.parent = w.alive(t.parent) ? slot[t.parent.index] : ecs::Entity{t.parent.index, 999};
      fresh.emplace<Transform>(p.second, t);
      if (const auto* mr = w.try_get<MeshRenderer>(p.first)) fresh.emplace<MeshRenderer>(p.second, *mr);
    }
    update_transforms(fresh, assets);
    for (auto& p : pairs) {
      ASSERT_EQ(std::memcmp(&w.get<WorldTransform>(p.first).matrix,
                            &fresh.get<WorldTransform>(p.second).matrix, sizeof(glm::mat4)), 0)
          << "frame " << frame << " entity " << p.first.index;
      if (w.has<MeshRenderer>(p.first)) {
        ASSERT_EQ(std::memcmp(&w.get<WorldBounds>(p.first).box, &fresh.get<WorldBounds>(p.second).box,
                              sizeof(Aabb)), 0)
            << "frame " << frame << " entity " << p.first.index;
      }
    }
  }
  ::testing::internal::GetCapturedStderr();
}

// A camera `offset` + (0, 2, 10) looking at a 2 m box at `offset`, with `near` and `far`.
struct CameraSetup {
  ecs::World w;
  AssetStore assets;
  ecs::Entity camera, box;
  CameraSetup(glm::vec3 offset, float near, float far) {
    camera = w.create();
    Transform t;
    t.translation = offset + glm::vec3(0, 2, 10);
    t.rotation = glm::quat_cast(glm::inverse(
        glm::mat3(glm::lookAt(t.translation, offset, glm::vec3(0, 1, 0)))));
    w.emplace<Transform>(camera, t);
    Camera c;
    c.near = near;
    c.far = far;
    c.active = true;
    w.emplace<Camera>(camera, c);
    w.emplace<Name>(camera, Name{"eye"});
    box = w.create();
    w.emplace<Transform>(box);
    w.emplace<Name>(box, Name{"crate"});
    update_transforms(w, assets);
    w.emplace<WorldBounds>(box, WorldBounds{Aabb::from_corners(offset - 1.0f, offset + 1.0f)});
  }
  std::vector<std::string> warnings() { return camera_warnings(w, 16.0f / 9.0f, 720); }
};

std::string joined(const std::vector<std::string>& lines) {
  std::string all;
  for (const auto& l : lines) all += l + "\n";
  return all;
}

TEST(CameraSystem, AWellSetCameraHasNothingToSay) {
  EXPECT_EQ(joined(CameraSetup(glm::vec3(0), 0.1f, 100.0f).warnings()), "");
  EXPECT_EQ(joined(CameraSetup(glm::vec3(0), 1e-3f, 1e3f).warnings()), "");  // step 0.6 mm at 10 m
  EXPECT_EQ(joined(CameraSetup(glm::vec3(1e3f, 0, -1e3f), 0.1f, 100.0f).warnings()), "");
}

// A camera scaled to zero on an axis (or under such a parent) keeps an invertible view: the
// collapsed axis is rebuilt from the other two, so it sees what the unscaled camera sees; with
// two axes gone its orientation is the world's. Nothing is infinite.
TEST(CameraSystem, AZeroScaleKeepsTheViewInvertible) {
  const glm::quat turned = glm::angleAxis(glm::radians(30.0f), glm::normalize(glm::vec3(1, 2, 0)));
  auto view_with_scale = [&](glm::vec3 scale) {
    ecs::World w;
    AssetStore assets;
    const ecs::Entity cam = w.create();
    w.emplace<Transform>(cam, Transform{{1, 2, 3}, turned, scale});
    w.emplace<Camera>(cam, Camera{});
    update_transforms(w, assets);
    return select_camera(w, 1.0f).view;
  };
  const glm::mat4 reference = view_with_scale(glm::vec3(1.0f));
  for (const glm::vec3 scale : {glm::vec3(0, 1, 1), glm::vec3(1, 0, 1), glm::vec3(2, 2, 0)}) {
    const glm::mat4 view = view_with_scale(scale);
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) EXPECT_NEAR(view[c][r], reference[c][r], 1e-5f) << c << r;
  }
  const glm::mat4 flat = view_with_scale(glm::vec3(0, 0, 1));
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_TRUE(std::isfinite(flat[c][r])) << c << r;
  EXPECT_NEAR(flat[0][0], 1.0f, 1e-6f);  // the world's orientation
}

TEST(CameraSystem, SeveralActiveCamerasAreNamedAndTheFirstRenders) {
  CameraSetup s(glm::vec3(0), 0.1f, 100.0f);
  const ecs::Entity other = s.w.create();
  s.w.emplace<Transform>(other);
  Camera c;
  c.active = true;
  s.w.emplace<Camera>(other, c);
  s.w.emplace<Name>(other, Name{"spare"});
  update_transforms(s.w, s.assets);
  const std::string all = joined(s.warnings());
  EXPECT_NE(all.find("2 cameras are active ('eye', 'spare'); 'eye', the first, renders"),
            std::string::npos)
      << all;
  EXPECT_EQ(select_camera(s.w, 1.0f).entity, s.camera);
}

TEST(CameraSystem, ANearPlaneTooCloseForTheContentIsReported) {
  const std::string all = joined(CameraSetup(glm::vec3(0), 1e-6f, 1e7f).warnings());
  EXPECT_NE(all.find("camera 'eye': with near 1e-06 and far 1e+07"), std::string::npos) << all;
  EXPECT_NE(all.find("raise near"), std::string::npos) << all;
}

TEST(CameraSystem, ContentFarFromTheOriginIsReportedWithItsJitter) {
  // At 1e5 m floats are 1/128 m apart; a pixel at the box's near face (about 9 m, 45 degrees,
  // 720 rows) is about 1 cm.
  const std::string all = joined(CameraSetup(glm::vec3(1e5f, 0, 0), 0.1f, 100.0f).warnings());
  EXPECT_NE(all.find("lies 100000 m from the origin, where 32-bit float positions are 0.00781 m "
                     "apart"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("at 'crate'"), std::string::npos) << all;
}

TEST(CameraSystem, ActiveCameraWinsAndAutoFrameFitsTheBounds) {
  ecs::World w;
  AssetStore assets;
  const ecs::Entity first = w.create(), second = w.create();
  w.emplace<Transform>(first);
  w.emplace<Camera>(first);
  Transform t;
  t.rotation = glm::quat_cast(glm::inverse(glm::mat3(glm::lookAt(glm::vec3(0), glm::vec3(0, -0.5f, -1), glm::vec3(0, 1, 0)))));
  w.emplace<Transform>(second, t);
  Camera cam;
  cam.active = true;
  cam.auto_frame = true;
  w.emplace<Camera>(second, cam);
  Aabb bounds;
  bounds.expand(glm::vec3(-10, 0, -10));
  bounds.expand(glm::vec3(10, 2, 10));
  frame_auto_cameras(w, bounds, bounds, 16.0f / 9.0f);
  update_transforms(w, assets);
  const CameraState s = select_camera(w, 16.0f / 9.0f);
  ASSERT_EQ(s.entity, second);
  // All 8 corners project inside the view volume.
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 c{(i & 1) ? 10.f : -10.f, (i & 2) ? 2.f : 0.f, (i & 4) ? 10.f : -10.f};
    const glm::vec4 clip = s.proj * s.view * glm::vec4(c, 1.0f);
    const glm::vec3 ndc = glm::vec3(clip) / clip.w;
    EXPECT_LE(std::abs(ndc.x), 1.0f) << i;
    EXPECT_LE(std::abs(ndc.y), 1.0f) << i;
    EXPECT_LE(std::abs(ndc.z), 1.0f) << i;
  }
}

TEST(CameraPlanes, FollowACameraMovedInsideAndOutsideTheBounds) {
  Aabb bounds;
  bounds.expand(glm::vec3(-1, 0, -1));
  bounds.expand(glm::vec3(1, 2, 1));
  Camera c;
  // Outside: near just short of the box's nearest point, far past its farthest corner.
  fit_planes_to_bounds(c, glm::vec3(0, 1, 3), bounds);
  EXPECT_NEAR(c.near, 0.9f * 2.0f, 1e-4f);
  EXPECT_GE(c.far, glm::length(glm::vec3(1, 1, 4)));
  EXPECT_LT(c.far, 1.02f * glm::length(glm::vec3(1, 1, 4)));
  // Inside: near at its floor, far / 1000, never 0.
  fit_planes_to_bounds(c, glm::vec3(0, 1, 0), bounds);
  EXPECT_NEAR(c.near, 1e-3f * c.far, 1e-7f);
  EXPECT_GE(c.far, glm::length(glm::vec3(1, 1, 1)));
  // Far away: near at most far / 2.
  fit_planes_to_bounds(c, glm::vec3(0, 1, 1000), bounds);
  EXPECT_LE(c.near, 0.5f * c.far);
  EXPECT_LT(c.near, 999.0f);
}

}  // namespace
}  // namespace kaskad
