// Atomic outputs (runtime/core/atomic_file.h): a failed write leaves the previous file
// byte-identical and no temporary file behind; nothing creates folders.
#include "runtime/core/atomic_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/unit/core/atomic_file_util.h"

namespace kaskad {
namespace {

using namespace test;  // fs, fresh_dir, read_text, files_in, mentions, FileSizeLimit

TEST(AtomicFile, WritesAndReplacesLeavingNoTemporaryFile) {
  const fs::path dir = fresh_dir("replace");
  ASSERT_TRUE(write_file_atomic(dir / "a.txt", std::string("first")).ok());
  ASSERT_TRUE(write_file_atomic(dir / "a.txt", std::string("second, longer")).ok());
  EXPECT_EQ(read_text(dir / "a.txt"), "second, longer");
  EXPECT_EQ(files_in(dir), 1u);
}

TEST(AtomicFile, AnOutputNamedByALinkReplacesTheFileItPointsTo) {
  const fs::path dir = fresh_dir("link");
  fs::create_directories(dir / "real");
  ASSERT_TRUE(write_file_atomic(dir / "real" / "a.png", std::string("old")).ok());
  fs::create_symlink("real/a.png", dir / "latest.png");  // relative, from the link's folder
  fs::create_symlink(dir / "latest.png", dir / "chain.png");  // a link to a link
  ASSERT_TRUE(write_file_atomic(dir / "chain.png", std::string("new")).ok());
  EXPECT_TRUE(fs::is_symlink(dir / "chain.png"));
  EXPECT_TRUE(fs::is_symlink(dir / "latest.png"));
  EXPECT_EQ(read_text(dir / "real" / "a.png"), "new");
  EXPECT_EQ(files_in(dir / "real"), 1u) << "a temporary file was left behind";

  // A library's writer (TempFile) too, and a dangling link's target is created.
  fs::create_symlink("real/b.exr", dir / "b.exr");
  auto temp = TempFile::create(dir / "b.exr");
  ASSERT_TRUE(temp.ok()) << temp.error().to_string();
  EXPECT_EQ(temp->path().parent_path(), dir / "real");
  ASSERT_TRUE(write_file_atomic(temp->path(), std::string("exr")).ok());
  ASSERT_TRUE(temp->commit().ok());
  EXPECT_TRUE(fs::is_symlink(dir / "b.exr"));
  EXPECT_EQ(read_text(dir / "real" / "b.exr"), "exr");
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
