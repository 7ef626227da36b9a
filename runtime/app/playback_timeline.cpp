// The timeline: the pose of a track at any time, and events and poses applied to a loaded scene.
#include <algorithm>
#include <cmath>

#include "components/camera.h"
#include "components/name.h"
#include "components/transform.h"
#include "runtime/app/playback.h"
#include "runtime/app/playback_internal.h"
#include "runtime/assets/scene_io.h"
#include "systems/transform_system.h"

namespace kaskad {
namespace {

glm::vec3 catmull_rom(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2,
                      const glm::vec3& p3, float u) {
  // Uniform Catmull-Rom: passes through p1 at u = 0 and p2 at u = 1.
  const float u2 = u * u, u3 = u2 * u;
  return 0.5f * ((2.0f * p1) + (-p0 + p2) * u + (2.0f * p0 - 5.0f * p1 + 4.0f * p2 - p3) * u2 +
                 (-p0 + 3.0f * p1 - 3.0f * p2 + p3) * u3);
}

// The orientation a key gives, if any.
std::optional<glm::quat> key_rotation(const PoseKey& k) {
  if (k.rotation) return k.rotation;
  if (k.look_at && k.position) return look_rotation(glm::normalize(*k.look_at - *k.position));
  return std::nullopt;
}

}  // namespace

PoseKey sample_track(const Track& track, double t) {
  PoseKey out;
  out.t = t;
  const auto& k = track.keys;
  if (k.empty()) return out;
  if (track.loop && k.back().t > k.front().t && t > k.back().t)
    t = k.front().t + std::fmod(t - k.front().t, k.back().t - k.front().t);
  // The segment [i, i + 1] holding t (clamped to the ends).
  std::size_t i = 0;
  while (i + 1 < k.size() && k[i + 1].t <= t) ++i;
  const std::size_t j = std::min(i + 1, k.size() - 1);
  // Each field between the nearest keys that have it (a key may leave fields out), by the
  // fraction of the time between those two keys.
  struct Span {
    std::size_t a = 0, b = 0;
    float u = 0.0f;
    bool found = false;
  };
  auto span = [&](auto has) {
    Span sp;
    for (std::size_t n = 0; n <= i; ++n)
      if (has(k[n])) sp.a = n, sp.found = true;
    sp.b = sp.a;
    for (std::size_t n = j; n < k.size(); ++n)
      if (has(k[n])) {
        if (!sp.found) sp.a = n;
        sp.b = n;
        sp.found = true;
        break;
      }
    if (sp.b != sp.a)
      sp.u = float(std::clamp((t - k[sp.a].t) / (k[sp.b].t - k[sp.a].t), 0.0, 1.0));
    return sp;
  };
  if (const Span sp = span([](const PoseKey& p) { return bool(p.position); }); sp.found) {
    const glm::vec3 a = *k[sp.a].position, b = *k[sp.b].position;
    if (track.interpolation == Interpolation::catmull_rom && sp.a == i && sp.b == j && j != i) {
      const glm::vec3 p0 = i > 0 && k[i - 1].position ? *k[i - 1].position : a;
      const glm::vec3 p3 = j + 1 < k.size() && k[j + 1].position ? *k[j + 1].position : b;
      out.position = catmull_rom(p0, a, b, p3, sp.u);
    } else {
      out.position = glm::mix(a, b, sp.u);
    }
  }
  if (const Span sp = span([](const PoseKey& p) { return bool(key_rotation(p)); }); sp.found)
    out.rotation = glm::slerp(*key_rotation(k[sp.a]), *key_rotation(k[sp.b]), sp.u);
  if (const Span sp = span([](const PoseKey& p) { return bool(p.scale); }); sp.found)
    out.scale = glm::mix(*k[sp.a].scale, *k[sp.b].scale, sp.u);
  if (const Span sp = span([](const PoseKey& p) { return bool(p.fov_y_deg); }); sp.found)
    out.fov_y_deg = *k[sp.a].fov_y_deg + (*k[sp.b].fov_y_deg - *k[sp.a].fov_y_deg) * sp.u;
  return out;
}

namespace playback_detail {

ecs::Entity find_named(const ecs::World& w, const std::string& name) {
  ecs::Entity found = ecs::kNullEntity;
  w.view<Name>().each([&](ecs::Entity e, const Name& n) {
    if (n.value == name && !found.valid()) found = e;
  });
  return found;
}

// `start` is the entity's transform at load: relative tracks move from it along its axes.
void apply_pose(ecs::World& w, ecs::Entity e, const Track& track, const PoseKey& pose,
                const Transform& start) {
  if (!w.alive(e) || !w.has<Transform>(e)) return;  // removed by the timeline
  Transform& t = w.get<Transform>(e);
  if (pose.position && track.relative) {
    const glm::vec3 m = *pose.position;
    t.translation = start.translation + start.rotation * glm::vec3(m.x, m.y, -m.z);
  } else if (pose.position) {
    t.translation = *pose.position;
  }
  if (pose.rotation) t.rotation = *pose.rotation;
  if (pose.scale) t.scale = *pose.scale;
  if (pose.fov_y_deg && w.has<Camera>(e)) w.get<Camera>(e).fov_y_deg = *pose.fov_y_deg;
}

// One timeline event of playback file `file` on a loaded scene.
Status apply_event(Scene& scene, const SetEvent& ev, const std::filesystem::path& file) {
  if (ev.add) {
    auto e = add_entity(scene, *ev.add, ev.where + "/add", file);
    if (!e) return e.error();
    update_transforms(scene.world, scene.assets);
    return {};
  }
  if (!ev.remove.empty()) return remove_entity(scene, ev.remove);
  return apply_live_override(scene, ev.assignment);
}

}  // namespace playback_detail
}  // namespace kaskad
