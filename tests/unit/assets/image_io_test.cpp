#include "runtime/assets/image_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tests/unit/assets/asset_test_util.h"

namespace kaskad {
namespace {

using test::content_path;
using test::read_bytes;
using test::temp_dir;
using test::write_bytes;

/// A small image whose values are exact 8-bit levels (k / 255), so an 8-bit round trip is exact.
Image make_levels_image(int width, int height, int channels) {
  Image image;
  image.width = width;
  image.height = height;
  image.channels = channels;
  image.pixels.resize(std::size_t(width) * height * channels);
  for (std::size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = float((i * 37 + 11) % 256) / 255.0f;
  return image;
}

bool mentions(const Error& error, const std::string& text) {
  return error.to_string().find(text) != std::string::npos;
}

TEST(ImageIo, PngRoundTripIsExactForEightBitLevels) {
  const Image image = make_levels_image(5, 3, 4);
  const auto path = temp_dir() / "levels.png";
  ASSERT_TRUE(save_image(path, image).ok());

  auto loaded = load_image(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  EXPECT_EQ(loaded->width, 5);
  EXPECT_EQ(loaded->height, 3);
  ASSERT_EQ(loaded->channels, 4);
  for (std::size_t i = 0; i < image.pixels.size(); ++i)
    ASSERT_FLOAT_EQ(loaded->pixels[i], image.pixels[i]) << "value " << i;
}

TEST(ImageIo, PngClampsOutOfRangeValues) {
  Image image;
  image.width = 4;
  image.height = 1;
  image.channels = 1;
  image.pixels = {-0.5f, 1.5f, NAN, 0.5f};
  const auto path = temp_dir() / "clamped.png";
  ASSERT_TRUE(save_image(path, image).ok());

  auto loaded = load_image(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  EXPECT_EQ(loaded->pixels[0], 0.0f);
  EXPECT_EQ(loaded->pixels[1], 1.0f);
  EXPECT_EQ(loaded->pixels[2], 0.0f);  // NaN is written as 0, not left to the plugin
  EXPECT_NEAR(loaded->pixels[3], 128.0f / 255.0f, 1e-6f);
}

TEST(ImageIo, ExrRoundTripKeepsFloatsAndNamedChannels) {
  Image image;
  image.width = 3;
  image.height = 2;
  image.channels = 3;
  image.channel_names = {"P.X", "P.Y", "P.Z"};
  for (int i = 0; i < 18; ++i) image.pixels.push_back(float(i) * 1.37f - 7.0f + 1e-3f * i * i);
  image.pixels[4] = 65504.0f * 3.0f;  // beyond half range: must stay 32-bit
  const auto path = temp_dir() / "positions.exr";
  ASSERT_TRUE(save_image(path, image).ok());

  auto loaded = load_image(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  ASSERT_EQ(loaded->channels, 3);
  EXPECT_EQ(loaded->channel_names, image.channel_names);
  EXPECT_EQ(loaded->pixels, image.pixels);
}

TEST(ImageIo, ExrChannelsAreFoundByNameAfterReordering) {
  Image image;
  image.width = 1;
  image.height = 1;
  image.channels = 4;
  image.channel_names = {"Z", "A", "N.y", "B"};
  image.pixels = {1.0f, 2.0f, 3.0f, 4.0f};
  const auto path = temp_dir() / "reordered.exr";
  ASSERT_TRUE(save_image(path, image).ok());
  auto loaded = load_image(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  ASSERT_EQ(loaded->channels, 4);
  for (int c = 0; c < 4; ++c) {
    const auto it = std::find(loaded->channel_names.begin(), loaded->channel_names.end(),
                              image.channel_names[std::size_t(c)]);
    ASSERT_NE(it, loaded->channel_names.end()) << image.channel_names[std::size_t(c)];
    EXPECT_EQ(loaded->pixels[std::size_t(it - loaded->channel_names.begin())],
              image.pixels[std::size_t(c)]);
  }
}

TEST(ImageIo, ExrRoundTripRgba) {
  Image image = make_levels_image(4, 4, 4);
  image.pixels[0] = 12.5f;  // HDR value
  image.pixels[1] = -3.0f;
  const auto path = temp_dir() / "rgba.exr";
  ASSERT_TRUE(save_image(path, image).ok());
  auto loaded = load_image(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  EXPECT_EQ(loaded->channel_names, (std::vector<std::string>{"R", "G", "B", "A"}));
  EXPECT_EQ(loaded->pixels, image.pixels);
}

// Formats without alpha keep the colour: JPEG, and Radiance HDR (which refuses a fourth
// channel: an RGBA sphere map or face written as .hdr failed).
TEST(ImageIo, FormatsWithoutAlphaDropItAndStayClose) {
  Image image;
  image.width = 16;
  image.height = 16;
  image.channels = 4;
  for (int i = 0; i < 16 * 16; ++i) {
    image.pixels.insert(image.pixels.end(), {0.25f, 0.5f, 0.75f, 1.0f});
  }
  for (const char* name : {"flat.jpg", "flat.hdr"}) {
    const auto path = temp_dir() / name;
    auto saved = save_image(path, image);
    ASSERT_TRUE(saved.ok()) << saved.error().to_string();
    auto loaded = load_image(path);
    ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
    ASSERT_EQ(loaded->channels, 3) << name;
    EXPECT_NEAR(loaded->at(7, 7, 0), 0.25f, 0.02f) << name;
    EXPECT_NEAR(loaded->at(7, 7, 1), 0.5f, 0.02f) << name;
    EXPECT_NEAR(loaded->at(7, 7, 2), 0.75f, 0.02f) << name;
  }
}

TEST(ImageIo, LoadsRealJpeg) {
  auto image = load_image(content_path("env/cube/SwedishRoyalCastle/py.jpg"));
  ASSERT_TRUE(image.ok()) << image.error().to_string();
  EXPECT_EQ(image->width, 512);
  EXPECT_EQ(image->height, 512);
  EXPECT_EQ(image->channels, 3);
  const auto [lo, hi] = std::minmax_element(image->pixels.begin(), image->pixels.end());
  EXPECT_GE(*lo, 0.0f);
  EXPECT_LE(*hi, 1.0f);
  EXPECT_GT(*hi, *lo);  // not a blank image
}

TEST(ImageIo, LoadsRealHdrWithValuesAboveOne) {
  auto image = load_image(content_path("env/equirect/venice_sunset_1k.hdr"));
  ASSERT_TRUE(image.ok()) << image.error().to_string();
  EXPECT_EQ(image->width, 1024);
  EXPECT_EQ(image->height, 512);
  EXPECT_EQ(image->channels, 3);
  const float brightest = *std::max_element(image->pixels.begin(), image->pixels.end());
  EXPECT_GT(brightest, 10.0f);  // the sun
  for (float v : image->pixels) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
}

TEST(ImageIo, MemoryDecodeMatchesFileDecode) {
  const auto path = content_path("models/CesiumMilkTruck/glTF/CesiumMilkTruck.png");
  const auto bytes = read_bytes(path);
  auto from_file = load_image(path);
  // The name has no extension: the format must come from the magic bytes.
  auto from_memory = load_image_from_memory(bytes.data(), bytes.size(), "embedded image");
  ASSERT_TRUE(from_file.ok()) << from_file.error().to_string();
  ASSERT_TRUE(from_memory.ok()) << from_memory.error().to_string();
  EXPECT_EQ(from_memory->width, from_file->width);
  EXPECT_EQ(from_memory->channels, from_file->channels);
  EXPECT_EQ(from_memory->pixels, from_file->pixels);
}

TEST(ImageIo, MissingFileNamesTheFile) {
  const auto path = temp_dir() / "does_not_exist.png";
  auto image = load_image(path);
  ASSERT_FALSE(image.ok());
  EXPECT_TRUE(mentions(image.error(), path.string())) << image.error().to_string();
  EXPECT_TRUE(mentions(image.error(), "not found")) << image.error().to_string();
}

TEST(ImageIo, EmptyFileIsAnError) {
  const auto path = temp_dir() / "empty.png";
  write_bytes(path, nullptr, 0);
  auto image = load_image(path);
  ASSERT_FALSE(image.ok());
  EXPECT_TRUE(mentions(image.error(), path.string()));
  EXPECT_TRUE(mentions(image.error(), "empty")) << image.error().to_string();
}

TEST(ImageIo, GarbageBytesAreAnErrorNotACrash) {
  std::vector<std::uint8_t> garbage(4096);
  for (std::size_t i = 0; i < garbage.size(); ++i) garbage[i] = std::uint8_t(i * 131 + 7);
  for (const char* name : {"garbage.png", "garbage.jpg", "garbage.exr", "garbage.hdr",
                           "garbage.unknownext", "garbage"}) {
    const auto path = temp_dir() / name;
    write_bytes(path, garbage);
    auto image = load_image(path);
    ASSERT_FALSE(image.ok()) << name;
    EXPECT_TRUE(mentions(image.error(), path.string())) << image.error().to_string();

    auto from_memory = load_image_from_memory(garbage.data(), garbage.size(), name);
    ASSERT_FALSE(from_memory.ok()) << name;
    EXPECT_TRUE(mentions(from_memory.error(), name)) << from_memory.error().to_string();
  }
}

TEST(ImageIo, TruncatedPngIsAnError) {
  auto bytes = read_bytes(content_path("models/CesiumMilkTruck/glTF/CesiumMilkTruck.png"));
  ASSERT_GT(bytes.size(), 1000u);
  for (std::size_t keep : {bytes.size() / 2, std::size_t(100), std::size_t(8)}) {
    const auto path = temp_dir() / ("truncated_" + std::to_string(keep) + ".png");
    write_bytes(path, bytes.data(), keep);
    auto image = load_image(path);
    ASSERT_FALSE(image.ok()) << "kept " << keep << " bytes";
    EXPECT_TRUE(mentions(image.error(), path.string())) << image.error().to_string();

    auto from_memory = load_image_from_memory(bytes.data(), keep, "truck.png", "image/png");
    ASSERT_FALSE(from_memory.ok());
    EXPECT_TRUE(mentions(from_memory.error(), "truck.png"));
  }
}

TEST(ImageIo, TruncatedJpegAndHdrAreErrorsOrDecodedPartially) {
  // libjpeg pads a truncated scan with grey and warns; either outcome is fine as long as it is
  // reported without crashing and a successful result is complete.
  for (const char* file :
       {"env/cube/SwedishRoyalCastle/py.jpg", "env/equirect/venice_sunset_1k.hdr"}) {
    auto bytes = read_bytes(content_path(file));
    auto image = load_image_from_memory(bytes.data(), bytes.size() / 2, file);
    if (image.ok()) {
      EXPECT_EQ(image->pixels.size(), std::size_t(image->width) * image->height * image->channels);
    } else {
      EXPECT_TRUE(mentions(image.error(), file));
    }
  }
}

TEST(ImageIo, SaveToMissingDirectoryIsAnError) {
  const auto path = temp_dir() / "no_such_dir" / "out.png";
  auto status = save_image(path, make_levels_image(2, 2, 3));
  ASSERT_FALSE(status.ok());
  EXPECT_TRUE(mentions(status.error(), path.string())) << status.error().to_string();
}

}  // namespace
}  // namespace kaskad
