// The script runner: each --script action (editor/script.h parses them) done on the editor, and
// the pointer, keys and typing a script gives the panels, fed to Dear ImGui a step a frame at
// the widgets the last frame drew.
#include <cfloat>
#include <cstdio>
#include <string>
#include <vector>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <glm/gtc/constants.hpp>

#include "editor/editor_app.h"
#include "runtime/assets/image_io.h"

namespace kaskad::editor {

void Editor::name_item(const std::string& label) {
  const std::string name = label.substr(0, label.find("##"));
  const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
  widgets_[name] = {{lo.x, lo.y, hi.x, hi.y}, ImGui::IsItemVisible()};
  if (name == scroll_to_) {
    ImGui::SetScrollHereY(0.5f);
    scroll_to_.clear();
  }
}

void Editor::queue_pointer(const std::string& what, bool ctrl, int presses, int drag_pixels,
                           int line) {
  using K = UiStep::Kind;
  // A frame first, so that the panels show what the actions before changed (a selection's
  // inspector); then the mouse goes there, and presses (and drags) and releases, a frame each.
  ui_steps_.push_back({K::settle, "", false, 0, line});
  ui_steps_.push_back({K::move, what, ctrl, 0, line});
  for (int i = 0; i < presses; ++i) {
    ui_steps_.push_back({K::press, what, ctrl, 0, line});
    for (int k = 0; drag_pixels != 0 && k < 8; ++k)
      ui_steps_.push_back(
          {K::move_by, "", ctrl, (drag_pixels * (k + 1)) / 8 - (drag_pixels * k) / 8, line});
    ui_steps_.push_back({K::release, what, ctrl, 0, line});
  }
  ui_steps_.push_back({K::settle, "", false, 0, line});
}

Status Editor::feed_ui_step() {
  ImGuiIO& io = ImGui::GetIO();
  if (ui_steps_.empty()) {
    if (ui_mouse_.x != -FLT_MAX) io.MousePos = ui_mouse_;  // the script's mouse stays put
    return {};
  }
  const UiStep step = ui_steps_.front();
  ui_steps_.pop_front();
  using K = UiStep::Kind;
  // A script's frames are a user's: two clicks a few frames apart make a double click; a settle
  // step lasts half a second, so that clicks of separate actions never do.
  io.DeltaTime = step.kind == UiStep::Kind::settle ? 0.5f : 1.0f / 60.0f;
  io.KeyCtrl = step.ctrl;
  // The mouse follows the widget to where the last frame drew it (a panel's lines may move).
  auto centre = [&](const Widget& w) {
    ui_mouse_ = ImVec2(0.5f * (w.rect[0] + w.rect[2]), 0.5f * (w.rect[1] + w.rect[3]));
  };
  if (step.kind == K::press)
    if (const auto it = widgets_.find(step.what); it != widgets_.end()) centre(it->second);
  switch (step.kind) {
    case K::settle:
      break;
    case K::move: {
      const auto it = widgets_.find(step.what);
      if (it == widgets_.end()) {
        ui_steps_.clear();
        std::vector<std::string> shown;
        for (const auto& [name, widget] : widgets_)
          if (shown.size() < 40) shown.push_back(name);
        if (widgets_.size() > shown.size())
          shown.push_back("... (" + std::to_string(widgets_.size()) + " in all)");
        return Error{opt_.script.string(), "line " + std::to_string(step.line),
                     "no widget named '" + step.what +
                         "' in the last frame; it showed: " + json_reader::join(shown)};
      }
      if (!it->second.visible) {
        // Scrolled out of its panel: scrolled to as it is drawn, then looked for again.
        if (step.key >= 3)
          return Error{opt_.script.string(), "line " + std::to_string(step.line),
                       "widget '" + step.what + "' stays out of view"};
        scroll_to_ = step.what;
        UiStep again = step;
        ++again.key;  // the attempts
        ui_steps_.push_front(again);
        ui_steps_.push_front({K::settle, "", step.ctrl, 0, step.line});
        break;
      }
      centre(it->second);
      break;
    }
    case K::press:
      io.MouseDown[0] = true;
      break;
    case K::move_by:
      io.MouseDown[0] = true;
      ui_mouse_.x += float(step.key);
      break;
    case K::release:
      io.MouseDown[0] = false;
      break;
    case K::text:
      io.AddInputCharactersUTF8(step.what.c_str());
      break;
    case K::key_down:
      io.KeysDown[step.key] = true;
      break;
    case K::key_up:
      io.KeysDown[step.key] = false;
      break;
  }
  if (ui_mouse_.x != -FLT_MAX) io.MousePos = ui_mouse_;
  return {};
}

Status Editor::run_action(const ScriptAction& a, bool& quit) {
  switch (a.kind) {
    case ActionKind::set:
      return edit(a.args[0], false);
    case ActionKind::choices: {
      // What the inspector's combo for KEY lists.
      const std::vector<std::string>* names = choices(a.args[0]);
      if (!names) return Error{"", "", "choices: '" + a.args[0] + "' is not an enumerated field"};
      std::printf("kaskad edit: choices %s: %s\n", a.args[0].c_str(),
                  json_reader::join(*names).c_str());
      return {};
    }
    case ActionKind::choose:
      return choose(a.args[0], a.args[1]);
    case ActionKind::select:
      if (!find(a.args[0])) return Error{"", "", "select: no entity named '" + a.args[0] + "'"};
      selected_ = a.args[0];
      changed_since_frame_ = true;  // the probe faces view follows the selection
      return {};
    case ActionKind::camera: {
      float v[6] = {};
      for (std::size_t i = 0; i < a.args.size(); ++i) v[i] = std::stof(a.args[i]);
      camera_.position = glm::vec3(v[0], v[1], v[2]);
      if (a.args.size() == 6) {
        const glm::vec3 d = glm::vec3(v[3], v[4], v[5]) - camera_.position;
        if (glm::length(d) <= 0.0f) return Error{"", "", "camera: the look-at point is the position"};
        camera_.look_along(d);
      }
      write_camera();
      return {};
    }
    case ActionKind::key:
      if (dialog_.visible && a.args[0] != "enter" && a.args[0] != "escape")
        return Error{"", "", "key " + a.args[0] + ": the file dialog is up and has the keys"};
      if (a.args[0] == "enter" || a.args[0] == "escape") {
        // To the panels: pressed for a frame, then released.
        const int key = a.args[0] == "enter" ? GLFW_KEY_ENTER : GLFW_KEY_ESCAPE;
        ui_steps_.push_back({UiStep::Kind::key_down, "", false, key, a.line});
        ui_steps_.push_back({UiStep::Kind::key_up, "", false, key, a.line});
        ui_steps_.push_back({UiStep::Kind::settle, "", false, 0, a.line});
        return {};
      }
      // One fly step is a frame's worth at 30 Hz; a key that fails (nothing to undo, a save
      // refused) fails the script.
      return press(a.args[0], 1.0f / 30.0f);
    case ActionKind::click:
    case ActionKind::ctrl_click:
    case ActionKind::double_click:
      queue_pointer(a.args[0], a.kind == ActionKind::ctrl_click,
                    a.kind == ActionKind::double_click ? 2 : 1, 0, a.line);
      return {};
    case ActionKind::drag:  // PIXELS to the right (left if negative)
      queue_pointer(a.args[0], false, 1, std::stoi(a.args[1]), a.line);
      return {};
    case ActionKind::type:
      // A character a frame (UTF-8 sequences whole), as typed.
      for (std::size_t i = 0; i < a.args[0].size();) {
        std::size_t n = 1;
        while (i + n < a.args[0].size() &&
               (static_cast<unsigned char>(a.args[0][i + n]) & 0xC0) == 0x80)
          ++n;
        ui_steps_.push_back({UiStep::Kind::text, a.args[0].substr(i, n), false, 0, a.line});
        i += n;
      }
      return {};
    case ActionKind::frames:
    case ActionKind::input:  // the run loop counts both
      return {};
    case ActionKind::create:
      return create(a.args[0]);
    case ActionKind::import:
      return import_model(a.args[0]);
    case ActionKind::remove:
      return remove_selected();
    case ActionKind::duplicate:
      return duplicate_selected();
    case ActionKind::rename:
      return rename_selected(a.args[0]);
    case ActionKind::parent:
      return reparent_selected(a.args[0] == "-" ? std::string() : a.args[0]);
    case ActionKind::orbit:
      return orbit(glm::radians(std::stof(a.args[0])), glm::radians(std::stof(a.args[1])));
    case ActionKind::view:
      view_ = *view_named(a.args[0]);  // checked by parse_script
      changed_since_frame_ = true;
      return {};
    case ActionKind::screenshot:
      if (last_frame_.width == 0) return Error{"", "", "screenshot: no frame rendered yet"};
      KASKAD_TRY(save_image(a.args[0], last_frame_));
      std::printf("kaskad edit: wrote %s\n", a.args[0].c_str());
      return {};
    case ActionKind::window_screenshot:
      KASKAD_TRY(check_image_output(a.args[0]));
      window_shot_ = a.args[0];
      return {};
    case ActionKind::save:
      return save(a.args.empty() ? opt_.scene : fs::path(a.args[0]));
    case ActionKind::open:
      return open(a.args[0]);
    case ActionKind::save_as:
      return save_as(a.args[0]);
    case ActionKind::undo:
      return undo();
    case ActionKind::redo:
      return redo();
    case ActionKind::quit:
      if (dirty())
        return Error{"", "", "quit with unsaved changes (save first, or quit! to discard them)"};
      quit = true;
      return {};
    case ActionKind::force_quit:
      quit = true;
      return {};
  }
  return {};
}

}  // namespace kaskad::editor
