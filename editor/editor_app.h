// The editor's state and its parts, for the files that define them (internal to editor/):
// editor.cpp the app loop and entry, document.cpp the document and its undo history,
// camera_controller.cpp the fly camera, viewport.cpp the frame and its debug views
// (debug_views.h), inspector.cpp, entity_panel.cpp and file_dialog_panel.cpp the panels,
// script_runner.cpp the --script actions and the widgets they click.
#pragma once

#include <chrono>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <imgui.h>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "components/bounds.h"
#include "editor/camera_controller.h"
#include "editor/editor.h"
#include "editor/file_dialog.h"
#include "editor/script.h"
#include "runtime/app/player.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/scene.h"
#include "runtime/assets/scene_io.h"
#include "runtime/core/json_reader.h"
#include "runtime/gpu/gl_handles.h"
#include "runtime/result/result.h"

namespace kaskad::editor {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Options = EditOptions;

// The panels: full height at the window's sides, resizable in width (each at most 45% of the
// window); the viewport is what is left between them, never less than one pixel.
struct Layout {
  bool panels = false;        ///< the side panels are drawn (not hidden by H, the window wide enough)
  float left = 0, right = 0;  ///< panel widths in pixels
  int view_x = 0, view_w = 0, view_h = 0;
};

inline constexpr float kMinPanel = 120.0f;
/// The narrowest window that has the side panels: both at their least width and 64 pixels of
/// viewport. A narrower window is all viewport, as after H (the viewport's frame, which a
/// script's screenshot waits for, would otherwise have no pixels).
inline constexpr int kMinPanelsWindow = 2 * int(kMinPanel) + 64;
// The side panels: fixed in place, resizable at their inner edge.
inline constexpr ImGuiWindowFlags kPanelFlags =
    ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoSavedSettings;
inline float max_panel(int window_width) { return std::max(kMinPanel, 0.45f * float(window_width)); }

/// `left` and `right` < 0: the first layout, a share of the window with limits in pixels, the
/// two panels together at most 55% of it. `hidden`, or a window narrower than kMinPanelsWindow:
/// no panels, the viewport is the window. For w, h >= 1 the viewport is at least 1x1.
Layout layout_for(int w, int h, float left, float right, bool hidden);

class Editor {
 public:
  /// The editor on `scene`, loaded from options.scene; `script` is --script's, parsed (empty:
  /// interactive). `player`'s context is current and outlives the editor.
  Editor(Options options, Scene scene, Player& player, std::vector<ScriptAction> script);

  /// The app loop (editor.cpp): frames until quit; returns the exit status.
  int run();

 private:
  // The document and its undo history (document.cpp). Edits: one --set assignment through
  // scene IO's own override path.
  Status edit(const std::string& assignment, bool merge);
  void record(bool merge);  ///< a snapshot of the scene as it is now, after an edit
  /// The scene becomes history document `index`; the view stays where the user put it, otherwise
  /// it is the document's camera.
  Status restore(std::size_t index);
  /// The scene becomes canonical document `doc` (read as a file of the scene's path would be),
  /// its programs compiled before its next frame; the scene is unchanged on an error.
  Status load_document(const json& doc);
  std::string unused_name(const std::string& stem) const;
  Status create(const std::string& shape);
  Status import_model(const std::string& path);
  Status remove_selected();
  Status duplicate_selected();
  Status rename_selected(const std::string& name);
  /// `parent` empty: make the selection a root. Its local transform is kept.
  Status reparent_selected(const std::string& parent);
  Status undo();
  Status open(const fs::path& file);     ///< refused while there are unsaved changes
  Status save_as(const fs::path& file);  ///< save, and make `file` the scene's own file
  Status redo();
  Status save(const fs::path& file);
  bool dirty() const { return position_ != saved_; }

