// The camera controller: the viewport's camera (the scene's active one) follows the fly camera;
// keys fly it, F frames the selection, orbit turns about it.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "components/camera.h"
#include "components/name.h"
#include "components/transform.h"
#include "editor/editor_app.h"
#include "runtime/assets/scene_io.h"
#include "systems/camera_system.h"
#include "systems/transform_system.h"

namespace kaskad::editor {

std::optional<ecs::Entity> Editor::active_camera() const {
  // As the camera system picks it: the first active camera, else the first camera.
  std::optional<ecs::Entity> first, active;
  std::vector<ecs::Entity> cams;
  scene_.world.view<Camera>().each([&](ecs::Entity e, const Camera&) { cams.push_back(e); });
  std::sort(cams.begin(), cams.end(), [](ecs::Entity a, ecs::Entity b) { return a.index < b.index; });
  for (ecs::Entity e : cams) {
    if (!first) first = e;
    if (!active && scene_.world.get<Camera>(e).active) active = e;
  }
  return active ? active : first;
}

void Editor::take_camera_from_scene() {
  const auto cam = active_camera();
  if (!cam) return;
  const auto* wt = scene_.world.try_get<WorldTransform>(*cam);
  if (!wt) return;
  camera_.position = glm::vec3(wt->matrix[3]);
  camera_.look_along(-glm::vec3(wt->matrix[2]));
}

void Editor::place_camera() {
  const auto cam = active_camera();
  if (!cam) return;
  Transform& t = scene_.world.get<Transform>(*cam);
  t.translation = camera_.position;
  t.rotation = look_rotation(camera_.forward());
  // A camera under a parent (a glTF model's camera) gets the pose in its parent's space.
  if (const auto* parent =
          t.parent.valid() ? scene_.world.try_get<WorldTransform>(t.parent) : nullptr) {
    const Transform local =
        decompose(glm::inverse(parent->matrix) * glm::translate(glm::mat4(1.0f), camera_.position) *
                  glm::mat4_cast(t.rotation));
    t.translation = local.translation;
    t.rotation = local.rotation;
    t.scale = local.scale;
  }
  // A glTF model's camera: the pose is kept in the model's nodes block when saved.
  note_node_override(scene_, *cam, "transform", {"translation", "rotation", "scale"});
  doc_stale_ = true;
  changed_since_frame_ = true;
}

void Editor::write_camera() {
  place_camera();
  const auto cam = active_camera();
  if (!cam) return;
  camera_.moved = true;
  // An auto_frame camera moved by the user is placed where they put it: saved and reloaded
  // there, not framed again. Its near and far planes had been fitted to the scene from where the
  // load put it; they follow the camera (until near, far or auto_frame is edited), so that
  // flying in (or F) does not clip what is close.
  Camera& c = scene_.world.get<Camera>(*cam);
  if (c.auto_frame) {
    c.auto_frame = false;
    planes_follow_ = true;
  }
  if (planes_follow_ && !bounds_.empty()) fit_planes_to_bounds(c, camera_.position, bounds_);
}

void Editor::update_bounds_speed() {
  const Aabb b = scene_bounds(scene_.world);
  bounds_ = b;
  // About five seconds to cross the scene, whatever its units.
  const float size = b.empty() ? 10.0f : glm::length(b.max - b.min);
  speed_ = std::max(size / 5.0f, 0.01f);
}

Status Editor::press(const std::string& key, float seconds) {
  if (key == "f") return frame_selection();
  if (key == "h") {
    panels_hidden_ = !panels_hidden_;
    changed_since_frame_ = true;  // the viewport changes size
    return {};
  }
  if (key == "ctrl+z") return undo();
  if (key == "ctrl+y") return redo();
  if (key == "ctrl+s") return save(opt_.scene);
  const glm::vec3 fwd = camera_.forward();
  const glm::vec3 right = glm::normalize(glm::cross(fwd, glm::vec3(0, 1, 0)));
  glm::vec3 move{0.0f};
  if (key == "w") move = fwd;
  if (key == "s") move = -fwd;
  if (key == "d") move = right;
  if (key == "a") move = -right;
  if (key == "e") move = glm::vec3(0, 1, 0);
  if (key == "q") move = glm::vec3(0, -1, 0);
  camera_.position += move * speed_ * seconds;
  write_camera();
  return {};
}

Status Editor::orbit(float yaw, float pitch) {
  const auto e = find(selected_);
  if (!e) return Error{"", "", "orbit: select an entity first (the camera turns about it)"};
  glm::vec3 centre{0.0f};
  if (const auto* b = scene_.world.try_get<WorldBounds>(*e); b && !b->box.empty())
    centre = 0.5f * (b->box.min + b->box.max);
  else if (const auto* wt = scene_.world.try_get<WorldTransform>(*e))
    centre = glm::vec3(wt->matrix[3]);
  // The camera keeps its distance to the centre and looks at it from the turned heading.
  const float distance = std::max(glm::length(camera_.position - centre), 0.01f);
  camera_.look_along(centre - camera_.position);
  camera_.yaw += yaw;
  camera_.pitch = std::clamp(camera_.pitch + pitch, -1.55f, 1.55f);
  camera_.position = centre - camera_.forward() * distance;
  write_camera();
  return {};
}

Status Editor::frame_selection() {
  const auto e = find(selected_);
  if (!e) return Error{"", "", "F frames the selection: select an entity first"};
  // The entity and everything below it: a model's entity, or a glTF node, has no mesh of its own.
  std::map<std::uint32_t, std::vector<ecs::Entity>> children;  // by parent index, one pass
  scene_.world.view<Transform>().each([&](ecs::Entity x, const Transform& t) {
    if (t.parent.valid()) children[t.parent.index].push_back(x);
  });
  Aabb box;
  std::vector<ecs::Entity> subtree{*e};
  for (std::size_t i = 0; i < subtree.size(); ++i) {
    if (const auto* b = scene_.world.try_get<WorldBounds>(subtree[i]); b && !b->box.empty()) {
      box.expand(b->box.min);
      box.expand(b->box.max);
    }
    if (const auto it = children.find(subtree[i].index); it != children.end())
      for (ecs::Entity c : it->second)
        if (scene_.world.get<Transform>(c).parent == subtree[i]) subtree.push_back(c);
  }
  if (box.empty()) {
    const auto* wt = scene_.world.try_get<WorldTransform>(*e);
    const glm::vec3 p = wt ? glm::vec3(wt->matrix[3]) : glm::vec3(0.0f);
    box.expand(p - glm::vec3(0.5f));
    box.expand(p + glm::vec3(0.5f));
  }
  const glm::vec3 centre = 0.5f * (box.min + box.max);
  const float radius = std::max(0.5f * glm::length(box.max - box.min), 0.01f);
  float fov = glm::radians(45.0f);
  if (const auto cam = active_camera()) fov = glm::radians(scene_.world.get<Camera>(*cam).fov_y_deg);
  // The bounding sphere fills the vertical field of view, with a margin.
  const float distance = 1.2f * radius / std::sin(0.5f * fov);
  camera_.position = centre - camera_.forward() * distance;
  write_camera();
  // F asked to see the selection: a camera whose own near and far planes leave it out (a small
  // part of a model scaled up, seen from its framing distance) takes planes around it, and says so.
  if (const auto cam = active_camera(); cam && !planes_follow_) {
    Camera& c = scene_.world.get<Camera>(*cam);
    // The camera system scales near and far by the camera's uniform world scale.
    const auto* wt = scene_.world.try_get<WorldTransform>(*cam);
    const float s = wt ? camera_world_scale(wt->matrix) : 1.0f;
    const float far = std::max(c.far * s, (distance + radius) * 1.05f);
    const float near = std::min(c.near * s, std::max((distance - radius) * 0.9f, far * 1e-4f));
    if (near != c.near * s || far != c.far * s) {
      c.near = near / s;
      c.far = far / s;
      message_ = "F: the camera's near and far are now " + json(json_reader::num(c.near)).dump() +
                 " and " + json(json_reader::num(c.far)).dump() +
                 ", so that they hold the selection";
      message_is_error_ = false;
      std::printf("kaskad edit: %s\n", message_.c_str());
      record(false);  // a change of the camera's settings: an undo step, and unsaved
    }
  }
  return {};
}

}  // namespace kaskad::editor
