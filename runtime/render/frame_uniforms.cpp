#include "runtime/render/frame_uniforms.h"

#include <algorithm>
#include <string>

#include "components/ibl.h"
#include "runtime/assets/env_map.h"

namespace kaskad::render {

int shaded_lights(const FrameInput& frame) {
  return std::min<int>(int(frame.lights.size()), kMaxLights);
}

std::string shadow_views_error(const FrameInput& frame) {
  const auto& views = frame.shadow_views;
  if (int(views.size()) > kMaxShadowedLights)
    return std::to_string(views.size()) + " shadow views; at most " +
           std::to_string(kMaxShadowedLights);
  int next_layer = 0;
  for (std::size_t k = 0; k < views.size(); ++k) {
    const ShadowView& v = views[k];
    const std::string which = "shadow view " + std::to_string(k) + ": ";
    if (v.light_index < 0 || v.light_index >= shaded_lights(frame))
      return which + "light index " + std::to_string(v.light_index) + " is not one of the " +
             std::to_string(shaded_lights(frame)) + " shaded lights";
    if (v.layer_count < 1 || v.layer_count > kMaxCascades)
      return which + std::to_string(v.layer_count) + " layers; must be in [1, " +
             std::to_string(kMaxCascades) + "]";
    if (v.first_layer != next_layer)
      return which + "first layer " + std::to_string(v.first_layer) + ", expected " +
             std::to_string(next_layer) + " (views follow each other)";
    if (k > 0 && v.projection != ShadowProjection::ortho)
      return which + "only the first view may be a spot or point light's";
    next_layer += v.layer_count;
  }
  if (!views.empty() && (frame.aov_shadow_view < 0 || frame.aov_shadow_view >= int(views.size())))
    return "aov_shadow_view " + std::to_string(frame.aov_shadow_view) + " is not one of the " +
           std::to_string(views.size()) + " shadow views";
  return {};
}

namespace {

ShadowViewBlock pack_view(const ShadowView& v) {
  ShadowViewBlock b{};
  for (int i = 0; i < v.layer_count; ++i) {
    b.view_proj[i] = v.view_proj[std::size_t(i)];
    b.texel[i / 4][i % 4] = v.texel_size[std::size_t(i)];
  }
  for (int i = 0; i <= v.layer_count; ++i) b.splits[i / 4][i % 4] = v.splits[std::size_t(i)];
  b.info = glm::ivec4(v.light_index, v.first_layer, v.layer_count, 0);
  b.params = glm::vec4(v.normal_offset, v.blend_band, v.paraboloid_margin, v.light_size.y);
  b.soft = glm::vec4(v.light_size.x, v.pcf_radius, float(v.pcf_taps), v.filter_reach);
  return b;
}

}  // namespace

FrameBlock pack_frame_block(const FrameInput& frame) {
  FrameBlock fb{};
  fb.view_proj = frame.camera.proj * frame.camera.view;
  fb.view = frame.camera.view;
  // w: metres per pixel at 1 m of view depth, 2 tan(fov_y / 2) / height (proj[1][1] =
  // 1 / tan(fov_y / 2)); 0 for an orthographic camera (the VSM lookups then read mip 0).
  const bool ortho = frame.camera.proj[3][3] != 0.0f;
  const float pixel = ortho ? 0.0f : 2.0f / (frame.camera.proj[1][1] * float(frame.height));
  fb.camera_pos = glm::vec4(frame.camera.position, pixel);
  fb.ambient = glm::vec4(frame.ambient, 0.0f);
  if (frame.environment)
    fb.environment = glm::vec4(frame.environment_intensity,
                               float(ibl_specular_levels(frame.environment->size) - 1), 0.0f, 0.0f);
  for (std::size_t i = 0; i < 9; ++i) fb.environment_sh[i] = glm::vec4(frame.environment_sh[i], 0.0f);
  fb.frame_params = glm::vec4(frame.exposure, float(frame.shadow_settings.map_size),
                              float(frame.shadow_settings.lom_layers),
                              frame.shadow_settings.vsm_bleed_reduction);
  const int lights = shaded_lights(frame);
  const int views = int(frame.shadow_views.size());
  fb.counts =
      glm::ivec4(lights, views, views > 0 ? frame.aov_shadow_view : -1, frame.shadow_settings.vsm_blur);
  for (int i = 0; i < lights; ++i) {
    const LightItem& l = frame.lights[std::size_t(i)];
    fb.light_color[i] = glm::vec4(l.color, 0.0f);
    fb.light_info[i] = glm::ivec4(int(l.type), -1, 0, 0);
    fb.light_dir[i] = glm::vec4(l.direction, l.range);
    fb.light_pos[i] = glm::vec4(l.position, l.cos_outer);
    fb.light_cone[i] = glm::vec4(l.cos_inner, 0, 0, 0);
  }
  for (int k = 0; k < views; ++k) {
    const ShadowView& v = frame.shadow_views[std::size_t(k)];
    fb.shadow_views[k] = pack_view(v);
    fb.light_info[v.light_index].y = k;
  }
  return fb;
}

FrameBlock probe_face_block(const FrameBlock& main, const ProbeJob& job, int face) {
  FrameBlock fb = main;
  fb.view_proj = job.view_proj[std::size_t(face)];
  // A 90-degree face: 2 tan(45 deg) / resolution metres per pixel at 1 m. A face's depth is not
  // the main view's (u_view stays the main camera's), so negated as for an ortho camera: the
  // lookup's footprint then uses the distance from u_camera_pos (shadow_moments.glsl's pixel_footprint()).
  fb.camera_pos = glm::vec4(job.center, -2.0f / float(std::max(job.resolution, 1)));
  fb.frame_params.x = 1.0f;
  return fb;
}

}  // namespace kaskad::render
