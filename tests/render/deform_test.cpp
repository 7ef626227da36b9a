// Living content on the GPU: the deform pass's pose (content/shaders/deform.comp) against the
// CPU's (runtime/assets/mesh_pose.h), the pose's bounds, and the shadow of an animated character
// against the ray-traced reference at several times (the reference poses the mesh on the CPU).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "components/animation.h"
#include "components/camera.h"
#include "components/light.h"
#include "components/mesh_renderer.h"
#include "components/name.h"
#include "components/transform.h"
#include "runtime/app/player.h"
#include "runtime/assets/mesh_pose.h"
#include "runtime/assets/scene_io.h"
#include "runtime/reference/ray_tracer.h"
#include "runtime/reference/shadow_metrics.h"
#include "systems/animation_system.h"
#include "tests/render/player_fixture.h"

namespace kaskad {
namespace {

class DeformTest : public PlayerTest {
 protected:
  /// One frame of `scene` with every playing clip `t` seconds in (kaskad render --time).
  static Result<RenderTimings> render_at(Scene& scene, float t) {
    set_animation_time(scene.world, scene.assets, t);
    return render_frames(*player_, scene, RenderRun{});
  }
};

const std::filesystem::path kFoxScene = std::filesystem::path(KASKAD_CONTENT_DIR) / "scenes/fox_walk.json";

struct Posed {
  ecs::Entity entity;
  const Deformer* deformer = nullptr;
  MeshId mesh = kNoMesh;
};

Posed fox_mesh(Scene& scene) {
  Posed p;
  scene.world.view<Deformer, MeshRenderer>().each([&](ecs::Entity e, Deformer& d, MeshRenderer& mr) {
    p = {e, &d, mr.mesh};
  });
  return p;
}

TEST_F(DeformTest, GpuPoseMatchesTheCpuPoseAndStaysInItsBounds) {
  auto scene = load_scene(kFoxScene, {"render.width=320", "render.height=180"});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  float moved = 0.0f;
  std::vector<glm::vec3> first;
  for (float t : {0.0f, 0.37f, 0.81f}) {
    SCOPED_TRACE("t = " + std::to_string(t));
    auto frames = render_at(*scene, t);
    ASSERT_TRUE(frames.ok()) << frames.error().to_string();
    EXPECT_EQ(frames->last.stats.deformed_meshes, 1);
    const Posed p = fox_mesh(*scene);
    ASSERT_NE(p.deformer, nullptr);
    ASSERT_NE(p.deformer->posed, kNoMesh);
    const std::vector<glm::vec3> gpu = player_->renderer->read_mesh_positions(p.deformer->posed);
    const MeshData& base = scene->assets.meshes[index(p.mesh)];
    ASSERT_EQ(gpu.size(), base.positions.size());
    MeshData cpu = base;
    pose_mesh(base, p.deformer->weights, p.deformer->skin_matrices, cpu);
    const Aabb bounds = scene->world.get<WorldBounds>(p.entity).box;
    const float size = glm::length(bounds.extent());
    ASSERT_GT(size, 0.1f);
    float worst = 0.0f;
    for (std::size_t v = 0; v < gpu.size(); ++v) {
      worst = std::max(worst, glm::length(gpu[v] - cpu.positions[v]));
      // Bounds hold the pose (a thousandth of the size for rounding).
      for (int c = 0; c < 3; ++c) {
        EXPECT_GE(gpu[v][c], bounds.min[c] - 1e-3f * size) << v;
        EXPECT_LE(gpu[v][c], bounds.max[c] + 1e-3f * size) << v;
      }
    }
    EXPECT_LT(worst, 1e-5f * size) << "GPU and CPU poses differ by " << worst << " m";
    // ... and are tight: no side more than 1.5 times the pose's own (the bind pose's box, or one in
    // the mesh's units, would hold it too).
    Aabb own;
    for (const glm::vec3& v : gpu) own.expand(v);
    const glm::vec3 ratio = bounds.extent() / glm::max(own.extent(), glm::vec3(1e-3f * size));
    std::printf("t=%.2f: bounds / pose extent %.2f %.2f %.2f\n", t, ratio.x, ratio.y, ratio.z);
    EXPECT_LT(std::max({ratio.x, ratio.y, ratio.z}), 1.5f);
    if (first.empty()) first = gpu;
    else
      for (std::size_t v = 0; v < gpu.size(); ++v) moved = std::max(moved, glm::length(gpu[v] - first[v]));
  }
  // The clip moves the fox: a pose that never changed would pass the comparisons above.
  EXPECT_GT(moved, 0.05f);
}

TEST_F(DeformTest, AnimatedShadowAgreesWithTheReferenceAtSeveralTimes) {
  auto scene = load_scene(kFoxScene, {"render.width=400", "render.height=225"});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  for (float t : {0.1f, 0.45f, 0.9f}) {
    SCOPED_TRACE("t = " + std::to_string(t));
    auto frames = render_at(*scene, t);
    ASSERT_TRUE(frames.ok()) << frames.error().to_string();
    const Image aov = player_->renderer->read_aovs();
    const ecs::Entity light = frames->last.shadow().light;
    ASSERT_TRUE(light.valid());
    auto tracer = reference::RayTracer::build(*scene);
    ASSERT_TRUE(tracer.ok()) << tracer.error().to_string();
    const auto rlight = reference::reference_light(scene->world, light);
    auto ref = tracer->shadow_reference(aov, rlight, {});
    ASSERT_TRUE(ref.ok()) << ref.error().to_string();
    auto m = reference::compare_shadows(aov, ref->image);
    ASSERT_TRUE(m.ok()) << m.error().to_string();
    const auto& s = m->outside_edges;
    std::printf("fox_walk t=%.2f: %zu of %zu misclassified away from edges (%.3f%%)\n", t,
                s.misclassified, s.pixels, s.misclassified_pct);
    EXPECT_GT(s.pixels, 10000u);
    EXPECT_LT(s.misclassified_pct, 0.5);
  }
}

// The kept-layer cache with an animated caster: the Fox walks far off, in some of the shadow
// map's layers but not all. Each frame poses it anew, so from the second frame on only layers
// that hold it are drawn again, each over the texels of its box alone (patched: a layer whose
// lookups read none of them draws nothing); with its clip stopped, none is. (Breaking the pose
// hash in the layer's inputs, or drawing every layer for any deformed caster, fails it.)
TEST_F(DeformTest, AnAnimatedCasterRedrawsOnlyTheLayersThatHoldIt) {
  const std::vector<std::string> far = {"render.width=320", "render.height=180",
                                        "walker.transform.translation=[-4,0,-7]"};
  std::vector<std::string> hidden = far;
  hidden.push_back("walker.renderer.cast_shadows=false");
  auto without = load_scene(kFoxScene, hidden);
  ASSERT_TRUE(without.ok()) << without.error().to_string();
  RenderRun run;
  run.dt = 0.05;
  auto base = render_frames(*player_, *without, run);
  ASSERT_TRUE(base.ok()) << base.error().to_string();
  auto scene = load_scene(kFoxScene, far);
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  auto first = render_frames(*player_, *scene, run);
  ASSERT_TRUE(first.ok()) << first.error().to_string();
  const render::FrameStats& a = first->last.stats;
  const int layers = a.shadow_layers;
  ASSERT_GE(layers, 2);
  EXPECT_EQ(a.shadow_layers_rendered, (1u << layers) - 1u);
  std::uint32_t holding = 0;  // the layers with the Fox among their casters
  for (int l = 0; l < layers; ++l)
    if (a.layer_casters[std::size_t(l)] != base->last.stats.layer_casters[std::size_t(l)]) holding |= 1u << l;
  std::printf("Fox far off: in layers 0x%x of %d\n", holding, layers);
  ASSERT_NE(holding, 0u) << "the Fox casts into no layer: the test proves nothing";
  ASSERT_NE(holding, (1u << layers) - 1u) << "the Fox is in every layer: the test proves nothing";
  for (int frame = 0; frame < 3; ++frame) {
    auto next = render_frames(*player_, *scene, run);
    ASSERT_TRUE(next.ok()) << next.error().to_string();
    const render::FrameStats& st = next->last.stats;
    EXPECT_NE(st.shadow_layers_rendered, 0u) << "frame " << frame;
    EXPECT_EQ(st.shadow_layers_rendered & ~holding, 0u) << "frame " << frame;
    EXPECT_EQ(st.shadow_layers_rendered & ~st.shadow_layers_patched, 0u) << "frame " << frame;
    if (frame == 0)
      std::printf("walking: layers 0x%x drawn, over %lld texels\n", st.shadow_layers_rendered,
                  static_cast<long long>(st.shadow_texels_drawn));
  }
  // Stopped: the next frame shows the clip where its clock stopped (its last move), then the
  // pose holds and every layer keeps its depth.
  ASSERT_TRUE(apply_live_override(*scene, "walker.animation.Walk.playing=false").ok());
  for (int frame = 0; frame < 3; ++frame) {
    auto still = render_frames(*player_, *scene, run);
    ASSERT_TRUE(still.ok()) << still.error().to_string();
    const std::uint32_t drawn = still->last.stats.shadow_layers_rendered;
    if (frame == 0)
      EXPECT_TRUE(drawn != 0 && (drawn & ~holding) == 0) << "stopped, frame 0: 0x" << std::hex << drawn;
    else
      EXPECT_EQ(drawn, 0u) << "stopped, frame " << frame;
  }
}

// A glTF opened directly frames its camera and ground on the first frame's pose: a skinned mesh
// is placed by its joints, so its node's own transform (here a parent scaled 1000x, as exporters
// put meshes under armatures) must not make the view 1000 times too large. The bar is 2 m tall.
TEST_F(DeformTest, AutoFramingUsesThePosedBoundsOfSkinnedMeshes) {
  const auto file = std::filesystem::path(KASKAD_TEST_DATA) / "skinned_under_scaled_parent.gltf";
  auto scene = load_scene(file, {"render.width=320", "render.height=180"});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  const Posed bar = fox_mesh(*scene);
  ASSERT_TRUE(bar.entity.valid());
  const Aabb posed = scene->world.get<WorldBounds>(bar.entity).box;
  EXPECT_LT(glm::length(posed.extent()), 5.0f) << "the bar's bounds, from its joints";
  Aabb ground;
  glm::vec3 eye(0.0f);
  scene->world.view<Name, WorldBounds>().each([&](ecs::Entity, const Name& n, const WorldBounds& b) {
    if (n.value == "ground") ground = b.box;
  });
  scene->world.view<Camera, WorldTransform>().each(
      [&](ecs::Entity, const Camera&, const WorldTransform& wt) { eye = glm::vec3(wt.matrix[3]); });
  ASSERT_FALSE(ground.empty());
  EXPECT_LT(glm::length(ground.extent()), 50.0f);
  EXPECT_LT(glm::distance(eye, posed.center()), 30.0f);
  // And it is seen: a frame's shadow pass and main view draw it.
  RenderRun run;
  auto frames = render_frames(*player_, *scene, run);
  ASSERT_TRUE(frames.ok()) << frames.error().to_string();
  EXPECT_EQ(frames->last.stats.frustum_culled, 0);
}

}  // namespace
}  // namespace kaskad
