// Tone mapping of the frame's linear colour: the curves the forward shader applies
// (content/shaders/tone_mapping.glsl evaluates the same formulas; tests/render/tone_mapping_test
// compares the two), also used on the CPU for the clear colour and by the tests. Plain maths.
#pragma once

#include <algorithm>
#include <array>
#include <string_view>

#include <glm/glm.hpp>

namespace kaskad {

/// render.tone_mapping. none: linear colour clamped by the sRGB target (the default, so that
/// images, goldens and the reference comparisons of colour keep their meaning).
enum class ToneMapping { none, khr_pbr_neutral, aces };
constexpr std::array<std::string_view, 3> enum_names(ToneMapping) {
  return {"none", "khr_pbr_neutral", "aces"};
}
static_assert(enum_names(ToneMapping{}).size() == std::size_t(ToneMapping::aces) + 1);

/// Khronos PBR Neutral (the Khronos 3D Commerce "PBR Neutral" tone mapper, 2024): colours below
/// a peak of 0.76 are only shifted down by an offset (at most 0.04, less for dark colours), so
/// base colours survive; brighter ones are compressed towards 1 and desaturated a little.
inline glm::vec3 tone_map_khr_pbr_neutral(glm::vec3 c) {
  constexpr float kStart = 0.8f - 0.04f;  // compression starts at this peak
  constexpr float kDesaturation = 0.15f;
  const float x = std::min(c.r, std::min(c.g, c.b));
  const float offset = x < 0.08f ? x - 6.25f * x * x : 0.04f;
  c -= offset;
  const float peak = std::max(c.r, std::max(c.g, c.b));
  if (peak < kStart) return c;
  constexpr float d = 1.0f - kStart;
  const float new_peak = 1.0f - d * d / (peak + d - kStart);
  c *= new_peak / peak;
  const float g = 1.0f - 1.0f / (kDesaturation * (peak - new_peak) + 1.0f);
  return glm::mix(c, glm::vec3(new_peak), g);
}

/// The fitted ACES filmic curve (Narkowicz 2015, "ACES Filmic Tone Mapping Curve"):
/// x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14) per channel, clamped to [0, 1].
inline glm::vec3 tone_map_aces(glm::vec3 x) {
  return glm::clamp(x * (2.51f * x + 0.03f) / (x * (2.43f * x + 0.59f) + 0.14f), 0.0f, 1.0f);
}

/// Linear colour (already scaled by the exposure) -> the colour written to the sRGB target.
inline glm::vec3 tone_map(ToneMapping mode, glm::vec3 c) {
  switch (mode) {
    case ToneMapping::khr_pbr_neutral: return tone_map_khr_pbr_neutral(c);
    case ToneMapping::aces: return tone_map_aces(c);
    case ToneMapping::none: break;
  }
  return c;
}

}  // namespace kaskad
