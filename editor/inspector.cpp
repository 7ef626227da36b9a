// The inspector panel: the frame's stats, the view, the file line and --set line, and the
// selection's and the scene's fields as widgets whose names and limits are the readers' own.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "components/animation.h"
#include "components/camera.h"
#include "components/light.h"
#include "components/model.h"
#include "components/name.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "editor/editor_app.h"
#include "runtime/assets/scene_io.h"

namespace kaskad::editor {

namespace {

// A float drag's change per pixel: 1% of the value's magnitude, at least 0.001, and within a
// range of at most 1000 at least 1/500 of it (a 0..1 field crosses in 500 pixels).
float drag_speed(float magnitude, const json_reader::FieldRecorder::Range* range) {
  float speed = std::max(magnitude * 0.01f, 0.001f);
  if (range && range->hi - range->lo <= 1000.0)
    speed = std::max(speed, float(range->hi - range->lo) * 0.002f);
  return speed;
}

// What the readers recorded (`recorded`, by field path) for the inspector field KEY, found by its
// object and field (FieldRecorder::object_and_field()) in `by_pair`, which takes in the records
// made since the last call (`from` of them were taken in before).
template <class T>
const T* recorded_for(const std::string& key, const std::map<std::string, T>& recorded,
                      std::map<std::string, T>& by_pair, std::size_t& from) {
  using json_reader::FieldRecorder;
  if (from != recorded.size()) {
    for (const auto& [path, value] : recorded)
      by_pair[FieldRecorder::object_and_field(path, '/')] = value;
    from = recorded.size();
  }
  const auto it = by_pair.find(FieldRecorder::object_and_field(key, '.'));
  return it == by_pair.end() ? nullptr : &it->second;
}

}  // namespace

void Editor::request(const std::string& assignment) {
  // A drag edits one history entry while the mouse is held, not one per frame.
  const std::string key = assignment.substr(0, assignment.find('='));
  const bool merge = key == last_drag_key_;
  last_drag_key_ = ImGui::IsItemActive() ? key : "";
  requests_.emplace_back(assignment, merge);
}

const std::vector<std::string>* Editor::choices(const std::string& key) {
  return recorded_for(key, recorded_.enumerations(), choices_, choices_from_);
}

const json_reader::FieldRecorder::Range* Editor::limits(const std::string& key) {
  return recorded_for(key, recorded_.ranges(), limits_, limits_from_);
}

void Editor::number_edit(const std::string& key, bool changed, const std::string& assignment) {
  // While typing, the widget hands over each keystroke's number ("9" on the way to "90"): only
  // the last one, when the typing ends, is an edit.
  if (ImGui::IsItemActive() && ImGui::GetIO().WantTextInput) {
    if (changed) typed_ = {key, assignment};
    return;
  }
  // Enter or a click elsewhere ends the typing with its number; Escape with the old one.
  const bool escaped = ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape), false);
  if (changed) {
    request(assignment);
  } else if (ImGui::IsItemDeactivated() && typed_.first == key && !escaped) {
    request(typed_.second);
  }
  if (changed || ImGui::IsItemDeactivated()) typed_ = {};
  // A drag ends with the mouse released: the next drag of the field is another undo step.
  if (ImGui::IsItemDeactivated() && last_drag_key_ == key) last_drag_key_.clear();
}

Status Editor::choose(const std::string& key, const std::string& name) {
  const std::vector<std::string>* names = choices(key);
  if (!names) return Error{"", "", "'" + key + "' is not an enumerated field"};
  if (std::find(names->begin(), names->end(), name) == names->end())
    return Error{"", "", "'" + name + "' is not one of " + key + "'s choices (" +
                             json_reader::join(*names) + ")"};
  return edit(key + "=" + json(name).dump(), false);
}

