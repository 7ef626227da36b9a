// Image files through OpenImageIO: PNG, JPEG, EXR, HDR, TIFF, BMP, TGA, GIF, WebP, PNM, DDS, PSD.
// The format comes from the data's signature, else the MIME type, else the extension.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/result/result.h"

namespace kaskad {

/// Float pixels, channel-interleaved, rows top to bottom. Values are as stored in the file
/// (no colour-space conversion): 8-bit files map to [0,1].
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<std::string> channel_names;  ///< optional; e.g. {"R","G","B","A"} or {"P.X",...}
  std::vector<float> pixels;               ///< width * height * channels

  float& at(int x, int y, int c) { return pixels[(std::size_t(y) * width + x) * channels + c]; }
  float at(int x, int y, int c) const {
    return pixels[(std::size_t(y) * width + x) * channels + c];
  }
  /// Index of the channel named `name` (channel_names), or -1.
  int channel(std::string_view name) const {
    for (int c = 0; c < channels && c < int(channel_names.size()); ++c)
      if (channel_names[std::size_t(c)] == name) return c;
    return -1;
  }
};

/// Reads an image. Errors name the file and the problem (missing, unreadable, corrupt,
/// zero-sized, or beyond the limits: 32768 pixels a side, 16 channels, 2^28 values).
Result<Image> load_image(const std::filesystem::path& path);

/// Reads an image from memory (e.g. a glTF buffer view); `name` is used in error messages and
/// `mime_type` (may be empty) helps choose the format.
Result<Image> load_image_from_memory(const void* data, std::size_t size, const std::string& name,
                                     const std::string& mime_type = {});

/// 8-bit RGBA (TextureData's layout): grey expands to RGB, a missing alpha is 1, values are clamped
/// to [0,1] and rounded.
std::vector<std::uint8_t> to_rgba8(const Image& image);

/// Checks before any work that save_image(path, ...) can succeed: an image format OpenImageIO
/// writes (by the extension) and a writable path (check_output_path in atomic_file.h).
Status check_image_output(const std::filesystem::path& path);

/// Writes an image atomically (runtime/core/atomic_file.h: a failure leaves the previous file
/// as it was); the format follows the extension. 8-bit formats (PNG, JPEG) get values clamped
/// to [0,1] and quantised; EXR keeps 32-bit float and channel_names. Reading an EXR back may
/// reorder its channels (OIIO puts R, G, B, A first): look channels up by name.
Status save_image(const std::filesystem::path& path, const Image& image);

/// How two images of the same size differ (OpenImageIO's ImageBufAlgo::compare, as idiff).
struct ImageDiff {
  double max_error = 0.0;       ///< largest per-channel difference
  double mean_error = 0.0;      ///< mean per-channel difference
  std::size_t failing = 0;      ///< pixels with a channel difference above fail_threshold
  std::size_t warning = 0;      ///< pixels above warn_threshold
  std::size_t pixels = 0;
  Image diff;                   ///< |a - b| per channel, scaled by `diff_scale` for viewing
};

/// Compares `a` with `b` (same width, height and channels, else an error naming both sizes).
Result<ImageDiff> compare_images(const Image& a, const Image& b, float fail_threshold,
                                 float warn_threshold, float diff_scale = 10.0f);

}  // namespace kaskad
