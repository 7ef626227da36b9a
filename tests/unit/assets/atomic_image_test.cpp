// Atomic image outputs (runtime/assets/image_io.h over runtime/core/atomic_file.h): a failed
// image write leaves the previous file byte-identical and no temporary file behind.
#include <gtest/gtest.h>

#include <string>

#include "runtime/assets/image_io.h"
#include "tests/unit/core/atomic_file_util.h"

namespace kaskad {
namespace {

using namespace test;  // fs, fresh_dir, read_text, files_in, mentions, FileSizeLimit

Image gradient(int width, int height) {
  Image image;
  image.width = width;
  image.height = height;
  image.channels = 3;
  for (int i = 0; i < width * height * 3; ++i) image.pixels.push_back(float((i * 7919) % 1000) / 999.0f);
  return image;
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

TEST(AtomicFile, AnImageNamedByAFolderSaysSo) {
  // The editor's `screenshot FOLDER` was told "cannot write this image format".
  const fs::path dir = fresh_dir("image_folder");
  fs::create_directories(dir / "shots");
  const Status st = save_image(dir / "shots", gradient(4, 4));
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().to_string().find("is a folder"), std::string::npos)
      << st.error().to_string();
  EXPECT_TRUE(fs::is_directory(dir / "shots"));
}

}  // namespace
}  // namespace kaskad