void Editor::field(const std::string& key, const std::string& label, const json& v) {
  ImGui::PushID(key.c_str());
  const std::vector<std::string>* names = v.is_string() ? choices(key) : nullptr;
  if (v.is_boolean()) {
    bool b = v.get<bool>();
    if (ImGui::Checkbox(label.c_str(), &b)) request(key + "=" + (b ? "true" : "false"));
    name_item(key);
  } else if (v.is_number()) {
    // Drag fields within the readers' own limits (one source of truth): a drag stops at them; a
    // typed value outside them is refused with the readers' message.
    const auto* range = limits(key);
    if (range && range->power_of_two) {
      // A map size: the powers of two in its bounds (a value outside them shown as it is).
      const int current = v.get<int>();
      const bool open = ImGui::BeginCombo(label.c_str(), std::to_string(current).c_str());
      name_item(key);
      if (open) {
        for (double p = range->lo; p <= range->hi; p *= 2.0) {
          const std::string item = std::to_string(int(p));
          if (ImGui::Selectable(item.c_str(), int(p) == current) && int(p) != current)
            request(key + "=" + item);
          name_item(key + "=" + item);
        }
        ImGui::EndCombo();
      }
    } else if (v.is_number_integer() || v.is_number_unsigned()) {
      int i = v.get<int>();
      // An int drag computes max - min: only limits that cannot overflow it.
      const bool bounded = range && range->lo > -1e9 && range->hi < 1e9;
      const bool changed = ImGui::DragInt(label.c_str(), &i, 1.0f, bounded ? int(range->lo) : 0,
                                          bounded ? int(range->hi) : 0);
      name_item(key);
      number_edit(key, changed, key + "=" + std::to_string(i));
    } else {
      float f = v.get<float>();
      const bool changed = ImGui::DragFloat(label.c_str(), &f, drag_speed(std::abs(f), range),
                                            range ? float(range->lo) : 0.0f,
                                            range ? float(range->hi) : 0.0f, "%.5g");
      name_item(key);
      number_edit(key, changed, key + "=" + json(double(f)).dump());
    }
    if (range && ImGui::IsItemHovered())
      ImGui::SetTooltip("%s: [%g, %g]", key.c_str(), range->lo, range->hi);
  } else if (names) {
    // The reader's names; a value outside them (none is read, but a file may be edited while
    // open) is shown as it is. A choice is the same KEY=VALUE edit as a typed one.
    const std::string current = v.get<std::string>();
    const bool open = ImGui::BeginCombo(label.c_str(), current.c_str());
    name_item(key);
    if (open) {
      for (const std::string& n : *names) {
        const bool is_current = n == current;
        if (ImGui::Selectable(n.c_str(), is_current) && !is_current)
          operations_.push_back([this, key, n] { return choose(key, n); });
        name_item(key + "=" + n);
        if (is_current) ImGui::SetItemDefaultFocus();
      }
      ImGui::EndCombo();
    }
  } else if (v.is_string()) {
    char buf[512];
    std::snprintf(buf, sizeof buf, "%s", v.get<std::string>().c_str());
    // A click selects the whole value: what is typed replaces it.
    if (ImGui::InputText(
            label.c_str(), buf, sizeof buf,
            ImGuiInputTextFlags_EnterReturnsTrue | ImGuiInputTextFlags_AutoSelectAll)) {
      // A word is the string; a JSON array or object typed over a word such as a reflector's
      // "auto" centre or "none" box is that value ([0, 1, 0]).
      const json typed = json::parse(buf, nullptr, /*allow_exceptions=*/false);
      const bool structured = typed.is_array() || typed.is_object();
      request(key + "=" + (structured ? std::string(buf) : json(std::string(buf)).dump()));
    }
    name_item(key);
  } else if (v.is_array() && v.size() >= 2 && v.size() <= 4 &&
             std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); })) {
    float f[4] = {};
    for (std::size_t i = 0; i < v.size(); ++i) f[i] = v[i].get<float>();
    float largest = 0.0f;
    for (float x : f) largest = std::max(largest, std::abs(x));
    const auto* range = limits(key);
    const float lo = range ? float(range->lo) : 0.0f, hi = range ? float(range->hi) : 0.0f;
    const bool changed = ImGui::DragScalarN(label.c_str(), ImGuiDataType_Float, f, int(v.size()),
                                            drag_speed(largest, range), range ? &lo : nullptr,
                                            range ? &hi : nullptr, "%.4g");
    name_item(key);
    json a = json::array();
    for (std::size_t i = 0; i < v.size(); ++i) a.push_back(double(f[i]));
    number_edit(key, changed, key + "=" + a.dump());
    if (range && ImGui::IsItemHovered())
      ImGui::SetTooltip("%s: each in [%g, %g]", key.c_str(), range->lo, range->hi);
  } else if (v.is_object() || v.is_array()) {
    if (ImGui::TreeNode(label.c_str())) {
      if (v.is_object())
        for (auto it = v.begin(); it != v.end(); ++it) field(key + "." + it.key(), it.key(), it.value());
      else
        for (std::size_t i = 0; i < v.size(); ++i) field(key + "." + std::to_string(i), std::to_string(i), v[i]);
      ImGui::TreePop();
    }
  } else {
    ImGui::TextDisabled("%s: %s", label.c_str(), v.dump().c_str());
  }
  ImGui::PopID();
}

