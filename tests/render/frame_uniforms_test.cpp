// FrameBlock (runtime/render/frame_uniforms.h) against the block the driver compiles from
// common.glsl: the block's size and every member's offset (and array stride) as the driver
// reports them for a forward program, so a field added, moved or resized on one side only fails
// here instead of shading with shifted data.
#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <cstddef>
#include <string>

#include "runtime/render/frame_uniforms.h"
#include "runtime/render/renderer.h"
#include "tests/render/player_fixture.h"

namespace kaskad {
namespace {

using render::FrameBlock;
using render::ShadowViewBlock;

class FrameUniformsTest : public PlayerTest {
 protected:
  static GLint property(GLuint program, const std::string& name, GLenum prop) {
    const GLuint index = glGetProgramResourceIndex(program, GL_UNIFORM, name.c_str());
    EXPECT_NE(index, GL_INVALID_INDEX) << name;
    if (index == GL_INVALID_INDEX) return -1;
    GLint value = -1;
    glGetProgramResourceiv(program, GL_UNIFORM, index, 1, &prop, 1, nullptr, &value);
    return value;
  }
};

TEST_F(FrameUniformsTest, CppLayoutMatchesTheCompiledBlock) {
  // A forward program of a frame with shadows, so the shadow code is compiled too (a std140
  // block keeps every member either way).
  render::FrameInput frame;
  frame.lights.resize(1);
  frame.shadow_views.resize(1);
  frame.shadow_views[0].light_index = 0;
  frame.shadow_views[0].layer_count = 4;
  const render::VariantKey key = render::frame_variant(frame).filtered_for(render::Pass::forward);
  auto program = player_->renderer->shaders().program(render::Pass::forward, key);
  ASSERT_TRUE(program.ok()) << program.error().to_string();
  const GLuint prog = program->id();

  const GLuint block = glGetProgramResourceIndex(prog, GL_UNIFORM_BLOCK, "FrameBlock");
  ASSERT_NE(block, GL_INVALID_INDEX);
  const GLenum size_prop = GL_BUFFER_DATA_SIZE;
  GLint block_size = 0;
  glGetProgramResourceiv(prog, GL_UNIFORM_BLOCK, block, 1, &size_prop, 1, nullptr, &block_size);
  EXPECT_EQ(std::size_t(block_size), sizeof(FrameBlock));

  struct Member {
    const char* glsl;
    std::size_t offset;
    std::size_t stride;  // array stride, 0 for a single value
    int length;          // array length, 0 for a single value
  };
  auto check = [&](const std::string& name, const Member& m, std::size_t base) {
    EXPECT_EQ(property(prog, name, GL_OFFSET), GLint(base + m.offset)) << name;
    if (m.stride) {
      EXPECT_EQ(property(prog, name, GL_ARRAY_STRIDE), GLint(m.stride)) << name;
      EXPECT_EQ(property(prog, name, GL_ARRAY_SIZE), m.length) << name;
    }
  };
  const Member members[] = {
      {"u_view_proj", offsetof(FrameBlock, view_proj), 0, 0},
      {"u_view", offsetof(FrameBlock, view), 0, 0},
      {"u_camera_pos", offsetof(FrameBlock, camera_pos), 0, 0},
      {"u_ambient", offsetof(FrameBlock, ambient), 0, 0},
      {"u_environment", offsetof(FrameBlock, environment), 0, 0},
      {"u_environment_sh[0]", offsetof(FrameBlock, environment_sh), sizeof(glm::vec4), 9},
      {"u_frame", offsetof(FrameBlock, frame_params), 0, 0},
      {"u_counts", offsetof(FrameBlock, counts), 0, 0},
      {"u_light_color[0]", offsetof(FrameBlock, light_color), sizeof(glm::vec4), kMaxLights},
      {"u_light_info[0]", offsetof(FrameBlock, light_info), sizeof(glm::ivec4), kMaxLights},
      {"u_light_dir[0]", offsetof(FrameBlock, light_dir), sizeof(glm::vec4), kMaxLights},
      {"u_light_pos[0]", offsetof(FrameBlock, light_pos), sizeof(glm::vec4), kMaxLights},
      {"u_light_cone[0]", offsetof(FrameBlock, light_cone), sizeof(glm::vec4), kMaxLights},
      {"u_previous_view_proj", offsetof(FrameBlock, previous_view_proj), 0, 0},
      {"u_previous_camera_pos", offsetof(FrameBlock, previous_camera_pos), 0, 0},
  };
  for (const Member& m : members) check(m.glsl, m, 0);
  // Every shadow view's members: the struct's own offsets plus the view's place in the array.
  for (int k = 0; k < kMaxShadowedLights; ++k) {
    const std::string view = "u_shadow_views[" + std::to_string(k) + "].";
    const std::size_t base = offsetof(FrameBlock, shadow_views) + std::size_t(k) * sizeof(ShadowViewBlock);
    const Member view_members[] = {
        {"view_proj[0]", offsetof(ShadowViewBlock, view_proj), sizeof(glm::mat4), kMaxCascades},
        {"splits[0]", offsetof(ShadowViewBlock, splits), sizeof(glm::vec4), 3},
        {"texel[0]", offsetof(ShadowViewBlock, texel), sizeof(glm::vec4), 2},
        {"info", offsetof(ShadowViewBlock, info), 0, 0},
        {"params", offsetof(ShadowViewBlock, params), 0, 0},
        {"soft", offsetof(ShadowViewBlock, soft), 0, 0},
    };
    for (const Member& m : view_members) check(view + m.glsl, m, base);
  }
}

}  // namespace
}  // namespace kaskad
