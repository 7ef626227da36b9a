#include "runtime/math/keyframes.h"

#include <algorithm>
#include <cmath>

namespace kaskad {
namespace {

bool finite(const glm::vec4& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w);
}

glm::vec4 normalized(const glm::vec4& q) {
  const float len = glm::length(q);
  return len > 0.0f ? q / len : glm::vec4(0, 0, 0, 1);
}

// Spherical interpolation along the shorter arc (glTF Appendix C); nearly parallel quaternions
// interpolate linearly, where the sine would lose its precision.
glm::vec4 slerp(glm::vec4 a, const glm::vec4& b, float s) {
  float d = glm::dot(a, b);
  if (d < 0.0f) {
    a = -a;
    d = -d;
  }
  if (d > 0.9995f) return normalized(a + s * (b - a));
  const float angle = std::acos(std::min(d, 1.0f));
  const float sin_angle = std::sin(angle);
  return normalized(a * (std::sin((1.0f - s) * angle) / sin_angle) +
                    b * (std::sin(s * angle) / sin_angle));
}

}  // namespace

std::string validate_track(const KeyTrack& track) {
  if (track.times.empty()) return "no keys";
  for (std::size_t i = 0; i < track.times.size(); ++i) {
    if (!std::isfinite(track.times[i])) return "key " + std::to_string(i) + ": time is not finite";
    if (track.times[i] < 0.0f)
      return "key " + std::to_string(i) + ": time is negative (times start at 0 or later)";
    if (i > 0 && !(track.times[i] > track.times[i - 1]))
      return "key " + std::to_string(i) + ": times must increase strictly";
  }
  const std::size_t per_key = track.interpolation == KeyInterpolation::cubic_spline ? 3 : 1;
  if (track.values.size() != per_key * track.times.size())
    return std::to_string(track.values.size()) + " values for " +
           std::to_string(track.times.size()) + " keys (" + std::to_string(per_key) +
           " per key expected)";
  for (std::size_t i = 0; i < track.values.size(); ++i)
    if (!finite(track.values[i])) return "value " + std::to_string(i) + " is not finite";
  return {};
}

glm::vec4 sample(const KeyTrack& track, float t) {
  const bool cubic = track.interpolation == KeyInterpolation::cubic_spline;
  auto value = [&](std::size_t k) { return track.values[cubic ? 3 * k + 1 : k]; };
  const std::size_t n = track.times.size();
  auto finish = [&](const glm::vec4& v) {
    return track.kind == KeyKind::rotation ? normalized(v) : v;
  };
  if (n == 1 || !(t > track.times.front())) return finish(value(0));
  if (t >= track.times.back()) return finish(value(n - 1));
  // The key interval [k, k + 1] holding t: times[k] <= t < times[k + 1].
  const std::size_t k =
      std::size_t(std::upper_bound(track.times.begin(), track.times.end(), t) - track.times.begin()) - 1;
  const float t0 = track.times[k], t1 = track.times[k + 1], span = t1 - t0;
  const float s = (t - t0) / span;
  switch (track.interpolation) {
    case KeyInterpolation::step: return finish(value(k));
    case KeyInterpolation::linear:
      if (track.kind == KeyKind::rotation) return slerp(value(k), value(k + 1), s);
      return value(k) + s * (value(k + 1) - value(k));
    case KeyInterpolation::cubic_spline: {
      // Hermite: value and out-tangent of key k, in-tangent and value of key k + 1, the
      // tangents scaled by the interval's length.
      const glm::vec4 v0 = value(k), b0 = track.values[3 * k + 2];
      const glm::vec4 a1 = track.values[3 * (k + 1)], v1 = value(k + 1);
      const float s2 = s * s, s3 = s2 * s;
      return finish((2 * s3 - 3 * s2 + 1) * v0 + span * (s3 - 2 * s2 + s) * b0 +
                    (-2 * s3 + 3 * s2) * v1 + span * (s3 - s2) * a1);
    }
  }
  return finish(value(k));
}

}  // namespace kaskad
