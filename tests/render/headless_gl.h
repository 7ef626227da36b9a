// Test fixture: one headless GL 4.5 context per test suite, and GL errors fail each test
// (KHR_debug errors are counted by gpu::debug_error_count()).
#pragma once

#include <gtest/gtest.h>

#include <memory>

#include "runtime/gpu/context.h"

namespace kaskad {

class HeadlessGlTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    gpu::ContextOptions opt;
    opt.headless = true;
    auto ctx = gpu::Context::create(opt);
    ASSERT_TRUE(ctx.ok()) << ctx.error().to_string();
    context().reset(ctx.value().release());
  }
  static void TearDownTestSuite() { context().reset(); }
  void SetUp() override { gpu::reset_debug_error_count(); }
  void TearDown() override { EXPECT_EQ(gpu::debug_error_count(), 0) << "GL errors were logged"; }

  static std::unique_ptr<gpu::Context>& context() {
    static std::unique_ptr<gpu::Context> ctx;
    return ctx;
  }
};

}  // namespace kaskad
