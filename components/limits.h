// The engine's fixed limits, defined once: the C++ side sizes its arrays with them and the shader
// library defines them in every program (MAX_LIGHTS, MAX_CASCADES, MAX_SHADOW_VIEWS,
// PCSS_MAX_RADIUS; see
// FeatureManifest::defines), so the FrameBlock layout of both sides follows from one place.
#pragma once

namespace kaskad {

/// The largest |coordinate| or distance a file may give, scene units: beyond it float precision is
/// meaningless (a metre step at 1e7 is below float's resolution).
inline constexpr float kMaxCoordinate = 1.0e7f;
/// Lights shaded per frame; further lights are left out (with a warning).
inline constexpr int kMaxLights = 8;
/// Cascades of one directional light (S0's N), and the most layers any shadow view has (a point
/// light's cube has 6).
inline constexpr int kMaxCascades = 8;
/// Shadow views per frame: one per shadowed light, all in one depth texture array.
inline constexpr int kMaxShadowedLights = 4;

/// PCSS's widest blocker search and filter radius, texels (PCSS_MAX_RADIUS in the shaders): bounds
/// the cost of sparse taps over huge regions (a receiver far behind the map's near plane);
/// penumbrae wider than twice this are cut. Local lights keep this many texels (plus one) free at
/// their maps' edges (filter_reach_texels()).
inline constexpr int kPcssMaxRadiusTexels = 48;

/// Layers of the shadow map array at most (every view at its most layers).
inline constexpr int kMaxShadowLayers = kMaxShadowedLights * kMaxCascades;
// DrawItem::shadow_layers and FrameStats::shadow_layers_rendered have one bit per layer.
static_assert(kMaxShadowLayers <= 32);

}  // namespace kaskad