void Editor::direction_helpers() {
  // Lights and cameras are aimed: their direction and a look-at point, set through the scene
  // files' own rotation forms (transform.direction, transform.look_at).
  const auto e = find(selected_);
  if (!e || !(scene_.world.has<Light>(*e) || scene_.world.has<Camera>(*e))) return;
  const auto* wt = scene_.world.try_get<WorldTransform>(*e);
  if (!wt) return;
  const bool aim_open = ImGui::CollapsingHeader("aim", ImGuiTreeNodeFlags_DefaultOpen);
  name_item(selected_ + ".aim");
  if (!aim_open) return;
  glm::vec3 d = glm::normalize(-glm::vec3(wt->matrix[2]));
  const bool turned = ImGui::DragFloat3("direction", &d.x, 0.01f, -1.0f, 1.0f, "%.3f");
  name_item(selected_ + ".aim.direction");
  if (turned && glm::length(d) > 1e-4f)
    request(selected_ + ".transform.direction=" +
            json::array({double(d.x), double(d.y), double(d.z)}).dump());
  ImGui::DragFloat3("look-at point", &look_at_.x, 0.05f, 0.0f, 0.0f, "%.3g");
  name_item(selected_ + ".aim.look-at point");
  if (button("look at it"))
    requests_.emplace_back(selected_ + ".transform.look_at=" +
                               json::array({double(look_at_.x), double(look_at_.y), double(look_at_.z)}).dump(),
                           false);
}

