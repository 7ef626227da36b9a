// Helpers shared by the asset tests: content paths, byte files, a per-process temp directory.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#ifndef KASKAD_CONTENT_DIR
#error "KASKAD_CONTENT_DIR must be defined (a string: the path of the repository's content/)"
#endif

namespace kaskad::test {

/// Path of a file under content/, e.g. content_path("models/Box/glTF-Binary/Box.glb").
inline std::filesystem::path content_path(const std::string& relative) {
  return std::filesystem::path(KASKAD_CONTENT_DIR) / relative;
}

inline std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_bytes(const std::filesystem::path& path, const void* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(static_cast<const char*>(data), std::streamsize(size));
}

inline void write_bytes(const std::filesystem::path& path, const std::vector<std::uint8_t>& b) {
  write_bytes(path, b.data(), b.size());
}

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  write_bytes(path, text.data(), text.size());
}

/// A directory for this test process's files, unique per process so that tests run in parallel
/// do not collide; created on first use, removed when the process exits. It lies under
/// KASKAD_TEST_TMP when the build defines it (the build tree), else under the system temp dir.
inline std::filesystem::path temp_dir() {
  struct Dir {
    std::filesystem::path path;
    Dir()
#ifdef KASKAD_TEST_TMP
        : path(std::filesystem::path(KASKAD_TEST_TMP) /
#else
        : path(std::filesystem::temp_directory_path() /
#endif
               ("kaskad_asset_tests_" + std::to_string(::getpid()))) {
      std::filesystem::create_directories(path);
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

}  // namespace kaskad::test
