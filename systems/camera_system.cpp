#include "systems/camera_system.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "components/name.h"
#include "components/transform.h"
#include "runtime/core/log.h"

namespace kaskad {
namespace {

// World matrix without scale: rotation columns normalised. A column a zero scale collapsed (a
// camera scaled to 0 on one axis, or under such a parent) is the cross product of the other two,
// so the view stays invertible; with fewer than two left the orientation is the world's.
glm::mat4 rigid(const glm::mat4& m) {
  glm::mat4 r = m;
  int collapsed = -1, count = 0;
  for (int i = 0; i < 3; ++i) {
    const float len = glm::length(glm::vec3(m[i]));
    if (std::isfinite(len) && len > 1e-30f) {
      r[i] = glm::vec4(glm::vec3(m[i]) / len, 0.0f);
    } else {
      collapsed = i;
      ++count;
    }
  }
  if (count == 1) {
    const int a = (collapsed + 1) % 3, b = (collapsed + 2) % 3;  // x = y^z, y = z^x, z = x^y
    const glm::vec3 c = glm::cross(glm::vec3(r[a]), glm::vec3(r[b]));
    if (glm::length(c) > 1e-6f) {
      r[collapsed] = glm::vec4(glm::normalize(c), 0.0f);
      return r;
    }
  }
  if (count > 0)
    for (int i = 0; i < 3; ++i) r[i] = glm::mat4(1.0f)[i];
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

std::vector<std::string> camera_warnings(const ecs::World& world, float output_aspect,
                                         int output_height) {
  std::vector<std::string> out;
  auto name_of = [&](ecs::Entity e) {
    const Name* n = world.try_get<Name>(e);
    return n && !n->value.empty() ? "'" + n->value + "'" : "entity " + std::to_string(e.index);
  };
  std::vector<ecs::Entity> active;
  world.view<Camera>().each([&](ecs::Entity e, const Camera& c) {
    if (c.active) active.push_back(e);
  });
  if (active.size() > 1) {
    std::string names;
    for (ecs::Entity e : active) names += (names.empty() ? "" : ", ") + name_of(e);
    out.push_back(std::to_string(active.size()) + " cameras are active (" + names + "); " +
                  name_of(active.front()) + ", the first, renders");
  }
  const CameraState cam = select_camera(world, output_aspect);
  if (!cam.entity.valid()) return out;
  const Camera& c = cam.camera;
  const bool perspective = c.projection == Projection::perspective;
  // Metres a pixel spans at distance d.
  const float tan_half = std::tan(glm::radians(c.fov_y_deg) * 0.5f);
  auto pixel_at = [&](float d) {
    return (perspective ? 2.0f * tan_half * d : c.ortho_height) / float(std::max(output_height, 1));
  };
  const glm::mat4 view_proj = cam.proj * cam.view;
  float farthest = 0.0f;  // the farthest centre of what the camera sees
  float worst_jitter = 0.0f, worst_spacing = 0.0f, worst_from_origin = 0.0f;
  ecs::Entity worst = ecs::kNullEntity;
  world.view<WorldBounds>().each([&](ecs::Entity e, const WorldBounds& b) {
    if (b.box.empty() || outside_clip_volume(view_proj, b.box)) return;
    const glm::vec3 nearest = glm::clamp(cam.position, b.box.min, b.box.max);
    const float d = std::clamp(glm::distance(cam.position, nearest), c.near, c.far);
    farthest = std::max(farthest, std::min(glm::distance(cam.position, b.box.center()), c.far));
    // Float spacing at the box's point nearest the camera (or at the camera: the view's
    // translation), where the box looks largest.
    const glm::vec3 m = glm::max(glm::abs(nearest), glm::abs(cam.position));
    const float from_origin = std::max({m.x, m.y, m.z});
    const float spacing = std::nextafter(from_origin, INFINITY) - from_origin;
    const float jitter = spacing / pixel_at(d);
    if (jitter > worst_jitter) {
      worst_jitter = jitter;
      worst_spacing = spacing;
      worst_from_origin = from_origin;
      worst = e;
    }
  });
  char line[512];
  if (perspective && farthest > 0.0f) {
    const double d = farthest, n = c.near, f = c.far;
    const double step = d * d * (f - n) / (n * f * 16777216.0);
    if (step > 0.01 * d) {
      std::snprintf(line, sizeof line,
                    "camera %s: with near %g and far %g the depth buffer tells surfaces %g m from "
                    "the camera apart only when they are %.3g m apart (%.0f%% of the distance): "
                    "they will fight or vanish; raise near (or lower far)",
                    name_of(cam.entity).c_str(), n, f, d, step, 100.0 * step / d);
      out.push_back(line);
    }
  }
  if (worst_jitter > 0.5f) {
    std::snprintf(line, sizeof line,
                  "what camera %s sees lies %g m from the origin, where 32-bit float positions "
                  "are %.3g m apart: %.2g pixels at %s; its edges and shadows will jitter as "
                  "the camera moves. Move the scene nearer the origin",
                  name_of(cam.entity).c_str(), double(worst_from_origin), double(worst_spacing),
                  double(worst_jitter), name_of(worst).c_str());
    out.push_back(line);
  }
  return out;
}

void fit_planes_to_bounds(Camera& camera, const glm::vec3& position, const Aabb& bounds) {
  float far = 0.0f;
  for (int i = 0; i < 8; ++i) far = std::max(far, glm::length(bounds.corner(i) - position));
  far = std::max(far * 1.01f, 1e-3f);
  const glm::vec3 nearest = glm::clamp(position, bounds.min, bounds.max);
  camera.near = std::clamp(0.9f * glm::length(nearest - position), 1e-3f * far, 0.5f * far);
  camera.far = far;
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
    for (int i = 0; i < 8 && !depth_bounds.empty(); ++i)
      cam.far =
          std::max(cam.far, glm::dot(depth_bounds.corner(i) - t.translation, forward) * 1.01f);
  });
}

}  // namespace kaskad
