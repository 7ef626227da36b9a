// Cascaded shadow map parameters of one shadowed directional light (S0, with S2's stabilisation),
// kept apart from Light and from the basic ShadowSettings (Bevy's CascadeShadowConfig beside
// DirectionalLight). Plain data; validate_cascade_settings() names the first bad value. Each
// default says where it comes from. The maths lives in systems/cascade_math.h.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

namespace kaskad {

/// How the view depth range [near, far] is cut into cascades (S0 eq. (1)-(3)).
enum class SplitScheme {
  uniform,  ///< S0 eq. (1): d_i = d_n + (d_f - d_n) i / N
  log,      ///< S0 eq. (2): d_i = d_n (d_f / d_n)^(i / N)
  mixed,    ///< S0 eq. (3): lambda * (2) + (1 - lambda) * (1)
};

/// Depth attachment format of the cascade maps.
enum class DepthFormat { d16, d24, d32f };

/// How a cascade's light projection is fitted to its view-frustum slice.
enum class FitMode {
  crop,    ///< S0 steps 2-5: M_proj = M_crop * M_Lprj, tight around the slice's 8 corners; the
           ///< size changes as the camera turns, so edges shimmer when the camera moves
  stable,  ///< S2: the slice's bounding sphere (size fixed by the slice's shape), origin snapped
           ///< to whole texels; wastes some area but shadow edges stay still
};

/// How a shaded point picks its cascade.
enum class CascadeSelection {
  depth,       ///< S0: slice i where D[i] <= |z_view| < D[i+1]
  map_bounds,  ///< the first cascade whose map contains the point (uses the stable fit's slack)
};

struct CascadeSettings {
  /// N, in [1, 8]. 4: S0 recommends 3..5 (fewer is barely better than one map; each more costs
  /// a scene render).
  int cascade_count = 4;
  /// S0 eq. (3), the paper's choice.
  SplitScheme split_scheme = SplitScheme::mixed;
  /// Mixed-split weight of the log scheme, in [0, 1]. 0.5: S0's default.
  float lambda = 0.5f;
  /// Metres from the camera where the last cascade ends; 0 = the camera's far plane. 100: engine
  /// choice, half the default camera far (components/camera.h), so resolution is not spent on
  /// the horizon.
  float max_distance = 100.0f;
  /// Texels per side of each cascade map; power of two in [64, 16384]. 2048: the basic map's
  /// default (shadow_settings.h).
  int map_size = 2048;
  /// S2: 16 bits suffice when near/far are tight; 24 because S0 step 3 pulls the near plane back
  /// to distant casters, which loosens the range.
  DepthFormat depth_format = DepthFormat::d24;
  /// S2: stabilised cascades do not shimmer as the camera moves.
  FitMode fit_mode = FitMode::stable;
  /// Metres, >= 0: S0's searchlight cylinder radius R around the light axis (through the light
  /// entity's position); 0 = fit to the scene. Used by FitMode::crop only.
  float beam_radius = 0.0f;
  /// Texels of the cascade, in [0, 16]: shading points move this far along the normal before
  /// the lookup. 1 texel as in MJP's 2015 shadow sample update (offset scaled by texel size).
  float normal_offset_bias = 1.0f;
  /// Fraction of a cascade's depth range, in [0, 1], over which it fades into the next one
  /// (with map_bounds selection: fraction of the map's half-width); 0 = hard seams. 0.1: engine
  /// choice.
  float blend_band = 0.1f;
  /// S0's D array by default.
  CascadeSelection selection = CascadeSelection::depth;
};

namespace cascade_settings_detail {
/// Shortest readable form of a setting ("1.2", not "1.200000").
inline std::string str(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
  return buf;
}
}  // namespace cascade_settings_detail

/// Empty string when valid, else a message naming the first bad value, e.g.
/// "lambda must be in [0, 1], was 1.2".
inline std::string validate_cascade_settings(const CascadeSettings& s) {
  using cascade_settings_detail::str;
  if (s.cascade_count < 1 || s.cascade_count > 8)
    return "cascade_count must be in [1, 8], was " + std::to_string(s.cascade_count);
  const int scheme = static_cast<int>(s.split_scheme);
  if (scheme < 0 || scheme > static_cast<int>(SplitScheme::mixed))
    return "split_scheme must be uniform, log or mixed, was " + std::to_string(scheme);
  if (!(s.lambda >= 0.0f && s.lambda <= 1.0f))  // also rejects NaN
    return "lambda must be in [0, 1], was " + str(s.lambda);
  if (!(s.max_distance >= 0.0f && std::isfinite(s.max_distance)))
    return "max_distance must be finite and >= 0 (0 = camera far), was " + str(s.max_distance);
  if (s.map_size < 64 || s.map_size > 16384 || (s.map_size & (s.map_size - 1)) != 0)
    return "map_size must be a power of two in [64, 16384], was " + std::to_string(s.map_size);
  const int format = static_cast<int>(s.depth_format);
  if (format < 0 || format > static_cast<int>(DepthFormat::d32f))
    return "depth_format must be d16, d24 or d32f, was " + std::to_string(format);
  const int fit = static_cast<int>(s.fit_mode);
  if (fit < 0 || fit > static_cast<int>(FitMode::stable))
    return "fit_mode must be crop or stable, was " + std::to_string(fit);
  if (!(s.beam_radius >= 0.0f && std::isfinite(s.beam_radius)))
    return "beam_radius must be finite and >= 0 (0 = fit to the scene), was " + str(s.beam_radius);
  if (!(s.normal_offset_bias >= 0.0f && s.normal_offset_bias <= 16.0f))
    return "normal_offset_bias must be in [0, 16] texels, was " + str(s.normal_offset_bias);
  if (!(s.blend_band >= 0.0f && s.blend_band <= 1.0f))
    return "blend_band must be in [0, 1], was " + str(s.blend_band);
  const int selection = static_cast<int>(s.selection);
  if (selection < 0 || selection > static_cast<int>(CascadeSelection::map_bounds))
    return "selection must be depth or map_bounds, was " + std::to_string(selection);
  return {};
}

}  // namespace kaskad
