// The headless GL context, KHR_debug routing and RAII handles.
#include <gtest/gtest.h>

#include <epoxy/gl.h>

#include <fstream>

#include "runtime/app/player.h"
#include "runtime/core/log.h"
#include "runtime/gpu/context.h"
#include "runtime/gpu/gl_handles.h"
#include "runtime/gpu/shader.h"
#include "tests/render/headless_gl.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

using GlTest = HeadlessGlTest;

TEST_F(GlTest, ContextIsOpenGL45Core) {
  EXPECT_GE(epoxy_gl_version(), 45);
  GLint mask = 0;
  glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &mask);
  EXPECT_TRUE(mask & GL_CONTEXT_CORE_PROFILE_BIT);
  EXPECT_FALSE(context()->description().empty());
  EXPECT_TRUE(context()->headless());
}

TEST_F(GlTest, DebugOutputCountsGlErrors) {
  // A deliberate error: binding a buffer to an invalid target. KHR_debug must report it.
  glBindBuffer(GL_TEXTURE_2D, 0);
  glGetError();  // clear the legacy error flag too
  EXPECT_EQ(gpu::debug_error_count(), 1);
  gpu::reset_debug_error_count();
}

TEST_F(GlTest, HandlesFreeTheirObjects) {
  GLuint name = 0;
  {
    gpu::Buffer b = gpu::make_buffer();
    name = b.id();
    EXPECT_TRUE(glIsBuffer(name));
    gpu::Buffer moved = std::move(b);
    EXPECT_EQ(b.id(), 0u);
    EXPECT_EQ(moved.id(), name);
  }
  EXPECT_FALSE(glIsBuffer(name));
  EXPECT_EQ(gpu::debug_error_count(), 0);
}

TEST_F(GlTest, ShaderErrorsNameTheOriginalFileAndLine) {
  const auto dir = testing_util::test_tmp();
  std::filesystem::create_directories(dir);
  {
    std::ofstream(dir / "inc.glsl") << "// line 1\nfloat helper() { return undefined_name; }\n";
    std::ofstream(dir / "bad.frag") << "#include \"inc.glsl\"\nout vec4 c;\nvoid main() { c = vec4(helper()); }\n";
    std::ofstream(dir / "ok.vert") << "void main() { gl_Position = vec4(0.0); }\n";
  }
  auto vs = gpu::preprocess_shader(dir, "ok.vert", {});
  auto fs = gpu::preprocess_shader(dir, "bad.frag", {{"X", "1"}});
  ASSERT_TRUE(vs.ok() && fs.ok());
  auto p = gpu::build_program(*vs, *fs);
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.error().message.find("inc.glsl:2"), std::string::npos) << p.error().message;
  // Compile failures are content errors, not GL errors.
  EXPECT_EQ(gpu::debug_error_count(), 0);

  auto missing = gpu::preprocess_shader(dir, "nope.frag", {});
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().to_string().find("nope.frag"), std::string::npos);
  std::ofstream(dir / "cycle.glsl") << "#include \"cycle.glsl\"\n";
  auto cycle = gpu::preprocess_shader(dir, "cycle.glsl", {});
  ASSERT_FALSE(cycle.ok());
  EXPECT_NE(cycle.error().to_string().find("cycle"), std::string::npos);
}

}  // namespace
}  // namespace kaskad
