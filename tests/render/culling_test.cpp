// Frustum culling of the forward pass: a narrow camera on the default scene culls draws, and the
// image is the same, pixel for pixel, as drawing everything (the culled draws were not visible).
#include <gtest/gtest.h>

#include "runtime/app/player.h"
#include "tests/render/headless_gl.h"

namespace kaskad {
namespace {

class CullingTest : public HeadlessGlTest {};

TEST_F(CullingTest, CulledDrawsChangeNoPixel) {
  auto scene = load_scene(content_dir() / "scenes" / "default.json",
                          {"render.width=320", "render.height=180", "camera.camera.fov_y_deg=30",
                           "camera.transform.rotation=[-0.1,0.7,0.1,0.7]"});
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  auto renderer = render::Renderer::create(content_dir() / "shaders");
  ASSERT_TRUE(renderer.ok()) << renderer.error().to_string();
  FrameContext ctx;
  ctx.width = 320;
  ctx.height = 180;
  render::FrameInput frame = plan_frame(*scene, ctx);
  ASSERT_TRUE((*renderer)->render(frame, scene->assets).ok());
  const render::FrameStats culled = (*renderer)->stats();
  const Image with_culling = (*renderer)->read_color();
  const Image aov_culling = (*renderer)->read_aovs();
  for (auto& d : frame.draws) d.bounds = Aabb{};  // unknown bounds: everything is drawn
  ASSERT_TRUE((*renderer)->render(frame, scene->assets).ok());
  EXPECT_EQ((*renderer)->stats().frustum_culled, 0);
  const Image everything = (*renderer)->read_color();
  const Image aov_everything = (*renderer)->read_aovs();
  std::printf("[ narrow view ] %d of %zu draws culled\n", culled.frustum_culled, frame.draws.size());
  EXPECT_GT(culled.frustum_culled, 2);
  EXPECT_EQ(culled.instances + culled.frustum_culled, (*renderer)->stats().instances);
  EXPECT_EQ(with_culling.pixels, everything.pixels);
  EXPECT_EQ(aov_culling.pixels, aov_everything.pixels);
}

}  // namespace
}  // namespace kaskad
