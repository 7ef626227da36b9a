// Multi-draw (render.multi_draw): draws that share program, material and winding but not their
// mesh become one glMultiDrawElementsIndirect, in the forward pass and in every shadow layer.
// The frame must be the same, pixel for pixel and in every AOV, as one call per mesh.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "runtime/app/player.h"
#include "runtime/render/gpu_cache.h"
#include "tests/render/headless_gl.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

class BatchingTest : public HeadlessGlTest {};


// Seven meshes of one material (box, cylinder, cone, spheres of 12, 48, 64 and 128 segments:
// more vertices and indices than the shared geometry's buffers first hold, so they grow), two
// instances of one of them (one instanced draw within the call), a mirrored instance (the other
// winding: a call of its own), two meshes of one alpha-masked material (their own call, in the
// depth pass too), a floor and the glTF Box (materials of their own), under a sun with four
// cascades.
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
                          R"("shape": "sphere", "segments": 128)",
                          R"("shape": "box")"};
  for (int i = 0; i < 8; ++i) {
    out << ",\n    { \"name\": \"s" << i << "\", \"transform\": { \"translation\": ["
        << -4.5 + 1.3 * i << ", 0.6, " << (i % 2 ? -1 : 1) << "], \"euler_deg\": [0, " << 25 * i
        << ", 0] }, \"primitive\": { " << shapes[i]
        << " }, \"material\": { \"base_color\": [0.8, 0.4, 0.2, 1], \"roughness\": 0.5 } }";
  }
  const std::string foliage = (content_dir() / "materials" / "foliage_card.json").string();
  out << R"(,
    { "name": "mirrored", "transform": { "translation": [2, 0.6, 2.5], "scale": [-1, 1, 1],
      "euler_deg": [0, 30, 0] }, "primitive": { "shape": "cone" },
      "material": { "base_color": [0.8, 0.4, 0.2, 1], "roughness": 0.5 } },
    { "name": "card", "transform": { "translation": [0, 1.2, 3], "euler_deg": [70, 20, 0] },
      "primitive": { "shape": "plane" }, "material": { "file": ")"
      << foliage << R"(" } },
    { "name": "cut_box", "transform": { "translation": [3.5, 0.7, 2] },
      "primitive": { "shape": "box" }, "material": { "file": ")"
      << foliage << R"(" } },
    { "name": "model", "transform": { "translation": [-2, 0.5, 2.5] },
      "model": { "path": ")"
      << (content_dir() / "models/Box/glTF-Binary/Box.glb").string() << R"(" } }
  ]
})";
  return file;
}

struct Frame {
  render::FrameStats stats;
  Image color, aovs, shadow_map;
};

// `frame` with multi-draw on or off, by a renderer of its own (nothing kept from another run:
// shadow layers, shared geometry). With `first`, that renderer draws `first` before: its meshes
// are uploaded first, so `frame`'s meshes lie elsewhere in the shared buffers.
Frame render_with(const Scene& scene, render::FrameInput frame, bool multi_draw,
                const render::FrameInput* first = nullptr) {
  auto renderer = render::Renderer::create(content_dir() / "shaders");
  EXPECT_TRUE(renderer.ok()) << renderer.error().to_string();
  Frame r;
  if (!renderer.ok()) return r;
  if (first) {
    const Status status = (*renderer)->render(*first, scene.assets);
    EXPECT_TRUE(status.ok()) << status.error().to_string();
  }
  frame.multi_draw = multi_draw;
  const Status status = (*renderer)->render(frame, scene.assets);
  EXPECT_TRUE(status.ok()) << status.error().to_string();
  r.stats = (*renderer)->stats();
  r.color = (*renderer)->read_color();
  r.aovs = (*renderer)->read_aovs();
  r.shadow_map = (*renderer)->read_shadow_map();
  return r;
}

TEST_F(BatchingTest, MultiDrawsGiveTheFrameOfOneCallPerMesh) {
  for (const char* layered : {"shadow.layered=false", "shadow.layered=true"}) {
    SCOPED_TRACE(layered);
    auto scene = load_scene(write_scene(), {layered});
    ASSERT_TRUE(scene.ok()) << scene.error().to_string();
    std::size_t vertices = 0, indices = 0;
    for (const MeshData& m : scene->assets.meshes) {
      vertices += m.positions.size();
      indices += m.indices.size();
    }
    ASSERT_GT(vertices, render::kGeometryFirstCapacity);  // the buffers grow
    ASSERT_GT(indices, 2 * render::kGeometryFirstCapacity);
    FrameContext ctx;
    ctx.width = 320;
    ctx.height = 180;
    const render::FrameInput frame = plan_frame(*scene, ctx);
    // The largest sphere and the card alone, uploaded before the rest.
    render::FrameInput first = frame;
    std::erase_if(first.draws, [&](const render::DrawItem& d) {
      return scene->assets.meshes[index(d.mesh)].positions.size() < 8000 &&
             d.material.alpha_mode == AlphaMode::opaque;
    });
    ASSERT_EQ(first.draws.size(), 3u);

    const Frame multi = render_with(*scene, frame, true), single = render_with(*scene, frame, false),
              moved = render_with(*scene, frame, true, &first);
    std::printf("[ %s ] forward: %d calls for %d meshes; shadow: %d calls for %d meshes\n",
                layered, multi.stats.draw_calls, multi.stats.mesh_draws,
                multi.stats.shadow_draw_calls, multi.stats.shadow_mesh_draws);
    // One call per mesh without it; fewer calls, the same meshes and instances with it.
    EXPECT_EQ(single.stats.draw_calls, single.stats.mesh_draws);
    EXPECT_EQ(single.stats.shadow_draw_calls, single.stats.shadow_mesh_draws);
    EXPECT_EQ(multi.stats.mesh_draws, single.stats.mesh_draws);
    EXPECT_EQ(multi.stats.shadow_mesh_draws, single.stats.shadow_mesh_draws);
    EXPECT_EQ(multi.stats.instances, single.stats.instances);
    EXPECT_EQ(multi.stats.shadow_instances, single.stats.shadow_instances);
    // Forward: the eight shapes (seven meshes, the two boxes one instanced draw) are one call;
    // the card and the cut box one; the mirrored cone, the floor and the model one each.
    EXPECT_EQ(multi.stats.draw_calls, 5);
    EXPECT_EQ(multi.stats.mesh_draws, 12);
    // Depth: per layer (or once, layered) one call for the opaque casters of each winding and
    // one for the alpha-masked ones.
    const int passes = std::string(layered) == "shadow.layered=true" ? 1 : 4;
    EXPECT_LE(multi.stats.shadow_draw_calls, 3 * passes);
    EXPECT_LT(multi.stats.shadow_draw_calls, multi.stats.shadow_mesh_draws / 2);
    EXPECT_EQ(moved.stats.draw_calls, multi.stats.draw_calls);
    ASSERT_FALSE(multi.color.pixels.empty());
    ASSERT_FALSE(multi.shadow_map.pixels.empty());
    // The same maps and frames, pixel for pixel.
    auto expect_same = [](const Frame& a, const Frame& b, const char* what) {
      EXPECT_EQ(a.shadow_map.pixels, b.shadow_map.pixels) << what;
      EXPECT_EQ(a.color.pixels, b.color.pixels) << what;
      EXPECT_EQ(a.aovs.pixels, b.aovs.pixels) << what;
    };
    expect_same(multi, single, "one call per mesh");
    expect_same(moved, multi, "meshes uploaded in another order");
  }
}

}  // namespace
}  // namespace kaskad
