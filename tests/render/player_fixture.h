// Test fixture for render tests that load scenes: one headless Player (GL context + renderer,
// shader binary cache in the test tmp folder) per test suite, and GL errors fail each test
// (KHR_debug errors are counted by gpu::debug_error_count()).
#pragma once

#include <gtest/gtest.h>

#include <filesystem>

#include "runtime/cli/player.h"
#include "runtime/gpu/context.h"

namespace kaskad {

class PlayerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    gpu::ContextOptions opt;
    opt.headless = true;
    render::RendererOptions ro;
    ro.shader_cache_dir = std::filesystem::path(KASKAD_TEST_TMP) / "shader_cache";
    auto p = Player::create(opt, ro);
    ASSERT_TRUE(p.ok()) << p.error().to_string();
    player_ = new Player(std::move(p.value()));
  }
  static void TearDownTestSuite() {
    delete player_;
    player_ = nullptr;
  }
  void SetUp() override { gpu::reset_debug_error_count(); }
  void TearDown() override { EXPECT_EQ(gpu::debug_error_count(), 0) << "GL errors were logged"; }

  static inline Player* player_ = nullptr;  ///< the suite's player (suites run one at a time)
};

}  // namespace kaskad
