// Limits of the shadow data the renderer packs into its frame block: the shadow system publishes
// no more than this (systems/shadow_cascade_system.h uses the same constant).
#pragma once

namespace kaskad::render {

/// Shadowed lights with maps at most: the first (any type) plus up to 3 further directional ones.
/// MAX_EXTRA_SHADOWS in content/shaders/common.glsl is this - 1 (the FrameBlock layout).
inline constexpr int kMaxShadowedLights = 4;

}  // namespace kaskad::render
