// Accuracy metrics of a shadow technique against the ray-traced reference (DESIGN.md
// "Measuring"): per-image error counts over shadow-receiving pixels, and world-space stability of
// the shadow factor over frames. Pure CPU maths; no Embree, no GL.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "runtime/assets/image_io.h"
#include "runtime/result/result.h"

namespace kaskad::reference {

/// Binary classification: a visibility below this is "shadowed", at or above it "lit".
inline constexpr float kShadowThreshold = 0.5f;

/// Errors of a method's visibility against the reference over a set of receiver pixels.
/// Percentages are of `pixels` (0 when there are none).
struct ShadowErrorStats {
  std::size_t pixels = 0;         ///< receiver pixels counted
  std::size_t misclassified = 0;  ///< binary method != binary reference
  std::size_t false_shadow = 0;   ///< reference lit, method shadowed: acne, over-darkening
  std::size_t false_light = 0;    ///< reference shadowed, method lit: Peter Panning, leaks, lost
                                  ///< casters
  double misclassified_pct = 0.0;
  double false_shadow_pct = 0.0;
  double false_light_pct = 0.0;
  double rmse = 0.0;            ///< sqrt(mean((method - reference)^2)) of visibility
  double mean_abs_error = 0.0;  ///< mean(|method - reference|) of visibility
};

struct ShadowMetrics {
  ShadowErrorStats all;  ///< every receiver pixel
  /// Receiver pixels outside the 1-pixel band around reference shadow edges: a pixel is in the
  /// band when any of its 8 neighbours that is a receiver has the other binary reference value.
  /// The band holds the pixels whose classification depends on sub-pixel edge placement.
  ShadowErrorStats outside_edges;
  std::size_t edge_pixels = 0;  ///< receiver pixels in the band (all.pixels - outside_edges.pixels)
  std::size_t non_finite = 0;   ///< receiver pixels skipped: method or reference not finite
};

/// Metrics from per-pixel arrays (row-major, width * height each): the method's visibility, the
/// reference visibility, and the receiver mask (non-zero = counted; see
/// ReferenceOptions::facing_threshold). Precondition: sizes match width * height.
ShadowMetrics compare_shadows(int width, int height, std::span<const float> method,
                              std::span<const float> reference,
                              std::span<const std::uint8_t> receiver);

/// Metrics from images: the method's "visibility" channel of an AOV image (Renderer::read_aovs())
/// and the "visibility" and "receiver" channels of a reference image (ShadowReference::image).
/// Channels are looked up by name. Errors: a channel is missing or the sizes differ.
Result<ShadowMetrics> compare_shadows(const Image& aov, const Image& reference);

/// A change of the shadow factor at a point between two frames counts when larger than this:
/// one step of an 8-bit image.
inline constexpr float kStabilityChangeThreshold = 1.0f / 255.0f;

/// World-space stability of the shadow factor while only the camera moves.
struct StabilityStats {
  std::size_t frames = 0;
  std::size_t points = 0;
  std::size_t samples = 0;   ///< (point, consecutive frame pair) samples with finite values
  double flicker = 0.0;      ///< mean |v[f+1][p] - v[f][p]| over all samples
  double changed_pct = 0.0;  ///< % of samples with |v[f+1][p] - v[f][p]| > change threshold
  std::vector<double> flicker_per_frame;  ///< mean |delta| of each frame pair (frames - 1 values)
};

/// Stability of visibility sampled at a fixed set of world points: visibility[f][p] is point p in
/// frame f. Non-finite values (a point off screen or hidden in that frame) leave their samples
/// out. Precondition: every frame has the same number of points.
StabilityStats shadow_stability(const std::vector<std::vector<float>>& visibility,
                                float change_threshold = kStabilityChangeThreshold);

}  // namespace kaskad::reference