  // The camera controller (camera_controller.cpp).
  std::optional<ecs::Entity> active_camera() const;
  void take_camera_from_scene();
  /// The active camera takes the fly camera's pose (nothing else of it changes).
  void place_camera();
  /// A move by the user (fly, F, orbit, a script's camera): place_camera(), and an auto_frame
  /// camera becomes a placed one whose near and far follow it.
  void write_camera();
  void update_bounds_speed();
  Status press(const std::string& key, float seconds);
  Status frame_selection();
  /// Turns the camera about the selection's centre by `yaw` and `pitch` radians.
  Status orbit(float yaw, float pitch);
  std::optional<ecs::Entity> find(const std::string& name) const;

  // A frame (viewport.cpp) and the UI: the window's layout (editor.cpp), the panels (inspector.cpp,
  // entity_panel.cpp, file_dialog_panel.cpp).
  Status render_viewport(int w, int h);
  void draw_ui(int w, int h);
  void entity_list();
  void entity_node(ecs::Entity e, const std::map<std::uint32_t, std::vector<ecs::Entity>>& children);
  void inspector();
  void field(const std::string& key, const std::string& label, const json& value);
  /// A collapsing section named `label` (widget `key`) of the fields of object `fields`, each
  /// field's key "KEY.FIELD".
  void section(const std::string& key, const std::string& label, const json& fields,
               bool open_at_first);
  void request(const std::string& assignment);
  /// The names the readers accept for the enumerated field KEY (an inspector key such as
  /// "shadow.filter" or "sun.light.type"); nullptr when KEY is not enumerated.
  const std::vector<std::string>* choices(const std::string& key);
  /// The bounds the readers check the number (or numbers) of field KEY against; nullptr when
  /// they check none.
  const json_reader::FieldRecorder::Range* limits(const std::string& key);
  /// A number field's edit after its widget: a drag applies as it moves, a number typed into the
  /// field (Ctrl+click or double-click) only when Enter or a click elsewhere ends the typing.
  void number_edit(const std::string& key, bool changed, const std::string& assignment);
  /// What picking NAME in KEY's combo does: the edit KEY="NAME", for a name of choices(KEY) only.
  Status choose(const std::string& key, const std::string& name);
  void direction_helpers();
  /// Shows the file dialog for `purpose`, in the folder of `typed` (a path typed in a panel) and
  /// with its name, else in the scene's folder.
  void show_file_dialog(FileDialog::Purpose purpose, const std::string& typed);
  void file_dialog(int w, int h);
  /// The dialog's OK: a folder is entered; a file is opened, saved to or imported after the frame,
  /// the dialog staying with the error when that is refused.
  void accept_file_dialog();
  void interactive_input(float dt);
  void entities_panel(int w, int h, const Layout& l);
  // The script runner (script_runner.cpp): widgets by name, a script's pointer and keys, its
  // actions.
  /// Records the last widget's place under `name` (its label without a "##..." part).
  void name_item(const std::string& name);
  bool button(const char* label) {
    const bool pressed = ImGui::Button(label);
    name_item(label);
    return pressed;
  }
  /// Queues a script's mouse on the widget named `what`: `presses` clicks (with Ctrl held), the
  /// mouse moved `drag_pixels` to the right over eight frames while the button is down.
  void queue_pointer(const std::string& what, bool ctrl, int presses, int drag_pixels, int line);
  /// Feeds the next queued script step to Dear ImGui (between the backend's frame and its own);
  /// an error when the widget a click names was not drawn in the last frame.
  Status feed_ui_step();
  Status run_action(const ScriptAction& a, bool& quit);

  const json& document() {
    if (doc_stale_) {
      doc_ = scene_to_json(scene_);
      doc_stale_ = false;
    }
    return doc_;
  }
  void report(const std::string& message) {
    message_ = message;
    message_is_error_ = true;
    std::fprintf(stderr, "kaskad edit: %s\n", message.c_str());
  }

