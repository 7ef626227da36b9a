// The entities panel: create a shape, import a model, and the entity tree (select, drag onto
// another to parent).
#include <algorithm>
#include <cstdint>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "components/name.h"
#include "components/transform.h"
#include "editor/editor_app.h"

namespace kaskad::editor {

void Editor::entity_node(ecs::Entity e,
                         const std::map<std::uint32_t, std::vector<ecs::Entity>>& children) {
  const auto* n = scene_.world.try_get<Name>(e);
  const std::string name = n ? n->value : "(unnamed " + std::to_string(e.index) + ")";
  const auto kids = children.find(e.index);
  ImGuiTreeNodeFlags flags = ImGuiTreeNodeFlags_OpenOnArrow | ImGuiTreeNodeFlags_SpanAvailWidth |
                             ImGuiTreeNodeFlags_DefaultOpen;
  if (kids == children.end()) flags |= ImGuiTreeNodeFlags_Leaf;
  if (n && n->value == selected_) flags |= ImGuiTreeNodeFlags_Selected;
  ImGui::PushID(int(e.index));
  const bool open = ImGui::TreeNodeEx(name.c_str(), flags);
  if (ImGui::IsItemClicked() && n) selected_ = n->value;
  if (n) name_item("entity:" + n->value);
  // Drag an entity onto another to parent it there.
  if (n && ImGui::BeginDragDropSource()) {
    ImGui::SetDragDropPayload("kaskad_entity", n->value.data(), n->value.size());
    ImGui::TextUnformatted(n->value.c_str());
    ImGui::EndDragDropSource();
  }
  if (n && ImGui::BeginDragDropTarget()) {
    if (const ImGuiPayload* p = ImGui::AcceptDragDropPayload("kaskad_entity")) {
      const std::string child(static_cast<const char*>(p->Data), std::size_t(p->DataSize));
      const std::string parent = n->value;
      operations_.push_back([this, child, parent] {
        selected_ = child;
        return reparent_selected(parent);
      });
    }
    ImGui::EndDragDropTarget();
  }
  if (open) {
    if (kids != children.end())
      for (ecs::Entity c : kids->second) entity_node(c, children);
    ImGui::TreePop();
  }
  ImGui::PopID();
}

void Editor::entity_list() {
  std::vector<ecs::Entity> all;
  scene_.world.view<Transform>().each([&](ecs::Entity e, const Transform&) { all.push_back(e); });
  std::sort(all.begin(), all.end(), [](ecs::Entity a, ecs::Entity b) { return a.index < b.index; });
  std::map<std::uint32_t, std::vector<ecs::Entity>> children;
  std::vector<ecs::Entity> roots;
  for (ecs::Entity e : all) {
    const ecs::Entity p = scene_.world.get<Transform>(e).parent;
    if (p.valid() && scene_.world.alive(p) && p != e)
      children[p.index].push_back(e);
    else
      roots.push_back(e);
  }
  for (ecs::Entity e : roots) entity_node(e, children);
}

void Editor::entities_panel(int w, int h, const Layout& l) {
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(l.left, float(h)));
  ImGui::SetNextWindowSizeConstraints(ImVec2(kMinPanel, float(h)), ImVec2(max_panel(w), float(h)));
  // Deep glTF hierarchies scroll sideways rather than cut their names.
  ImGui::Begin("Entities", nullptr, kPanelFlags | ImGuiWindowFlags_HorizontalScrollbar);
  static const char* kShapes[] = {"box", "sphere", "cylinder", "cone", "plane"};
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x * 0.5f);
  ImGui::Combo("##shape", &create_shape_, kShapes, int(std::size(kShapes)));
  name_item("shape");
  ImGui::SameLine();
  if (button("create")) {
    const std::string shape = kShapes[create_shape_];
    operations_.push_back([this, shape] { return create(shape); });
  }
  // A glTF file (path as typed, Enter or the button): imported in front of the camera.
  // The field takes what the two buttons after it leave.
  const ImGuiStyle& style = ImGui::GetStyle();
  const float buttons = ImGui::CalcTextSize("import").x + ImGui::CalcTextSize("...").x +
                        4.0f * style.FramePadding.x + 2.0f * style.ItemSpacing.x;
  ImGui::SetNextItemWidth(std::max(40.0f, ImGui::GetContentRegionAvail().x - buttons));
  const bool entered = ImGui::InputTextWithHint("##model", "model.gltf", import_path_,
                                                sizeof import_path_,
                                                ImGuiInputTextFlags_EnterReturnsTrue);
  name_item("model path");
  ImGui::SameLine();
  if ((button("import") || entered) && import_path_[0] != '\0') {
    const std::string path = import_path_;
    operations_.push_back([this, path] { return import_model(path); });
  }
  ImGui::SameLine();
  if (button("...")) show_file_dialog(FileDialog::Purpose::import, import_path_);
  ImGui::Separator();
  entity_list();
  left_w_ = ImGui::GetWindowWidth();
  ImGui::End();
}

}  // namespace kaskad::editor
