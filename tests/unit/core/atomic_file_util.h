// Helpers shared by the atomic-output tests (core_test: atomic_file_test.cpp; assets_test:
// atomic_image_test.cpp): a fresh folder, file contents, a file-size limit.
#pragma once

#include <sys/resource.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "runtime/result/result.h"
#include "tests/test_tmp.h"

#ifndef KASKAD_TEST_TMP
#error "KASKAD_TEST_TMP must be defined (a string: the tests' scratch folder)"
#endif

namespace kaskad::test {

namespace fs = std::filesystem;

inline fs::path fresh_dir(const std::string& name) {
  const fs::path dir = testing_util::test_tmp() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

inline std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline std::size_t files_in(const fs::path& dir) {
  return std::size_t(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

inline bool mentions(const Error& error, const std::string& text) {
  return error.to_string().find(text) != std::string::npos;
}

/// Limits the size of files this process writes (`ulimit -f`), SIGXFSZ ignored so that write()
/// fails with EFBIG as it does in `kaskad` (main.cpp). Restored on destruction.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &saved_);
    previous_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, previous_handler_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit saved_{};
  void (*previous_handler_)(int) = SIG_DFL;
};

}  // namespace kaskad::test
