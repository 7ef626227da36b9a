// Shadow map parameters of one shadowed light, kept apart from Light (Bevy's CascadeShadowConfig
// beside DirectionalLight). Validated by validate_shadow_settings(); defaults cite their source.
#pragma once

#include <string>

namespace kaskad {

enum class CullMode { back, front, none };
/// none: one hardware-compared tap (nearest); bilinear: one tap with GL_LINEAR compare
/// (hardware 2x2 PCF); pcf3x3: average of a 3x3 neighbourhood of compares (S4).
enum class ShadowFilter { none, bilinear, pcf3x3 };

struct ShadowSettings {
  int map_size = 2048;            ///< texels per side; power of two in [64, 16384]
  float constant_bias = 2.0f;     ///< glPolygonOffset units (multiples of the depth resolution)
  float slope_bias = 3.0f;        ///< glPolygonOffset factor (scales with the depth slope, S2).
                                  ///< 3 because the 3x3 PCF taps reach 1.5 texels along each axis,
                                  ///< where depth changes by up to 1.5 (|dz/dx| + |dz/dy|), at most
                                  ///< 3x the max slope that glPolygonOffset scales by; 2 leaves acne
                                  ///< rings on the default scene's ground plane
  CullMode cull = CullMode::back; ///< back is the default for the shadow pass (S2); front reduces
                                  ///< acne but loses single-sided casters (S4, S2)
  ShadowFilter filter = ShadowFilter::pcf3x3;  ///< S4's 3x3 PCF by default
};

/// Empty string when valid, else a message naming the bad value.
inline std::string validate_shadow_settings(const ShadowSettings& s) {
  if (s.map_size < 64 || s.map_size > 16384 || (s.map_size & (s.map_size - 1)) != 0)
    return "map_size must be a power of two in [64, 16384], was " + std::to_string(s.map_size);
  if (!(s.constant_bias >= 0.0f && s.constant_bias <= 1.0e4f))
    return "constant_bias must be in [0, 10000], was " + std::to_string(s.constant_bias);
  if (!(s.slope_bias >= 0.0f && s.slope_bias <= 100.0f))
    return "slope_bias must be in [0, 100], was " + std::to_string(s.slope_bias);
  return {};
}

}  // namespace kaskad
