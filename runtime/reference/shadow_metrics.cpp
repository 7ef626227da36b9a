#include "runtime/reference/shadow_metrics.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace kaskad::reference {
namespace {

/// Sums of one set of pixels, turned into ShadowErrorStats by finish().
struct Accumulator {
  ShadowErrorStats stats;
  double squared = 0.0;
  double absolute = 0.0;

  void add(float method, float reference) {
    const bool method_shadowed = method < kShadowThreshold;
    const bool reference_shadowed = reference < kShadowThreshold;
    ++stats.pixels;
    if (method_shadowed != reference_shadowed) {
      ++stats.misclassified;
      if (method_shadowed) {
        ++stats.false_shadow;
      } else {
        ++stats.false_light;
      }
    }
    const double d = double(method) - double(reference);
    squared += d * d;
    absolute += std::abs(d);
  }

  ShadowErrorStats finish() const {
    ShadowErrorStats s = stats;
    if (s.pixels == 0) return s;
    const double n = double(s.pixels);
    s.misclassified_pct = 100.0 * double(s.misclassified) / n;
    s.false_shadow_pct = 100.0 * double(s.false_shadow) / n;
    s.false_light_pct = 100.0 * double(s.false_light) / n;
    s.rmse = std::sqrt(squared / n);
    s.mean_abs_error = absolute / n;
    return s;
  }
};

bool consistent(const Image& image) {
  return image.width > 0 && image.height > 0 && image.channels > 0 &&
         image.pixels.size() ==
             std::size_t(image.width) * std::size_t(image.height) * std::size_t(image.channels);
}

}  // namespace

ShadowMetrics compare_shadows(int width, int height, std::span<const float> method,
                              std::span<const float> reference,
                              std::span<const std::uint8_t> receiver) {
  KASKAD_CHECK(width >= 0 && height >= 0, "image size must be >= 0, was " + std::to_string(width) +
                                              "x" + std::to_string(height));
  const std::size_t count = std::size_t(width) * std::size_t(height);
  KASKAD_CHECK(method.size() == count && reference.size() == count && receiver.size() == count,
               "arrays must hold width * height = " + std::to_string(count) + " values, were " +
                   std::to_string(method.size()) + ", " + std::to_string(reference.size()) + ", " +
                   std::to_string(receiver.size()));

  // A pixel takes part when it is a receiver with finite values on both sides.
  auto counted = [&](std::size_t i) {
    return receiver[i] != 0 && std::isfinite(method[i]) && std::isfinite(reference[i]);
  };
  ShadowMetrics out;
  Accumulator all, outside;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
      if (receiver[i] == 0) continue;
      if (!counted(i)) {
        ++out.non_finite;
        continue;
      }
      all.add(method[i], reference[i]);
      // 1. The edge band: any counted 8-neighbour with the other binary reference value.
      const bool shadowed = reference[i] < kShadowThreshold;
      bool edge = false;
      for (int dy = -1; dy <= 1 && !edge; ++dy) {
        for (int dx = -1; dx <= 1 && !edge; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
          const std::size_t j = std::size_t(ny) * std::size_t(width) + std::size_t(nx);
          edge = counted(j) && (reference[j] < kShadowThreshold) != shadowed;
        }
      }
      // 2. Pixels away from edges form the second set.
      if (edge) {
        ++out.edge_pixels;
      } else {
        outside.add(method[i], reference[i]);
      }
    }
  }
  out.all = all.finish();
  out.outside_edges = outside.finish();
  return out;
}

Result<ShadowMetrics> compare_shadows(const Image& aov, const Image& reference) {
  if (!consistent(aov)) return Error{"", "AOV image", "size does not match its pixel count"};
  if (!consistent(reference))
    return Error{"", "reference image", "size does not match its pixel count"};
  if (aov.width != reference.width || aov.height != reference.height) {
    return Error{"", "reference image",
                 "is " + std::to_string(reference.width) + "x" + std::to_string(reference.height) +
                     " but the AOV image is " + std::to_string(aov.width) + "x" +
                     std::to_string(aov.height)};
  }
  const int method_ch = aov.channel("visibility");
  const int reference_ch = reference.channel("visibility");
  const int receiver_ch = reference.channel("receiver");
  if (method_ch < 0) return Error{"", "AOV image", "has no channel 'visibility'"};
  if (reference_ch < 0) return Error{"", "reference image", "has no channel 'visibility'"};
  if (receiver_ch < 0) return Error{"", "reference image", "has no channel 'receiver'"};

  const std::size_t count = std::size_t(aov.width) * std::size_t(aov.height);
  std::vector<float> method(count), ref(count);
  std::vector<std::uint8_t> receiver(count);
  for (std::size_t i = 0; i < count; ++i) {
    method[i] = aov.pixels[i * std::size_t(aov.channels) + std::size_t(method_ch)];
    ref[i] = reference.pixels[i * std::size_t(reference.channels) + std::size_t(reference_ch)];
    receiver[i] =
        reference.pixels[i * std::size_t(reference.channels) + std::size_t(receiver_ch)] >= 0.5f
            ? 1
            : 0;
  }
  return compare_shadows(aov.width, aov.height, method, ref, receiver);
}

StabilityStats shadow_stability(const std::vector<std::vector<float>>& visibility,
                                float change_threshold) {
  StabilityStats out;
  out.frames = visibility.size();
  out.points = visibility.empty() ? 0 : visibility.front().size();
  for (std::size_t f = 0; f < visibility.size(); ++f) {
    KASKAD_CHECK(visibility[f].size() == out.points,
                 "every frame must have " + std::to_string(out.points) + " points; frame " +
                     std::to_string(f) + " has " + std::to_string(visibility[f].size()));
  }
  double total = 0.0;
  std::size_t changed = 0;
  for (std::size_t f = 0; f + 1 < visibility.size(); ++f) {
    double frame_sum = 0.0;
    std::size_t frame_samples = 0;
    for (std::size_t p = 0; p < out.points; ++p) {
      const float a = visibility[f][p], b = visibility[f + 1][p];
      if (!std::isfinite(a) || !std::isfinite(b)) continue;
      const double d = std::abs(double(b) - double(a));
      frame_sum += d;
      ++frame_samples;
      if (d > change_threshold) ++changed;
    }
    out.flicker_per_frame.push_back(frame_samples ? frame_sum / double(frame_samples) : 0.0);
    total += frame_sum;
    out.samples += frame_samples;
  }
  if (out.samples > 0) {
    out.flicker = total / double(out.samples);
    out.changed_pct = 100.0 * double(changed) / double(out.samples);
  }
  return out;
}

}  // namespace kaskad::reference
