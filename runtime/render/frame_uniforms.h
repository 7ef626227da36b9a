// The frame's uniform block (FrameBlock in content/shaders/common.glsl, std140): its C++ layout
// and how a FrameInput fills it. Pure: no GL. The GLSL side is written against the same limits
// (components/limits.h, defined in every program); tests/render/frame_uniforms_test.cpp checks
// every member's offset against what the driver reports for the compiled block.
#pragma once

#include <glm/glm.hpp>

#include "components/limits.h"
#include "runtime/render/frame_input.h"

namespace kaskad::render {

/// One shadow view as the shaders read it (u_shadow_views[k]; ShadowView).
struct alignas(16) ShadowViewBlock {
  glm::mat4 view_proj[kMaxCascades];  ///< world -> light clip space per layer
  glm::vec4 splits[3];                ///< S0's D[0..8], four per vec4 (view_split(k, i))
  glm::vec4 texel[2];                 ///< metres per texel per layer (view_texel(k, i))
  glm::ivec4 info;                    ///< x light index, y first layer, z layer count
  glm::vec4 params;                   ///< x normal offset (texels), y blend band, z paraboloid margin,
                                      ///< w the light's size along the map's y (light_size.y)
  /// Soft shadows: x light size along the map's x (ShadowView::light_size.x; params.w holds y),
  /// y Poisson disc radius (texels), z taps,
  /// w the lookup's reach in texels (ShadowView::filter_reach).
  glm::vec4 soft;
};

struct alignas(16) FrameBlock {
  glm::mat4 view_proj;
  glm::mat4 view;
  /// xyz: world position; w: metres per pixel at 1 m of view depth (0: orthographic camera;
  /// negative, probe faces: -w metres per pixel per metre of distance from xyz)
  glm::vec4 camera_pos;
  glm::vec4 ambient;       ///< rgb: linear ambient radiance
  /// The environment map (VARIANT_ENVIRONMENT map): x intensity, y its prefiltered cube's
  /// last level (roughness 1)
  glm::vec4 environment;
  glm::vec4 environment_sh[9];  ///< rgb: the environment map's SH coefficients (project_sh9)
  /// x exposure, y shadow map size (texels a side), z lom layers, w vsm_bleed_reduction
  glm::vec4 frame_params;
  /// x lights shaded, y shadow views, z the view the AOV shows, w vsm_blur (texels a side)
  glm::ivec4 counts;
  glm::vec4 light_color[kMaxLights];  ///< rgb: colour * intensity
  glm::ivec4 light_info[kMaxLights];  ///< x LightType, y its shadow view (-1: none)
  glm::vec4 light_dir[kMaxLights];    ///< xyz: direction the light travels, w: range (0 = inf)
  glm::vec4 light_pos[kMaxLights];    ///< xyz: world position, w: cos(outer cone)
  glm::vec4 light_cone[kMaxLights];   ///< x: cos(inner cone)
  ShadowViewBlock shadow_views[kMaxShadowedLights];
  /// render.visibility_cache, a reprojecting frame (VARIANT_SHADOW_REUSE reproject): the camera
  /// of the frame whose visibility it reads, its view_proj and xyz its position. Written by the
  /// renderer when it reprojects (Renderer::render()); zero in pack_frame_block().
  glm::mat4 previous_view_proj{0.0f};
  glm::vec4 previous_camera_pos{0.0f};
};

/// The lights the shaders shade: the first kMaxLights of the frame's.
int shaded_lights(const FrameInput& frame);

/// Why the frame's shadow views cannot be drawn as given (empty: they can): too many views,
/// a light index that is not a shaded light, a layer count outside [1, kMaxCascades], layers
/// that do not follow each other from 0, a spot or point view after the first, a bad AOV view.
std::string shadow_views_error(const FrameInput& frame);

/// The block of the main view. Precondition: shadow_views_error(frame) is empty.
FrameBlock pack_frame_block(const FrameInput& frame);

/// The block of face `face` of a probe capture: the face camera at the probe centre, exposure 1
/// (cubes hold linear radiance; exposure applies where the map is shown). u_view stays the main
/// camera's: sphere-map lookups are the main view's.
FrameBlock probe_face_block(const FrameBlock& main, const ProbeJob& job, int face);

}  // namespace kaskad::render
