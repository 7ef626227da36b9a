// Whole-file reads (runtime/core/file_io.h): what is not a regular file is refused by name before
// it is opened, so a named pipe given as an input fails at once instead of blocking the read.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "runtime/core/file_io.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

TEST(FileIo, OnlyRegularFilesAreRead) {
  const fs::path dir = testing_util::test_tmp();
  fs::remove(dir / "pipe.bin");
  const fs::path file = dir / "a.bin", pipe = dir / "pipe.bin";
  std::ofstream(file) << "abc";
  ASSERT_EQ(mkfifo(pipe.c_str(), 0600), 0);

  // Missing paths and folders are left to each reader's own words.
  EXPECT_EQ(special_file_error(file), "");
  EXPECT_EQ(special_file_error(dir), "");
  EXPECT_EQ(special_file_error(dir / "none"), "");
  EXPECT_EQ(special_file_error(pipe),
            "not a regular file but a named pipe (FIFO); kaskad reads only regular files");
  EXPECT_EQ(special_file_error("/dev/null"),
            "not a regular file but a character device; kaskad reads only regular files");

  EXPECT_EQ(read_file_bytes(dir, 1024).error().message, "is a directory, not a file");
  EXPECT_EQ(read_file_bytes(dir / "none", 1024).error().message, "file not found");
  auto bytes = read_file_bytes(file, 1024);
  ASSERT_TRUE(bytes.ok());
  EXPECT_EQ(bytes->size(), 3u);
  // Returns at once (opening the pipe would wait for a writer).
  auto piped = read_file_bytes(pipe, 1024);
  ASSERT_FALSE(piped.ok());
  EXPECT_EQ(piped.error().file, pipe.string());
  EXPECT_NE(piped.error().message.find("named pipe"), std::string::npos);
}

}  // namespace
}  // namespace kaskad