void Editor::inspector() {
  ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled));
  ImGui::TextUnformatted(stats_.c_str());
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", stats_.c_str());
  ImGui::PopStyleColor();
  if (!frame_ms_.empty())
    ImGui::PlotLines("frame ms", frame_ms_.data(), int(frame_ms_.size()), 0, nullptr, 0.0f,
                     FLT_MAX, ImVec2(0, 40));
  int view = int(view_);
  if (ImGui::Combo("view", &view, kViewNames, int(std::size(kViewNames)))) {
    view_ = View(view);
    changed_since_frame_ = true;
  }
  name_item("view");
  if (!message_.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, message_is_error_ ? ImVec4(1.0f, 0.45f, 0.35f, 1.0f)
                                                           : ImVec4(0.55f, 0.85f, 0.55f, 1.0f));
    ImGui::TextWrapped("%s", message_.c_str());
    ImGui::PopStyleColor();
  }
  ImGui::TextDisabled("%s%s", opt_.scene.filename().string().c_str(), dirty() ? " (unsaved)" : "");
  {
    char path[1024];
    std::snprintf(path, sizeof path, "%s", file_line_.c_str());
    ImGui::InputText("file", path, sizeof path);
    name_item("file");
    file_line_ = path;
    // The typed path at once; the dialog with the "..." buttons.
    if (button("open") && !file_line_.empty()) {
      const fs::path f = file_line_;
      operations_.push_back([this, f] { return open(f); });
    }
    ImGui::SameLine();
    if (button("save as") && !file_line_.empty()) {
      const fs::path f = file_line_;
      operations_.push_back([this, f] { return save_as(f); });
    }
    if (button("open...")) show_file_dialog(FileDialog::Purpose::open, file_line_);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Ctrl+O");
    ImGui::SameLine();
    if (button("save as...")) show_file_dialog(FileDialog::Purpose::save_as, file_line_);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Ctrl+Shift+S");
  }
  char buf[512];
  std::snprintf(buf, sizeof buf, "%s", set_line_.c_str());
  const bool set_entered =
      ImGui::InputText("--set", buf, sizeof buf, ImGuiInputTextFlags_EnterReturnsTrue);
  name_item("--set");
  set_line_ = buf;
  if (set_entered) requests_.emplace_back(set_line_, false);
  const json& doc = document();
  if (!selected_.empty()) {
    const json* ent = nullptr;
    for (const json& e : doc.at("entities"))
      if (e.value("name", std::string()) == selected_) ent = &e;
    if (ent) {
      ImGui::Separator();
      char name[256];
      std::snprintf(name, sizeof name, "%s", selected_.c_str());
      const bool renamed =
          ImGui::InputText("name", name, sizeof name, ImGuiInputTextFlags_EnterReturnsTrue);
      name_item("name");
      if (renamed) {
        const std::string n = name;
        operations_.push_back([this, n] { return rename_selected(n); });
      }
      if (button("duplicate")) operations_.push_back([this] { return duplicate_selected(); });
      ImGui::SameLine();
      if (button("delete")) operations_.push_back([this] { return remove_selected(); });
      if (ent->contains("transform") && ent->at("transform").contains("parent")) {
        ImGui::SameLine();
        if (button("make root")) operations_.push_back([this] { return reparent_selected(""); });
      }
      ImGui::TextDisabled("drag an entity onto another to parent it");
      if (const auto e = find(selected_); e && scene_.world.has<Camera>(*e))
        ImGui::TextDisabled(
            active_camera() == e
                ? "the viewport's camera"
                : "not the viewport's camera (the first active one, else the first, is)");
      // A light's shadow settings with every field (the file holds those that differ from the
      // scene's shadow block).
      json sections = *ent;
      if (const auto e = find(selected_); e && scene_.world.has<ShadowSettings>(*e))
        sections["shadow"] = live_entity_sections(scene_, *e)["shadow"];
      // A model's clips as they play now (time moves on while a clip plays): the timeline.
      if (const auto e = find(selected_); e && scene_.world.has<Animator>(*e))
        sections["animation"] = live_entity_sections(scene_, *e)["animation"];
      for (auto it = sections.begin(); it != sections.end(); ++it)
        if (it.key() != "name" && it.value().is_object())
          section(selected_ + "." + it.key(), it.key(), it.value(), true);
      direction_helpers();
    } else if (const auto e = find(selected_)) {
      // A glTF model's node: the sections a loaded entity takes, saved in its model's nodes
      // block. The ground and terrain tiles are remade at load: shown, not edited.
      ImGui::Separator();
      const ecs::Entity source = model_of(scene_.world, *e);
      const auto* model = source.valid() ? scene_.world.try_get<Name>(source) : nullptr;
      if (!model) {
        ImGui::TextWrapped(
            "'%s' is made when the scene loads (render.ground, a terrain's tiles) "
            "and is not saved: it cannot be edited",
            selected_.c_str());
      } else {
        ImGui::TextWrapped(
            "'%s' is a node of model '%s': its edits are saved in that model's "
            "nodes block",
            selected_.c_str(), model->value.c_str());
        const json sections = live_entity_sections(scene_, *e);
        for (const char* name : {"transform", "light", "shadow", "camera", "renderer"})
          if (sections.contains(name)) section(selected_ + "." + name, name, sections[name], true);
        direction_helpers();
      }
    }
  }
  for (const char* name : {"render", "shadow"})
    if (doc.contains(name)) section(name, name, doc[name], false);
}

void Editor::section(const std::string& key, const std::string& label, const json& fields,
                     bool open_at_first) {
  const bool open = ImGui::CollapsingHeader(
      label.c_str(), open_at_first ? ImGuiTreeNodeFlags_DefaultOpen : ImGuiTreeNodeFlags_None);
  name_item(key);
  if (open)
    for (auto f = fields.begin(); f != fields.end(); ++f) {
      if (!f.value().is_object()) {
        field(key + "." + f.key(), f.key(), f.value());
        continue;
      }
      // A block of blocks (a model's animation clips): one tree node each, with its fields
      // (a clip's playing is play/pause, its time the scrubber).
      const std::string sub = key + "." + f.key();
      const bool sub_open = ImGui::TreeNodeEx(sub.c_str(), ImGuiTreeNodeFlags_DefaultOpen, "%s",
                                              f.key().c_str());
      name_item(sub);
      if (!sub_open) continue;
      for (auto g = f.value().begin(); g != f.value().end(); ++g)
        field(sub + "." + g.key(), g.key(), g.value());
      ImGui::TreePop();
    }
}

}  // namespace kaskad::editor
