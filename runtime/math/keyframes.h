// Keyframe tracks as glTF 2.0 animation samplers define them (glTF 2.0, 3.11 "Animations" and
// Appendix C "Interpolation"): key times in seconds, strictly increasing, and a value per key
// (three per key for cubic splines: in-tangent, value, out-tangent). Pure maths: the glTF
// importer fills tracks, the animation system samples them.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace kaskad {

enum class KeyInterpolation { step, linear, cubic_spline };

/// What a track's values are: rotations are unit quaternions (x, y, z, w) and interpolate on the
/// sphere; everything else (translations, scales, morph weights) component by component.
enum class KeyKind { vector, rotation };

struct KeyTrack {
  KeyInterpolation interpolation = KeyInterpolation::linear;
  KeyKind kind = KeyKind::vector;
  std::vector<float> times;       ///< seconds, strictly increasing
  std::vector<glm::vec4> values;  ///< one per key; cubic_spline: 3 per key (in, value, out)

  float start() const { return times.empty() ? 0.0f : times.front(); }
  float end() const { return times.empty() ? 0.0f : times.back(); }
};

/// Why `track` cannot be sampled ("" when it can): no keys, times not finite or not strictly
/// increasing, the wrong number of values for its interpolation, non-finite values.
std::string validate_track(const KeyTrack& track);

/// The track's value at time `t` (seconds): before the first key the first value, after the last
/// the last (glTF: clamped); between keys as the interpolation says. Rotations come out unit
/// length. The track must be valid (validate_track()).
glm::vec4 sample(const KeyTrack& track, float t);

}  // namespace kaskad
