#include "systems/camera_system.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "components/transform.h"
#include "runtime/core/log.h"

namespace kaskad {
namespace {

// World matrix without scale: rotation columns normalised.
glm::mat4 rigid(const glm::mat4& m) {
  glm::mat4 r = m;
  for (int i = 0; i < 3; ++i) {
    const float len = glm::length(glm::vec3(m[i]));
    if (len > 0.0f) r[i] = m[i] / len;
  }
  return r;
}

}  // namespace

float camera_world_scale(const glm::mat4& world_matrix) {
  const float scale = std::cbrt(std::abs(glm::determinant(glm::mat3(world_matrix))));
  return std::isfinite(scale) && scale > 0.0f ? scale : 1.0f;
}

CameraState select_camera(const ecs::World& world, float output_aspect) {
  CameraState out;
  glm::mat4 world_matrix(1.0f);
  bool found_active = false;
  world.view<Camera, WorldTransform>().each(
      [&](ecs::Entity e, const Camera& cam, const WorldTransform& wt) {
        if (found_active) return;
        if (!out.entity.valid() || cam.active) {
          out.entity = e;
          out.camera = cam;
          world_matrix = wt.matrix;
          found_active = cam.active;
        }
      });
  if (!out.entity.valid()) return out;
  // A camera inside a scaled hierarchy sees what it saw before scaling (camera_world_scale());
  // its view drops the scale.
  const float scale = camera_world_scale(world_matrix);
  if (scale != 1.0f) {
    out.camera.near *= scale;
    out.camera.far *= scale;
    out.camera.ortho_height *= scale;
  }
  const Camera& c = out.camera;
  out.aspect = c.aspect > 0.0f ? c.aspect : output_aspect;
  const glm::mat4 m = rigid(world_matrix);
  out.view = glm::inverse(m);
  out.position = glm::vec3(m[3]);
  if (c.projection == Projection::perspective) {
    out.proj = glm::perspective(glm::radians(c.fov_y_deg), out.aspect, c.near, c.far);
  } else {
    const float h = 0.5f * c.ortho_height, w = h * out.aspect;
    out.proj = glm::ortho(-w, w, -h, h, c.near, c.far);
  }
  return out;
}

glm::ivec2 fit_output_to_camera(const ecs::World& world, int width, int height) {
  const glm::ivec2 request{width, height};
  const CameraState cam = select_camera(world, float(width) / float(height));
  if (!cam.entity.valid() || !(cam.camera.aspect > 0.0f)) return request;
  const float a = cam.camera.aspect;
  glm::ivec2 out = request;
  if (a > float(width) / float(height))
    out.y = std::max(1, int(std::lround(float(width) / a)));
  else
    out.x = std::max(1, int(std::lround(float(height) * a)));
  return out;
}

void frame_auto_cameras(ecs::World& world, const Aabb& bounds, const Aabb& depth_bounds,
                        float output_aspect) {
  if (bounds.empty()) return;
  const glm::vec3 center = bounds.center();
  const float radius = std::max(0.5f * glm::length(bounds.extent()), 1e-3f);
  world.view<Camera, Transform>().each([&](ecs::Entity e, Camera& cam, Transform& t) {
    if (!cam.auto_frame) return;
    if (t.parent.valid()) {
      log::warn("camera %u: auto_frame ignored for a camera with a parent", e.index);
      return;
    }
    const glm::vec3 forward = glm::normalize(t.rotation * glm::vec3(0, 0, -1));
    const float aspect = cam.aspect > 0.0f ? cam.aspect : output_aspect;
    float distance;
    if (cam.projection == Projection::perspective) {
      // Bounding sphere inside the narrower of the two field-of-view half-angles.
      const float half_v = glm::radians(cam.fov_y_deg) * 0.5f;
      const float half_h = std::atan(std::tan(half_v) * aspect);
      distance = radius / std::sin(std::min(half_v, half_h));
    } else {
      distance = 2.0f * radius;
      cam.ortho_height = 2.0f * radius * std::max(1.0f, 1.0f / aspect);
    }
    t.translation = center - forward * distance;
    cam.near = std::max(distance - radius, distance * 1e-3f) * 0.9f;
    cam.far = (distance + radius) * 1.1f;
    for (int i = 0; i < 8 && !depth_bounds.empty(); ++i) {
      const glm::vec3 c{(i & 1) ? depth_bounds.max.x : depth_bounds.min.x,
                        (i & 2) ? depth_bounds.max.y : depth_bounds.min.y,
                        (i & 4) ? depth_bounds.max.z : depth_bounds.min.z};
      cam.far = std::max(cam.far, glm::dot(c - t.translation, forward) * 1.01f);
    }
  });
}

}  // namespace kaskad
