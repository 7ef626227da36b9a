// Helpers shared by the scene file tests (scene_io_test.cpp, scene_blocks_test.cpp,
// scene_overrides_test.cpp).
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "components/name.h"
#include "runtime/assets/scene_io.h"
#include "tests/test_tmp.h"

namespace kaskad::scene_test {

namespace fs = std::filesystem;
inline const fs::path kContent = KASKAD_CONTENT_DIR;

inline fs::path temp_dir() {
  const fs::path d = testing_util::test_tmp();
  fs::create_directories(d);
  return d;
}

inline fs::path write_file(const std::string& name, const std::string& text) {
  const fs::path p = temp_dir() / name;
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

inline std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline ecs::Entity find(const Scene& s, const std::string& name) {
  ecs::Entity found;
  s.world.view<Name>().each([&](ecs::Entity e, const Name& n) {
    if (n.value == name) found = e;
  });
  return found;
}

inline void expect_error(const Result<Scene>& r, const std::vector<std::string>& parts) {
  ASSERT_FALSE(r.ok());
  const std::string msg = r.error().to_string();
  for (const auto& p : parts)
    EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
}

}  // namespace kaskad::scene_test
