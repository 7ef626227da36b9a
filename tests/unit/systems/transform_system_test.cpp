#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

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

}  // namespace
}  // namespace kaskad
