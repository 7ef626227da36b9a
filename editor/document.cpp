// The editor's document: the scene, its edits (create, import, delete, duplicate, rename,
// parent, --set), the undo history of canonical documents, open, save and save as.
#include <map>
#include <string>
#include <vector>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "components/model.h"
#include "components/name.h"
#include "components/transform.h"
#include "editor/editor_app.h"
#include "runtime/assets/scene_io.h"
#include "runtime/core/file_io.h"
#include "runtime/core/log.h"
#include "systems/transform_system.h"

namespace kaskad::editor {

Editor::Editor(Options options, Scene scene, Player& player, std::vector<ScriptAction> script)
    : opt_(std::move(options)), scene_(std::move(scene)), player_(player), script_(std::move(script)) {
  history_.push_back(scene_to_json(scene_));
  // The scene's enumerations as its reader sees them, whether the file gave them or not (scenes
  // read later, created entities and edits are recorded as they are read).
  (void)parse_scene(history_.front(), opt_.scene);
  take_camera_from_scene();
  update_bounds_speed();
}

std::optional<ecs::Entity> Editor::find(const std::string& name) const {
  std::optional<ecs::Entity> found;
  scene_.world.view<Name>().each([&](ecs::Entity e, const Name& n) {
    if (n.value == name && !found) found = e;
  });
  return found;
}

Status Editor::edit(const std::string& assignment, bool merge) {
  // What the load makes on its own (the ground, a terrain's tiles) is not saved: an edit of it
  // would be lost, so it is refused. The entity as scene IO resolves the key.
  const std::string key = assignment.substr(0, assignment.find('='));
  const auto target = entity_for_key(scene_, key);
  const ecs::Entity e = target ? target.value() : ecs::kNullEntity;
  if (e.valid() && scene_.world.has<Imported>(e) && !model_of(scene_.world, e).valid())
    return Error{"--set", key,
                 "'" + scene_.world.get<Name>(e).value +
                     "' is made when the scene loads and is not saved; change "
                     "render.ground instead"};
  Status live = apply_live_override(scene_, assignment);
  if (!live) {
    // Sections a loaded entity does not take live (material, primitive, model, name) are set on
    // the canonical document and the scene remade from it: the same override and readers.
    json doc = scene_to_json(scene_);
    if (!apply_override(doc, assignment)) return live;
    KASKAD_TRY(load_document(doc));
  }
  // Near, far or auto_frame of the viewport's camera set by the user: theirs from now on.
  if (const auto cam = active_camera(); cam && scene_.world.has<Name>(*cam)) {
    const std::string prefix = scene_.world.get<Name>(*cam).value + ".camera.";
    for (const char* field : {"near", "far", "auto_frame"})
      if (key == prefix + field) planes_follow_ = false;
  }
  record(merge);
  return {};
}

void Editor::record(bool merge) {
  update_transforms(scene_.world, scene_.assets);
  doc_stale_ = true;
  changed_since_frame_ = true;
  update_bounds_speed();  // what the fly speed and a placed camera's planes span
  json snapshot = scene_to_json(scene_);
  if (snapshot == history_[position_]) return;  // an edit that changed nothing is no undo step
  if (merge && position_ + 1 == history_.size() && position_ != saved_ && position_ > 0) {
    history_[position_] = std::move(snapshot);
  } else {
    history_.resize(position_ + 1);
    if (saved_ != std::string::npos && saved_ > position_) saved_ = std::string::npos;
    history_.push_back(std::move(snapshot));
    ++position_;
  }
}

std::string Editor::unused_name(const std::string& stem) const {
  for (int i = 1;; ++i) {
    const std::string name = stem + "_" + std::to_string(i);
    if (!find(name)) return name;
  }
}

Status Editor::create(const std::string& shape) {
  // In front of the camera, a tenth of the scene's size away (speed_ is a fifth of it per second).
  const glm::vec3 at = camera_.position + camera_.forward() * std::max(0.5f * speed_, 0.5f);
  const std::string name = unused_name(shape);
  json block = {{"name", name},
                {"transform", {{"translation", {at.x, at.y, at.z}}}},
                {"primitive", {{"shape", shape}}}};
  auto e = add_entity(scene_, block, "/create");
  if (!e) return e.error();
  selected_ = name;
  record(false);
  return {};
}

Status Editor::import_model(const std::string& path) {
  // A glTF model entity in front of the camera, like create(); its meshes are imported under it.
  // The path as given (absolute, or relative to the working folder) is saved relative to the
  // scene file, as scene files hold it.
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path file = fs::absolute(path, ec);
  if (!fs::is_regular_file(file, ec)) return Error{path, "", "import: no such model file"};
  if (const std::string ext = lowercase_extension(file); ext != ".gltf" && ext != ".glb")
    return Error{path, "", "import: a model is a .gltf or .glb file"};
  const fs::path base = fs::absolute(scene_.file.parent_path(), ec);
  const fs::path relative = file.lexically_normal().lexically_relative(base.lexically_normal());
  const glm::vec3 at = camera_.position + camera_.forward() * std::max(0.5f * speed_, 0.5f);
  const std::string name = unused_name(file.stem().string());
  json block = {{"name", name},
                {"transform", {{"translation", {at.x, at.y, at.z}}}},
                {"model", {{"path", relative.empty() ? file.generic_string() : relative.generic_string()}}}};
  auto e = add_entity(scene_, block, "/import");
  if (!e) return e.error();
  selected_ = name;
  record(false);
  return {};
}

Status Editor::remove_selected() {
  if (selected_.empty()) return Error{"", "", "delete: select an entity first"};
  KASKAD_TRY(remove_entity(scene_, selected_));
  selected_.clear();
  record(false);
  return {};
}

Status Editor::duplicate_selected() {
  if (selected_.empty()) return Error{"", "", "duplicate: select an entity first"};
  const json& doc = document();
  for (const json& ent : doc.at("entities")) {
    if (ent.value("name", std::string()) != selected_) continue;
    json block = ent;
    block["name"] = unused_name(selected_);
    auto e = add_entity(scene_, block, "/duplicate");
    if (!e) return e.error();
    selected_ = block["name"].get<std::string>();
    record(false);
    return {};
  }
  return Error{"", "", "duplicate: '" + selected_ + "' is imported from a model; duplicate the model's entity"};
}

Status Editor::reparent_selected(const std::string& parent) {
  if (selected_.empty()) return Error{"", "", "parent: select an entity first"};
  json doc = scene_to_json(scene_);
  std::map<std::string, std::string> parent_of;
  json* child = nullptr;
  for (json& ent : doc.at("entities")) {
    const std::string name = ent.value("name", std::string());
    if (ent.contains("transform")) parent_of[name] = ent["transform"].value("parent", std::string());
    if (name == selected_) child = &ent;
  }
  if (!child) return Error{"", "", "parent: '" + selected_ + "' is imported from a model"};
  // Up from the new parent: reaching the child would make a cycle (the transform system would
  // then treat both as roots).
  for (std::string p = parent; !p.empty(); p = parent_of.count(p) ? parent_of[p] : "")
    if (p == selected_)
      return Error{"", "", "parent: '" + parent + "' is '" + selected_ + "' or below it"};
  if (parent.empty()) (*child)["transform"].erase("parent");
  else (*child)["transform"]["parent"] = parent;
  KASKAD_TRY(load_document(doc));
  record(false);
  return {};
}

Status Editor::rename_selected(const std::string& name) {
  if (selected_.empty()) return Error{"", "", "rename: select an entity first"};
  // The name and every parent reference to it, on the document; the readers then check it (unique,
  // not empty) as in a scene file.
  json doc = scene_to_json(scene_);
  bool found = false;
  for (json& ent : doc.at("entities")) {
    if (ent.value("name", std::string()) == selected_) {
      ent["name"] = name;
      found = true;
    }
    if (ent.contains("transform") && ent["transform"].value("parent", std::string()) == selected_)
      ent["transform"]["parent"] = name;
  }
  if (!found) return Error{"", "", "rename: '" + selected_ + "' is imported from a model"};
  KASKAD_TRY(load_document(doc));
  selected_ = name;
  record(false);
  return {};
}

Status Editor::load_document(const json& doc) {
  auto scene = load_scene_document(doc, opt_.scene);
  if (!scene) return scene.error();
  const auto frame = scene_.frames_rendered;
  scene_ = std::move(scene.value());
  scene_.frames_rendered = frame;  // frame indices carry on (probes' every_n)
  prewarm_ = true;
  return {};
}

Status Editor::restore(std::size_t index) {
  KASKAD_TRY(load_document(history_[index]));
  position_ = index;
  update_bounds_speed();
  doc_stale_ = true;
  changed_since_frame_ = true;
  if (camera_.moved) {
    place_camera();
    update_transforms(scene_.world, scene_.assets);
  } else {
    take_camera_from_scene();
  }
  return {};
}

Status Editor::open(const fs::path& file) {
  if (dirty())
    return Error{"", "", "open: " + opt_.scene.string() + " has unsaved changes (save first, or undo them)"};
  auto scene = load_scene(file);
  if (!scene) return scene.error();
  scene_ = std::move(scene.value());
  opt_.scene = file;
  history_.assign(1, scene_to_json(scene_));
  position_ = saved_ = 0;
  selected_.clear();
  prewarm_ = true;
  doc_stale_ = true;
  changed_since_frame_ = true;
  camera_ = FlyCamera{};
  planes_follow_ = false;
  take_camera_from_scene();
  update_bounds_speed();
  glfwSetWindowTitle(player_.context->window(), ("Kaskad editor - " + file.string()).c_str());
  message_ = "opened " + file.string();
  message_is_error_ = false;
  return {};
}

Status Editor::save_as(const fs::path& file) {
  KASKAD_TRY(save(file));
  // From now on the scene is that file: Ctrl+S writes it and it is what "unsaved" refers to.
  // The undo history's paths (models, material files, maps) are relative to the scene's file:
  // each document is rewritten relative to the new one, and the scene loaded from its own, before
  // anything changes (a failure leaves the editor as it was; the copy is written).
  std::vector<json> rebased;
  for (const json& doc : history_) {
    auto parsed = parse_scene(doc, scene_.file);
    if (!parsed) return parsed.error();
    rebased.push_back(scene_to_json(*parsed, folder_of(file)));
  }
  // The scene as it is now (the camera where the user put it, with its planes), as just saved.
  rebased[position_] = scene_to_json(scene_, folder_of(file));
  auto scene = load_scene_document(rebased[position_], file);
  if (!scene) return scene.error();
  const auto frame = scene_.frames_rendered;
  history_ = std::move(rebased);
  opt_.scene = file;
  scene_ = std::move(scene.value());
  scene_.frames_rendered = frame;  // frame indices carry on (probes' every_n)
  log::set_context(file.string());
  prewarm_ = true;
  doc_stale_ = true;
  changed_since_frame_ = true;
  saved_ = position_;
  glfwSetWindowTitle(player_.context->window(), ("Kaskad editor - " + file.string()).c_str());
  return {};
}

Status Editor::undo() {
  if (position_ == 0) return Error{"", "", "nothing to undo"};
  return restore(position_ - 1);
}

Status Editor::redo() {
  if (position_ + 1 >= history_.size()) return Error{"", "", "nothing to redo"};
  return restore(position_ + 1);
}

Status Editor::save(const fs::path& file) {
  if (lowercase_extension(file) != ".json")
    return Error{file.string(), "", "scenes are saved as .json (a glTF file is never overwritten)"};
  KASKAD_TRY(save_scene(file, scene_));
  // Another path is a copy: the scene's own file is still the one with unsaved changes.
  std::error_code ec;
  if (fs::weakly_canonical(file, ec) == fs::weakly_canonical(opt_.scene, ec)) saved_ = position_;
  message_ = "saved " + file.string();
  message_is_error_ = false;
  std::printf("kaskad edit: wrote %s\n", file.string().c_str());
  return {};
}

}  // namespace kaskad::editor
