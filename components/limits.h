// The engine's fixed limits, defined once: the C++ side sizes its arrays with them and the shader
// library defines them in every program (MAX_LIGHTS, MAX_CASCADES, MAX_SHADOW_VIEWS; see
// FeatureManifest::defines), so the FrameBlock layout of both sides follows from one place.
#pragma once

namespace kaskad {

/// Lights shaded per frame; further lights are left out (with a warning).
inline constexpr int kMaxLights = 8;
/// Cascades of one directional light (S0's N), and the most layers any shadow view has (a point
/// light's cube has 6).
inline constexpr int kMaxCascades = 8;
/// Shadow views per frame: one per shadowed light, all in one depth texture array.
inline constexpr int kMaxShadowedLights = 4;

/// Layers of the shadow map array at most (every view at its most layers).
inline constexpr int kMaxShadowLayers = kMaxShadowedLights * kMaxCascades;
// DrawItem::shadow_layers and FrameStats::shadow_layers_rendered have one bit per layer.
static_assert(kMaxShadowLayers <= 32);

}  // namespace kaskad
