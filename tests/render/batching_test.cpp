// Multi-draw (render.multi_draw): draws that share program, material and winding but not their
// mesh become one glMultiDrawElementsIndirect, in the forward pass and in every shadow layer.
// The frame must be the same, pixel for pixel and in every AOV, as one call per mesh.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "runtime/cli/player.h"
#include "tests/render/headless_gl.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

class BatchingTest : public HeadlessGlTest {};

// Six meshes of one material (box, cylinder, cone, spheres of 12, 48 and 64 segments: more
// vertices than the shared geometry's first buffer holds, so it grows during the frame), two
// instances of one of them (one instanced draw within the call), a mirrored instance (the other
// winding: a call of its own), a floor and the glTF Box (materials of their own), under a sun
// with four cascades.
std::filesystem::path write_scene() {
  const std::filesystem::path file = testing_util::test_tmp() / "batching.json";
  std::ofstream out(file);
  out << R"({ "kaskad_scene": 1,
  "render": { "width": 320, "height": 180, "ground": "none" },
  "shadow": { "cascade_count": 4, "map_size": 1024, "filter": "pcf3x3" },
  "entities": [
    { "name": "floor", "transform": { "scale": [12, 1, 12] }, "primitive": { "shape": "plane" },
      "material": { "base_color": [0.6, 0.6, 0.6, 1] } },
    { "name": "sun", "transform": { "direction": [0.4, -0.7, -0.5] },
      "light": { "type": "directional", "intensity": 2, "cast_shadows": true } },
    { "name": "camera", "transform": { "translation": [0, 4, 9], "look_at": [0, 0.5, 0] },
      "camera": { "fov_y_deg": 50, "near": 0.1, "far": 40, "active": true } })";
  const char* shapes[] = {R"("shape": "box")",
                          R"("shape": "cylinder")",
                          R"("shape": "cone")",
                          R"("shape": "sphere", "segments": 12)",
                          R"("shape": "sphere", "segments": 48)",
                          R"("shape": "sphere", "segments": 64)",
                          R"("shape": "box")"};
  for (int i = 0; i < 7; ++i) {
    out << ",\n    { \"name\": \"s" << i << "\", \"transform\": { \"translation\": ["
        << -4.5 + 1.5 * i << ", 0.6, " << (i % 2 ? -1 : 1) << "], \"euler_deg\": [0, " << 25 * i
        << ", 0] }, \"primitive\": { " << shapes[i]
        << " }, \"material\": { \"base_color\": [0.8, 0.4, 0.2, 1], \"roughness\": 0.5 } }";
  }
  out << R"(,
    { "name": "mirrored", "transform": { "translation": [2, 0.6, 2.5], "scale": [-1, 1, 1],
      "euler_deg": [0, 30, 0] }, "primitive": { "shape": "cone" },
      "material": { "base_color": [0.8, 0.4, 0.2, 1], "roughness": 0.5 } },
    { "name": "model", "transform": { "translation": [-2, 0.5, 2.5] },
      "model": { "path": ")"
      << (content_dir() / "models/Box/glTF-Binary/Box.glb").string() << R"(" } }
  ]
})";
  return file;
}

TEST_F(BatchingTest, MultiDrawsGiveTheFrameOfOneCallPerMesh) {
  auto scene = load_scene(write_scene());
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  FrameContext ctx;
  ctx.width = 320;
  ctx.height = 180;
  render::FrameInput frame = plan_frame(*scene, ctx);
  struct Run {
    render::FrameStats stats;
    Image color, aovs;
  };
  auto render_with = [&](bool multi_draw) {
    // A renderer of its own: nothing kept from the other run (shadow layers, shared geometry).
    auto renderer = render::Renderer::create(content_dir() / "shaders");
    EXPECT_TRUE(renderer.ok()) << renderer.error().to_string();
    Run r;
    if (!renderer.ok()) return r;
    frame.multi_draw = multi_draw;
    const Status status = (*renderer)->render(frame, scene->assets);
    EXPECT_TRUE(status.ok()) << status.error().to_string();
    r.stats = (*renderer)->stats();
    r.color = (*renderer)->read_color();
    r.aovs = (*renderer)->read_aovs();
    return r;
  };
  const Run multi = render_with(true), single = render_with(false);
  std::printf("[ multi-draw ] forward: %d calls for %d meshes; shadow: %d calls for %d meshes\n",
              multi.stats.draw_calls, multi.stats.mesh_draws, multi.stats.shadow_draw_calls,
              multi.stats.shadow_mesh_draws);
  // One call per mesh without it; fewer calls, the same meshes and instances with it.
  EXPECT_EQ(single.stats.draw_calls, single.stats.mesh_draws);
  EXPECT_EQ(single.stats.shadow_draw_calls, single.stats.shadow_mesh_draws);
  EXPECT_EQ(multi.stats.mesh_draws, single.stats.mesh_draws);
  EXPECT_EQ(multi.stats.shadow_mesh_draws, single.stats.shadow_mesh_draws);
  EXPECT_EQ(multi.stats.instances, single.stats.instances);
  EXPECT_EQ(multi.stats.shadow_instances, single.stats.shadow_instances);
  // Forward: the seven shapes (six meshes, the two boxes one instanced draw) are one call; the
  // mirrored cone, the floor and the model (materials of their own) one each.
  EXPECT_EQ(multi.stats.draw_calls, 4);
  EXPECT_EQ(multi.stats.mesh_draws, 9);
  EXPECT_LT(multi.stats.shadow_draw_calls, multi.stats.shadow_mesh_draws / 2);
  ASSERT_FALSE(multi.color.pixels.empty());
  EXPECT_EQ(multi.color.pixels, single.color.pixels);
  EXPECT_EQ(multi.aovs.pixels, single.aovs.pixels);
}

}  // namespace
}  // namespace kaskad
