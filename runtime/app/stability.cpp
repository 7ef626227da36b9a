#include "runtime/app/stability.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "components/transform.h"
#include "systems/transform_system.h"

namespace kaskad {

void keep_points_within(StabilityPoints& points, const Aabb& box) {
  StabilityPoints kept;
  for (std::size_t i = 0; i < points.positions.size(); ++i) {
    const glm::vec3 p = points.positions[i];
    if (glm::any(glm::lessThan(p, box.min)) || glm::any(glm::greaterThan(p, box.max))) continue;
    kept.positions.push_back(p);
    kept.normals.push_back(points.normals[i]);
    kept.pixels.push_back(points.pixels[i]);
  }
  points = std::move(kept);
}

Result<StabilityPoints> stability_points(const Image& aov, int max_points) {
  auto channel = [&](const char* name) {
    const auto it = std::find(aov.channel_names.begin(), aov.channel_names.end(), name);
    return it == aov.channel_names.end() ? -1 : int(it - aov.channel_names.begin());
  };
  const int px = channel("P.X"), nx = channel("N.X"), mask = channel("mask");
  if (px < 0 || nx < 0 || mask < 0)
    return Error{"", "AOV image", "needs channels P.X P.Y P.Z N.X N.Y N.Z mask"};
  StabilityPoints out;
  if (max_points <= 0 || aov.width <= 0 || aov.height <= 0) return out;
  // Count the geometry pixels first, then pick a stride that keeps at most max_points.
  auto at = [&](int x, int y, int c) { return aov.at(x, y, c); };
  auto usable = [&](int x, int y, glm::vec3& p, glm::vec3& n) {
    if (at(x, y, mask) < 0.5f) return false;
    p = {at(x, y, px), at(x, y, px + 1), at(x, y, px + 2)};
    n = {at(x, y, nx), at(x, y, nx + 1), at(x, y, nx + 2)};
    const float len = glm::length(n);
    if (!std::isfinite(p.x + p.y + p.z) || !std::isfinite(len) || len < 0.5f) return false;
    n /= len;
    return true;
  };
  std::size_t geometry = 0;
  glm::vec3 p, n;
  for (int y = 0; y < aov.height; ++y)
    for (int x = 0; x < aov.width; ++x) geometry += usable(x, y, p, n) ? 1 : 0;
  const int stride = std::max(1, int(std::ceil(std::sqrt(double(geometry) / max_points))));
  for (int y = stride / 2; y < aov.height; y += stride)
    for (int x = stride / 2; x < aov.width; x += stride)
      if (usable(x, y, p, n) && int(out.positions.size()) < max_points) {
        out.positions.push_back(p);
        out.normals.push_back(n);
        out.pixels.emplace_back(x, y);
      }
  return out;
}

Result<std::vector<float>> visibility_at_seen_points(render::Renderer& renderer,
                                                     const CameraState& camera,
                                                     const StabilityPoints& points) {
  auto values = renderer.shadow_at_points(points.positions, points.normals);
  if (!values) return values.error();
  // Only points the camera sees count: one that a path has carried out of the view is outside
  // every cascade's fitted volume, and what its lookup returns there is nobody's picture (NaN:
  // shadow_stability() skips non-finite samples).
  const glm::mat4 view_proj = camera.proj * camera.view;
  std::vector<float> v(values->size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    const glm::vec4 c = view_proj * glm::vec4(points.positions[i], 1.0f);
    const bool seen = std::abs(c.x) <= c.w && std::abs(c.y) <= c.w && std::abs(c.z) <= c.w;
    v[i] = seen ? (*values)[i].x : std::numeric_limits<float>::quiet_NaN();
  }
  return v;
}

Result<StabilityRun> measure_stability(Player& player, Scene& scene, const StabilityPoints& points,
                                       const CameraPath& path) {
  FrameContext ctx;
  ctx.width = scene.render.width;
  ctx.height = scene.render.height;
  ctx.write_aovs = false;
  const CameraState camera = select_camera(scene.world, float(ctx.width) / float(ctx.height));
  if (!camera.entity.valid() || !scene.world.has<Transform>(camera.entity))
    return Error{"", "stability", "the scene has no camera to move"};
  Transform& transform = scene.world.get<Transform>(camera.entity);
  if (transform.parent.valid())
    return Error{"", "stability", "the camera has a parent; the path moves root cameras only"};
  const Transform original = transform;

  StabilityRun run;
  const Aabb bounds = scene_bounds(scene.world);
  run.step = path.step > 0.0f ? path.step
                              : 0.0007f * (bounds.empty() ? 1.0f : glm::length(bounds.extent()));
  // The camera's own axes in world space (view matrix rows), fixed for the whole path.
  const glm::mat4 world_from_view = glm::inverse(camera.view);
  const glm::vec3 right = glm::normalize(glm::vec3(world_from_view[0]));
  const glm::vec3 up = glm::normalize(glm::vec3(world_from_view[1]));
  const glm::vec3 direction = right + 0.5f * up;

  SystemState systems;  // the path's own: frames from 0
  FrameReport report;
  Status status;
  for (int f = 0; f < std::max(1, path.frames); ++f) {
    transform.translation = original.translation + float(f) * run.step * direction;
    ctx.index = std::uint64_t(f);
    status = run_frame(scene, *player.renderer, ctx, systems, report);
    if (!status) break;
    auto v = visibility_at_seen_points(*player.renderer, report.camera, points);
    if (!v) {
      status = v.error();
      break;
    }
    run.visibility.push_back(std::move(v.value()));
  }
  scene.world.get<Transform>(camera.entity) = original;
  update_transforms(scene.world, scene.assets);
  if (!status) return status.error();
  run.stats = reference::shadow_stability(run.visibility);
  return run;
}

}  // namespace kaskad
