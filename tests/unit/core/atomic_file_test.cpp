// Atomic outputs (runtime/core/atomic_file.h): a failed write leaves the previous file
// byte-identical and no temporary file behind; nothing creates folders.
#include "runtime/core/atomic_file.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "runtime/assets/image_io.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::path(KASKAD_TEST_TMP) / "atomic_file" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::size_t files_in(const fs::path& dir) {
  return std::size_t(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

bool mentions(const Error& error, const std::string& text) {
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

Image gradient(int width, int height) {
  Image image;
  image.width = width;
  image.height = height;
  image.channels = 3;
  for (int i = 0; i < width * height * 3; ++i) image.pixels.push_back(float((i * 7919) % 1000) / 999.0f);
  return image;
}

TEST(AtomicFile, WritesAndReplacesLeavingNoTemporaryFile) {
  const fs::path dir = fresh_dir("replace");
  ASSERT_TRUE(write_file_atomic(dir / "a.txt", std::string("first")).ok());
  ASSERT_TRUE(write_file_atomic(dir / "a.txt", std::string("second, longer")).ok());
  EXPECT_EQ(read_text(dir / "a.txt"), "second, longer");
  EXPECT_EQ(files_in(dir), 1u);
}

TEST(AtomicFile, FailedWriteUnderFileSizeLimitKeepsThePreviousFile) {
  const fs::path dir = fresh_dir("limit");
  const std::string previous(3000, 'p');
  ASSERT_TRUE(write_file_atomic(dir / "out.csv", previous).ok());
  Status st;
  {
    FileSizeLimit limit(4096);
    st = write_file_atomic(dir / "out.csv", std::string(100000, 'n'));
  }
  ASSERT_FALSE(st.ok());
  EXPECT_TRUE(mentions(st.error(), "out.csv")) << st.error().to_string();
  EXPECT_TRUE(mentions(st.error(), "4096 of 100000 bytes")) << st.error().to_string();
  EXPECT_TRUE(read_text(dir / "out.csv") == previous) << "out.csv changed";
  EXPECT_EQ(files_in(dir), 1u) << "a temporary file was left behind";
}

TEST(AtomicFile, FailedImageWritesKeepThePreviousImage) {
  // The PNG writer ignores short writes and used to leave a cut-off file; EXR left its half.
  const fs::path dir = fresh_dir("image");
  for (const char* name : {"out.png", "out.exr", "out.tif", "out.hdr"}) {
    ASSERT_TRUE(save_image(dir / name, gradient(8, 8)).ok()) << name;
    const std::string previous = read_text(dir / name);
    Status st;
    {
      FileSizeLimit limit(2048);
      st = save_image(dir / name, gradient(256, 256));
    }
    EXPECT_FALSE(st.ok()) << name << " was written past the file size limit";
    if (!st.ok()) {
      EXPECT_TRUE(mentions(st.error(), name)) << st.error().to_string();
    }
    EXPECT_TRUE(read_text(dir / name) == previous) << name << " changed";
  }
  EXPECT_EQ(files_in(dir), 4u) << "a temporary file was left behind";
}

TEST(AtomicFile, OutputPathChecksCreateNothing) {
  const fs::path dir = fresh_dir("paths");
  Status st = check_output_path(dir / "missing" / "x.png");
  ASSERT_FALSE(st.ok());
  EXPECT_TRUE(mentions(st.error(), "does not exist")) << st.error().to_string();
  EXPECT_FALSE(fs::exists(dir / "missing"));

  st = write_file_atomic(dir, std::string("x"));
  ASSERT_FALSE(st.ok());
  EXPECT_TRUE(mentions(st.error(), "is a folder")) << st.error().to_string();

  // Root may write anywhere by permission bits, but not into /proc.
  st = check_output_path("/proc/kaskad_test.exr");
  ASSERT_FALSE(st.ok());
  EXPECT_TRUE(mentions(st.error(), "/proc")) << st.error().to_string();

  st = check_output_path("/dev/null");
  ASSERT_FALSE(st.ok()) << "a device must never be replaced by rename";
  EXPECT_TRUE(check_output_path(dir / "fine.png").ok());
  EXPECT_EQ(files_in(dir), 0u);
}

}  // namespace
}  // namespace kaskad