  Options opt_;
  /// Every enumeration and range-checked number the scene readers are asked for while the
  /// editor runs: the combo boxes' items and the drag fields' limits are the readers' own.
  json_reader::FieldRecorder recorded_;
  std::map<std::string, std::vector<std::string>> choices_;  ///< by object_and_field()
  std::size_t choices_from_ = 0;  ///< how many recorded fields choices_ was made from
  std::map<std::string, json_reader::FieldRecorder::Range> limits_;  ///< by object_and_field()
  std::size_t limits_from_ = 0;                ///< how many recorded ranges limits_ was made from
  std::pair<std::string, std::string> typed_;  ///< a number being typed: its key and edit
  /// The named widgets of the last UI frame and where they were (min x, min y, max x, max y):
  /// fields by their key, buttons and text fields by their label, entity rows "entity:NAME",
  /// a combo's items "KEY=ITEM", the file dialog's rows "dialog:NAME" (docs/guide/editor.md,
  /// "Scripts", `click`).
  struct Widget {
    std::array<float, 4> rect;  ///< min x, min y, max x, max y
    bool visible;               ///< not scrolled out of its panel
  };
  std::map<std::string, Widget> widgets_;
  std::string scroll_to_;  ///< a widget to scroll into view as it is drawn (a script's click)
  /// A script's input to the panels (click, ctrl_click, double_click, type, key enter|escape):
  /// one step a frame, fed to Dear ImGui before its frame starts.
  struct UiStep {
    enum class Kind { settle, move, press, release, move_by, text, key_down, key_up } kind;
    std::string what;  ///< move: the widget; text: the characters
    bool ctrl = false;
    int key = 0;
    int line = 0;  ///< the script line, for messages
  };
  std::deque<UiStep> ui_steps_;
  ImVec2 ui_mouse_{-FLT_MAX, -FLT_MAX};  ///< where the script's mouse is
  Scene scene_;
  Player& player_;  ///< outlives the editor: its context outlives the UI's GL objects
  std::vector<ScriptAction> script_;  ///< --script, parsed before the window opened
  std::vector<json> history_;     ///< canonical documents, one per edit; [0] as loaded
  std::size_t position_ = 0;      ///< the document the scene is now
  std::size_t saved_ = 0;         ///< the document last saved (or loaded); npos: none of them
  std::string last_drag_key_;     ///< a drag in progress edits one history entry, not one a frame
  std::vector<std::pair<std::string, bool>> requests_;  ///< UI edits, applied after the frame
  std::string selected_;
  std::string message_;           ///< the last error or notice, shown in the inspector
  bool message_is_error_ = false;
  std::string set_line_;          ///< the inspector's free "key=value" field
  std::vector<std::function<Status()>> operations_;  ///< UI entity operations, after the frame
  std::string file_line_;         ///< the inspector's path field for open and save as
  FileDialog dialog_;
  int create_shape_ = 0;
  char import_path_[512] = "";
  json doc_;
  bool doc_stale_ = true;
  FlyCamera camera_;
  float speed_ = 1.0f;            ///< fly speed, metres per second (from the scene's size)
  Aabb bounds_;  ///< the scene's bounds, after each load and edit (fly speed, planes, notices)
  bool panels_hidden_ = false;    ///< H: the viewport takes the whole window
  bool empty_view_ = false;       ///< the last frame drew nothing of a scene with meshes
  bool planes_follow_ = false;    ///< the camera was auto_frame: its near and far follow it
  bool prewarm_ = true;           ///< compile the scene's programs before its first frame
  bool changed_since_frame_ = true;
  /// When the viewport last rendered: playing clips advance by the time since (a script's
  /// frames by 1/60 s each, so its screenshots do not depend on the machine's speed).
  std::chrono::steady_clock::time_point last_render_{};
  bool viewport_hovered_ = false;
  bool ask_quit_ = false;
  gpu::Texture view_texture_;
  int texture_w_ = 0, texture_h_ = 0;
  Image last_frame_;              ///< what the viewport shows (the colour, or a debug view)
  View view_ = View::colour;
  std::vector<float> frame_ms_;   ///< the last frames' times, for the graph
  float left_w_ = -1.0f, right_w_ = -1.0f;  ///< panel widths as the user left them; < 0: default
  std::string stats_;             ///< the last frame's time and counters, shown in the inspector
  glm::vec3 look_at_{0.0f};       ///< the inspector's look-at point for the selection
  fs::path window_shot_;          ///< window_screenshot: written after the next frame's UI
};

}  // namespace kaskad::editor
