// The file dialog (Open, Save as, Import model) as drawn: its folder logic is file_dialog.h's.
#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "editor/editor_app.h"
#include "runtime/core/file_io.h"

namespace kaskad::editor {

void Editor::show_file_dialog(FileDialog::Purpose purpose, const std::string& typed) {
  dialog_.purpose = purpose;
  std::error_code ec;
  const fs::path t = typed;
  if (!typed.empty() && fs::is_directory(t, ec)) {
    dialog_.enter(t);
    dialog_.name[0] = '\0';
  } else if (!typed.empty() && fs::is_directory(fs::absolute(t, ec).parent_path(), ec)) {
    dialog_.enter(fs::absolute(t, ec).parent_path());
    std::snprintf(dialog_.name, sizeof dialog_.name, "%s", t.filename().string().c_str());
  } else {
    dialog_.enter(folder_of(opt_.scene));
    const std::string own =
        purpose == FileDialog::Purpose::save_as ? opt_.scene.filename().string() : "";
    std::snprintf(dialog_.name, sizeof dialog_.name, "%s", own.c_str());
  }
  dialog_.replace.clear();
  dialog_.visible = dialog_.appearing = true;
}

void Editor::accept_file_dialog() {
  FileDialog& d = dialog_;
  const std::string typed = d.name;
  fs::path file = !d.picked.empty() && typed == display_name(d.picked.filename().string())
                      ? d.picked
                      : resolve_typed(d.folder, typed);
  if (file.empty()) {
    d.error = "type a file name, or pick one";
    return;
  }
  std::error_code ec;
  if (fs::is_directory(file, ec)) {
    d.enter(file);
    d.name[0] = '\0';
    return;
  }
  if (d.purpose == FileDialog::Purpose::save_as) {
    if (!file.has_extension()) file += ".json";
    // A file that is there is replaced only when asked twice.
    if (fs::exists(file, ec) && file != d.replace) {
      d.replace = file;
      d.error = display_name(file.filename().string()) + " exists: save again to replace it";
      return;
    }
  }
  const FileDialog::Purpose purpose = d.purpose;
  operations_.push_back([this, file, purpose] {
    const Status st = purpose == FileDialog::Purpose::open      ? open(file)
                      : purpose == FileDialog::Purpose::save_as ? save_as(file)
                                                                : import_model(file.string());
    if (st) dialog_.visible = false;
    else dialog_.error = st.error().to_string();
    return st;
  });
}

void Editor::file_dialog(int w, int h) {
  FileDialog& d = dialog_;
  if (d.appearing) {
    ImGui::OpenPopup("###file_dialog");
    d.appearing = false;
  }
  ImGui::SetNextWindowSize(
      ImVec2(std::min(640.0f, 0.8f * float(w)), std::min(460.0f, 0.85f * float(h))),
      ImGuiCond_Appearing);
  ImGui::SetNextWindowPos(ImVec2(0.5f * float(w), 0.5f * float(h)), ImGuiCond_Appearing,
                          ImVec2(0.5f, 0.5f));
  bool keep = true;
  if (!ImGui::BeginPopupModal(d.title(), &keep, ImGuiWindowFlags_NoSavedSettings)) {
    d.visible = false;  // closed by Escape or its close button
    return;
  }
  if (!keep || !d.visible) {
    d.visible = false;
    ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
    return;
  }
  if (button("up") && d.folder.has_parent_path() && d.folder.parent_path() != d.folder)
    d.enter(d.folder.parent_path());
  ImGui::SameLine();
  if (button("refresh")) d.enter(d.folder);
  ImGui::SameLine();
  ImGui::TextUnformatted(display_name(d.folder.string()).c_str());
  const ImVec4 red(1.0f, 0.45f, 0.35f, 1.0f);
  if (!d.listing.error.empty()) ImGui::TextColored(red, "%s", d.listing.error.c_str());
  // The rows: a folder is entered with one click; a file is picked with one, accepted with two.
  const float footer = ImGui::GetFrameHeightWithSpacing() * 2.0f +
                       (d.error.empty() ? 0.0f : ImGui::GetTextLineHeightWithSpacing() * 2.0f);
  ImGui::BeginChild("entries", ImVec2(0, -footer), true);
  std::optional<fs::path> enter;
  bool accept = false;
  for (const FolderEntry& e : d.listing.entries) {
    const std::string label = e.folder ? e.label + "/" : e.label;
    const bool picked = !e.folder && e.path == d.picked;
    const bool clicked =
        ImGui::Selectable(label.c_str(), picked, ImGuiSelectableFlags_AllowDoubleClick);
    name_item("dialog:" + label);
    if (clicked) {
      if (e.folder) {
        enter = e.path;
      } else {
        d.picked = e.path;
        std::snprintf(d.name, sizeof d.name, "%s", e.label.c_str());
        d.error.clear();
        accept = ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left);
      }
    }
  }
  if (d.listing.entries.empty() && d.listing.error.empty())
    ImGui::TextDisabled("no folders or %s files here", json_reader::join(d.extensions()).c_str());
  ImGui::EndChild();
  if (enter) d.enter(*enter);
  if (ImGui::IsWindowAppearing()) ImGui::SetKeyboardFocusHere();
  ImGui::SetNextItemWidth(-160.0f);
  ImGui::InputText("##name", d.name, sizeof d.name, ImGuiInputTextFlags_AutoSelectAll);
  name_item("dialog name");
  // Enter anywhere in the dialog (the name field gives up the keyboard on Enter, so a second one,
  // to answer "replace it?", comes with no field active); as pressed, not its repeats: a held
  // Enter must not answer by itself.
  if (ImGui::IsWindowFocused(ImGuiFocusedFlags_RootAndChildWindows) &&
      (ImGui::IsKeyPressed(GLFW_KEY_ENTER, false) || ImGui::IsKeyPressed(GLFW_KEY_KP_ENTER, false)))
    accept = true;
  // Escape closes it (in the name field, the first Escape leaves the field).
  const bool escape = ImGui::IsWindowFocused(ImGuiFocusedFlags_RootAndChildWindows) &&
                      ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false) && !ImGui::IsAnyItemActive();
  ImGui::SameLine();
  const char* verb = d.purpose == FileDialog::Purpose::open      ? "open"
                     : d.purpose == FileDialog::Purpose::save_as ? "save"
                                                                 : "import";
  if (button(verb)) accept = true;
  ImGui::SameLine();
  if (button("cancel") || escape) {
    d.visible = false;
    ImGui::CloseCurrentPopup();
  }
  if (!d.error.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, red);
    ImGui::TextWrapped("%s", d.error.c_str());
    ImGui::PopStyleColor();
  }
  if (accept && d.visible) accept_file_dialog();
  ImGui::EndPopup();
}

}  // namespace kaskad::editor
