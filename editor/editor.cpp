#include "editor/editor.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <functional>
#include <iterator>
#include <map>
#include <optional>
#include <string>
#include <vector>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "components/bounds.h"
#include "components/camera.h"
#include "components/light.h"
#include "components/model.h"
#include "components/name.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "editor/file_dialog.h"
#include "editor/script.h"
#include "runtime/assets/env_map.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/scene_io.h"
#include "runtime/app/player.h"
#include "runtime/core/file_io.h"
#include "runtime/core/json_reader.h"
#include "runtime/core/log.h"
#include "runtime/gpu/context.h"
#include "runtime/gpu/gl_handles.h"
#include "systems/camera_system.h"
#include "systems/transform_system.h"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace kaskad::editor {

namespace {

using Options = EditOptions;

// The fly camera: a position and a heading, written into the scene's active camera when moved.
struct FlyCamera {
  glm::vec3 position{0.0f};
  float yaw = 0.0f;    ///< radians about +Y; 0 looks down -Z
  float pitch = 0.0f;  ///< radians above the horizon
  bool moved = false;  ///< the user moved it since load (then it is kept over undo and redo)

  glm::vec3 forward() const {
    return {std::sin(yaw) * std::cos(pitch), std::sin(pitch), -std::cos(yaw) * std::cos(pitch)};
  }
  void look_along(const glm::vec3& d) {
    const glm::vec3 n = glm::normalize(d);
    pitch = std::asin(std::clamp(n.y, -1.0f, 1.0f));
    yaw = std::atan2(n.x, -n.z);
  }
};

// The panels: full height at the window's sides, resizable in width (each at most 45% of the
// window); the viewport is what is left between them.
struct Layout {
  float left = 0, right = 0;  ///< panel widths in pixels
  int view_x = 0, view_w = 0, view_h = 0;
};

constexpr float kMinPanel = 120.0f;
// The side panels: fixed in place, resizable at their inner edge.
constexpr ImGuiWindowFlags kPanelFlags =
    ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoSavedSettings;
float max_panel(int window_width) { return std::max(kMinPanel, 0.45f * float(window_width)); }

/// `left` and `right` < 0: the first layout, a share of the window with limits in pixels, the
/// two panels together at most 55% of it. `hidden`: no panels, the viewport is the window.
Layout layout_for(int w, int h, float left, float right, bool hidden) {
  Layout l;
  if (hidden) {
    l.view_w = w;
    l.view_h = h;
    return l;
  }
  const float fw = float(w);
  l.left = left < 0 ? std::clamp(0.2f * fw, 160.0f, 300.0f) : left;
  l.right = right < 0 ? std::clamp(0.32f * fw, 200.0f, 460.0f) : right;
  if (left < 0 && right < 0 && l.left + l.right > 0.55f * fw) {
    const float shrink = 0.55f * fw / (l.left + l.right);
    l.left *= shrink;
    l.right *= shrink;
  }
  l.left = std::clamp(l.left, kMinPanel, max_panel(w));
  l.right = std::clamp(l.right, kMinPanel, max_panel(w));
  l.view_x = int(l.left);
  l.view_w = std::max(0, w - int(l.left) - int(l.right));
  l.view_h = h;
  return l;
}

// The window as drawn (panels and viewport), top row first.
Image read_window(int w, int h) {
  Image img;
  img.width = w;
  img.height = h;
  img.channels = 3;
  std::vector<unsigned char> bytes(std::size_t(w) * std::size_t(h) * 3);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, bytes.data());
  img.pixels.resize(bytes.size());
  const std::size_t row = std::size_t(w) * 3;
  for (std::size_t y = 0; y < std::size_t(h); ++y)
    for (std::size_t i = 0; i < row; ++i)
      img.pixels[y * row + i] = float(bytes[(std::size_t(h) - 1 - y) * row + i]) / 255.0f;
  return img;
}

// Linear radiance clamped to [0, 1] and encoded for display with a 2.2 gamma (an approximation
// of sRGB is enough for a debug view).
float display_gamma(float linear) {
  return std::pow(std::clamp(linear, 0.0f, 1.0f), 1.0f / 2.2f);
}

// An AOV view as an RGB image; `aovs` has the channels of Renderer::read_aovs(), found by the
// names it gives them (README "AOV contract").
Image aov_view(View view, const Image& aovs) {
  Image out;
  out.width = aovs.width;
  out.height = aovs.height;
  out.channels = 3;
  out.pixels.assign(std::size_t(aovs.width) * std::size_t(aovs.height) * 3, 0.0f);
  auto channel = [&](const char* name) {
    const auto it = std::find(aovs.channel_names.begin(), aovs.channel_names.end(), name);
    KASKAD_CHECK(it != aovs.channel_names.end(), "the AOVs have a channel of every name read here");
    return int(it - aovs.channel_names.begin());
  };
  const int px = channel("P.X"), nx = channel("N.X"), z = channel("Z"), vis = channel("visibility"),
            mask = channel("mask"), cascade = channel("cascade"), rr = channel("reflection.R"),
            reflector = channel("reflector");
  // Cascades 0..7 in distinct colours (outside every cascade: black).
  static const glm::vec3 kCascade[] = {{1, 0.2f, 0.2f}, {0.2f, 1, 0.2f}, {0.3f, 0.4f, 1},
                                       {1, 1, 0.2f},    {1, 0.3f, 1},    {0.2f, 1, 1},
                                       {1, 0.6f, 0.2f}, {0.7f, 0.7f, 0.7f}};
  // The depth and position views span what is visible.
  float far = 0.0f;
  Aabb seen;
  auto vec3_at = [&](int x, int y, int first) {
    return glm::vec3(aovs.at(x, y, first), aovs.at(x, y, first + 1), aovs.at(x, y, first + 2));
  };
  for (int y = 0; y < aovs.height; ++y)
    for (int x = 0; x < aovs.width; ++x)
      if (aovs.at(x, y, mask) > 0.5f) {
        far = std::max(far, aovs.at(x, y, z));
        seen.expand(vec3_at(x, y, px));
      }
  const glm::vec3 span =
      seen.empty() ? glm::vec3(1.0f) : glm::max(seen.max - seen.min, glm::vec3(1e-6f));
  for (int y = 0; y < aovs.height; ++y)
    for (int x = 0; x < aovs.width; ++x) {
      glm::vec3 c{0.0f};
      if (aovs.at(x, y, mask) > 0.5f) {
        switch (view) {
          case View::visibility:
            c = glm::vec3(aovs.at(x, y, vis));
            break;
          case View::cascade: {
            const int k = int(std::lround(aovs.at(x, y, cascade)));
            if (k >= 0) c = kCascade[k % 8] * (0.4f + 0.6f * aovs.at(x, y, vis));
            break;
          }
          case View::normal:
            c = 0.5f * vec3_at(x, y, nx) + 0.5f;
            break;
          case View::depth:
            c = glm::vec3(far > 0.0f ? 1.0f - aovs.at(x, y, z) / far : 0.0f);
            break;
          case View::position:
            c = (vec3_at(x, y, px) - seen.min) / span;
            break;
          case View::reflection: {
            // C_t where a reflection map shades the surface; other surfaces dark grey (the
            // editor test's reflector mask, tests/editor/changed_within.py, knows this grey).
            constexpr float kNotReflecting = 0.08f;
            const glm::vec3 t = vec3_at(x, y, rr);
            c = aovs.at(x, y, reflector) > 0.5f
                    ? glm::vec3(display_gamma(t.r), display_gamma(t.g), display_gamma(t.b))
                    : glm::vec3(kNotReflecting);
            break;
          }
          default: break;
        }
      }
      float* p = &out.pixels[(std::size_t(y) * std::size_t(out.width) + std::size_t(x)) * 3];
      p[0] = c.r;
      p[1] = c.g;
      p[2] = c.b;
    }
  return out;
}

// A cube map's faces side by side (+X -X +Y -Y +Z -Z), encoded by display_gamma().
Image cube_strip(const CubeMap& cube) {
  Image out;
  out.width = cube.size * 6;
  out.height = cube.size;
  out.channels = 3;
  out.pixels.resize(std::size_t(out.width) * std::size_t(out.height) * 3);
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < cube.size; ++y)
      for (int x = 0; x < cube.size; ++x) {
        const glm::vec4 c = cube.at(CubeFace(f), x, y);
        float* p = &out.pixels[(std::size_t(y) * std::size_t(out.width) +
                                std::size_t(f * cube.size + x)) * 3];
        for (int k = 0; k < 3; ++k) p[k] = display_gamma(c[k]);
      }
  return out;
}

// A sphere map (row 0 at the top) as an image, encoded by display_gamma() like cube_strip().
Image sphere_image(const SphereMap& map) {
  Image out;
  out.width = out.height = map.size;
  out.channels = 3;
  out.pixels.resize(std::size_t(map.size) * std::size_t(map.size) * 3);
  for (std::size_t i = 0; i < map.texels.size(); ++i)
    for (int k = 0; k < 3; ++k)
      out.pixels[3 * i + std::size_t(k)] = display_gamma(map.texels[i][k]);
  return out;
}

// A one-channel image as grey RGB.
Image grey(const Image& one) {
  Image out;
  out.width = one.width;
  out.height = one.height;
  out.channels = 3;
  out.pixels.resize(one.pixels.size() * 3);
  for (std::size_t i = 0; i < one.pixels.size(); ++i)
    out.pixels[3 * i] = out.pixels[3 * i + 1] = out.pixels[3 * i + 2] = one.pixels[i];
  return out;
}

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

// The file dialog's state: what it is for, the folder shown and the name typed.
struct FileDialog {
  enum class Purpose { open, save_as, import };
  Purpose purpose = Purpose::open;
  bool visible = false;        ///< shown; the operation's success or Cancel ends it
  bool appearing = false;      ///< open the popup on the next frame
  fs::path folder;             ///< absolute
  FolderListing listing;       ///< of `folder`, read when it changes (and on refresh)
  char name[1024] = "";        ///< typed, or the label of the entry clicked
  fs::path picked;             ///< the entry clicked (its bytes, whatever its label)
  fs::path replace;            ///< save as: the existing file the user was asked about
  std::string error;           ///< the last refusal (an operation's error), shown in the dialog

  const char* title() const {
    return purpose == Purpose::open ? "Open scene###file_dialog"
           : purpose == Purpose::save_as ? "Save scene as###file_dialog"
                                         : "Import model###file_dialog";
  }
  std::vector<std::string> extensions() const {
    if (purpose == Purpose::import) return {".gltf", ".glb"};
    return {".json"};
  }
  void enter(const fs::path& dir) {
    std::error_code ec;
    const fs::path abs = fs::absolute(dir, ec);
    folder = (ec ? dir : abs).lexically_normal();
    // "a/b/.." normalises to "a/": shown, and gone up from, as "a".
    if (!folder.has_filename() && folder != folder.root_path()) folder = folder.parent_path();
    listing = list_folder(folder, extensions());
    picked.clear();
    error.clear();
  }
};

class Editor {
 public:
  Editor(Options options, Scene scene, Player& player, std::vector<ScriptAction> script)
      : opt_(std::move(options)), scene_(std::move(scene)), player_(player), script_(std::move(script)) {
    history_.push_back(scene_to_json(scene_));
    // The scene's enumerations as its reader sees them, whether the file gave them or not (scenes
    // read later, created entities and edits are recorded as they are read).
    (void)parse_scene(history_.front(), opt_.scene);
    take_camera_from_scene();
    update_bounds_speed();
  }

  int run();

 private:
  // Edits: one --set assignment through scene IO's own override path.
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

  // The camera.
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

  // A frame and the UI.
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
  /// a combo's items "KEY=ITEM", the file dialog's rows "dialog:NAME" (README, `click`).
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

std::optional<ecs::Entity> Editor::find(const std::string& name) const {
  std::optional<ecs::Entity> found;
  scene_.world.view<Name>().each([&](ecs::Entity e, const Name& n) {
    if (n.value == name && !found) found = e;
  });
  return found;
}

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

Status Editor::render_viewport(int w, int h) {
  RenderRun run;
  run.frames = 1;
  run.width = w;
  run.height = h;
  // The AOV targets cost fill rate: only for the views that show them.
  run.write_aovs = is_aov_view(view_);
  run.prewarm = prewarm_;
  auto t = render_frames(player_, scene_, run);
  if (!t) return t.error();
  // Nothing drawn while the scene has meshes: the viewport says why it may be.
  const bool was_empty = empty_view_;
  empty_view_ = t->last.stats.draw_calls == 0 && !bounds_.empty();
  if (empty_view_ && !was_empty && !opt_.script.empty())
    std::printf("kaskad edit: nothing in view (the viewport says why it may be)\n");
  prewarm_ = false;
  changed_since_frame_ = false;
  if (view_ == View::colour) {
    last_frame_ = player_.renderer->read_color();
  } else if (view_ == View::probe_faces || view_ == View::sphere_map) {
    const auto& probes = t->last.probes.probes;
    const auto sel = find(selected_);
    const ProbeData::Entry* shown = probes.empty() ? nullptr : &probes.front();
    for (const auto& p : probes)
      if (sel && p.entity == *sel) shown = &p;
    if (view_ == View::probe_faces) {
      CubeMap cube;
      if (shown) cube = player_.renderer->read_probe_cube(shown->job.handle, shown->job.visible);
      last_frame_ = cube.size > 0 ? cube_strip(cube) : player_.renderer->read_color();
    } else {
      SphereMap sphere;
      if (shown) sphere = player_.renderer->read_probe_sphere(shown->job.handle);
      last_frame_ = sphere.size > 0 ? sphere_image(sphere) : player_.renderer->read_color();
    }
  } else if (view_ == View::shadow_map) {
    last_frame_ = grey(player_.renderer->read_shadow_map());
    if (last_frame_.width == 0) last_frame_ = player_.renderer->read_color();  // no shadowed light
  } else if (view_ == View::soft_maps) {
    Image maps = player_.renderer->read_soft_shadow_maps();
    // Moments and evsm's warp exceed 1: scaled so the largest value is white.
    float top = 0.0f;
    for (float v : maps.pixels) top = std::max(top, v);
    if (top > 1.0f)
      for (float& v : maps.pixels) v /= top;
    last_frame_ = maps.pixels.empty() ? player_.renderer->read_color() : grey(maps);
  } else {
    last_frame_ = aov_view(view_, player_.renderer->read_aovs());
  }
  frame_ms_.push_back(float(t->first_frame_ms));
  if (frame_ms_.size() > 120) frame_ms_.erase(frame_ms_.begin());
  {
    const auto& st = t->last.stats;
    char line[384];
    // GPU times from timer queries; on llvmpipe a pass's work can land in the next pass's timer
    // (DESIGN.md, "Facts about these machines"), so they are indications only. The parts of
    // the shadow and probe passes are shown when they ran.
    std::string parts;
    char part[64];
    for (const auto& [name, ms] : {std::pair{"lom", st.lom_gpu_ms}, std::pair{"moments", st.moments_gpu_ms},
                                   std::pair{"prefilter", st.prefilter_gpu_ms}})
      if (ms > 0.0) {
        std::snprintf(part, sizeof part, ", %s %.2f", name, ms);
        parts += part;
      }
    // Four lines whatever their contents, so that the panel below does not move from frame to
    // frame (a narrow panel cuts them; the tooltip has them whole).
    const auto& shaders = player_.renderer->shaders().stats();
    std::snprintf(line, sizeof line,
                  "%.1f ms a frame%s\n"
                  "GPU ms: shadow %.2f, probes %.2f, fwd %.2f%s\n"
                  "%d draws, %zu shadow tris, %d probe faces\n"
                  "programs: %d compiled, %d from cache",
                  t->first_frame_ms, st.visibility_reused ? ", visibility read back" : "",
                  st.shadow_gpu_ms, st.probe_gpu_ms, st.forward_gpu_ms, parts.c_str(),
                  st.draw_calls, st.shadow_triangles, st.probe_faces, shaders.programs_compiled,
                  shaders.cache_hits);
    stats_ = line;
  }
  if (!opt_.script.empty()) {
    // The stats line the editor tests read: which frames captured probe faces and drew layers.
    const auto& st = t->last.stats;
    std::printf("frame %llu: %d probe faces, %d draws, %zu shadow triangles\n",
                static_cast<unsigned long long>(scene_.frames_rendered - 1), st.probe_faces,
                st.draw_calls, st.shadow_triangles);
  }
  if (texture_w_ != last_frame_.width || texture_h_ != last_frame_.height) {
    view_texture_ = gpu::make_texture(GL_TEXTURE_2D);
    glTextureStorage2D(view_texture_.id(), 1, GL_RGBA8, last_frame_.width, last_frame_.height);
    // No mipmaps: the default minifying filter would leave the texture incomplete (black).
    glTextureParameteri(view_texture_.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(view_texture_.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    texture_w_ = last_frame_.width;
    texture_h_ = last_frame_.height;
  }
  const GLenum format = last_frame_.channels == 4 ? GL_RGBA : last_frame_.channels == 3 ? GL_RGB
                                                                                         : GL_RED;
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTextureSubImage2D(view_texture_.id(), 0, 0, 0, last_frame_.width, last_frame_.height, format,
                      GL_FLOAT, last_frame_.pixels.data());
  return {};
}

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
    for (auto f = fields.begin(); f != fields.end(); ++f)
      field(key + "." + f.key(), f.key(), f.value());
}

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

void Editor::draw_ui(int w, int h) {
  widgets_.clear();
  const Layout l = layout_for(w, h, left_w_, right_w_, panels_hidden_);
  const ImGuiWindowFlags fixed = kPanelFlags | ImGuiWindowFlags_NoResize;
  // Panels keep the window's height; only their inner edge moves. H hides them.
  if (!panels_hidden_) entities_panel(w, h, l);

  ImGui::SetNextWindowPos(ImVec2(float(l.view_x), 0));
  ImGui::SetNextWindowSize(ImVec2(float(l.view_w), float(l.view_h)));
  ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(0, 0));
  ImGui::Begin("Viewport", nullptr, fixed | ImGuiWindowFlags_NoDecoration |
                                        ImGuiWindowFlags_NoBringToFrontOnFocus);
  if (view_texture_) {
    // Scaled to fit: the shadow map view is the map's size, its layers stacked.
    const float scale = std::min({1.0f, float(l.view_w) / float(texture_w_),
                                  float(l.view_h) / float(texture_h_)});
    ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<std::uintptr_t>(view_texture_.id())),
                 ImVec2(float(texture_w_) * scale, float(texture_h_) * scale));
  }
  if (panels_hidden_) {
    ImGui::SetCursorPos(ImVec2(6, 4));
    ImGui::TextDisabled("H: panels");
  }
  if (empty_view_ && view_ == View::colour) {
    if (const auto cam = active_camera()) {
      const Camera& c = scene_.world.get<Camera>(*cam);
      char text[256];
      std::snprintf(text, sizeof text,
                    "Nothing in view: the scene may lie outside the camera's near and far planes "
                    "(%g, %g). F frames the selection.",
                    double(c.near), double(c.far));
      // Wrapped to the viewport, on a dark band whatever the clear colour.
      const float wrap = std::max(80.0f, float(l.view_w) - 24.0f);
      const ImVec2 size = ImGui::CalcTextSize(text, nullptr, false, wrap);
      const ImVec2 at = ImVec2(ImGui::GetWindowPos().x + 8.0f, ImGui::GetWindowPos().y + 24.0f);
      ImGui::GetWindowDrawList()->AddRectFilled(ImVec2(at.x - 4.0f, at.y - 3.0f),
                                                ImVec2(at.x + size.x + 4.0f, at.y + size.y + 3.0f),
                                                IM_COL32(20, 20, 20, 210), 3.0f);
      ImGui::SetCursorScreenPos(at);
      ImGui::PushTextWrapPos(ImGui::GetCursorPos().x + wrap);
      ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.4f, 1.0f), "%s", text);
      ImGui::PopTextWrapPos();
    }
  }
  viewport_hovered_ = ImGui::IsWindowHovered();
  ImGui::End();
  ImGui::PopStyleVar();

  if (!panels_hidden_) {
    ImGui::SetNextWindowPos(ImVec2(float(w) - l.right, 0));
    ImGui::SetNextWindowSize(ImVec2(l.right, float(h)));
    ImGui::SetNextWindowSizeConstraints(ImVec2(kMinPanel, float(h)),
                                        ImVec2(max_panel(w), float(h)));
    ImGui::Begin("Inspector", nullptr, kPanelFlags);
    right_w_ = ImGui::GetWindowWidth();
    // Labels keep a fixed share of the panel, so long field names are not clipped.
    ImGui::PushItemWidth(-std::max(120.0f, 0.42f * l.right));
    inspector();
    ImGui::PopItemWidth();
    ImGui::End();
  }

  file_dialog(w, h);

  if (ask_quit_) ImGui::OpenPopup("Unsaved changes");
  if (ImGui::BeginPopupModal("Unsaved changes", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::Text("%s has unsaved changes.", opt_.scene.filename().string().c_str());
    GLFWwindow* window = player_.context->window();
    if (button("Save and quit")) {
      if (Status st = save(opt_.scene); st) glfwSetWindowShouldClose(window, true);
      else report(st.error().to_string());
      ask_quit_ = false;
      ImGui::CloseCurrentPopup();
    }
    ImGui::SameLine();
    if (button("Quit without saving")) {
      saved_ = position_;
      glfwSetWindowShouldClose(window, true);
      ask_quit_ = false;
      ImGui::CloseCurrentPopup();
    }
    ImGui::SameLine();
    if (button("Cancel")) {
      ask_quit_ = false;
      ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
  }
}

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

void Editor::interactive_input(float dt) {
  ImGuiIO& io = ImGui::GetIO();
  if (!ImGui::IsAnyItemActive()) last_drag_key_.clear();
  // The Dear ImGui 1.86 GLFW backend indexes keys by GLFW key code. While the file dialog is up,
  // keys are its own.
  if (!io.WantTextInput && !dialog_.visible) {
    const char* shortcut = nullptr;
    if (io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_Z, false)) shortcut = "ctrl+z";
    if (io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_Y, false)) shortcut = "ctrl+y";
    if (io.KeyCtrl && !io.KeyShift && ImGui::IsKeyPressed(GLFW_KEY_S, false)) shortcut = "ctrl+s";
    if (!io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_F, false)) shortcut = "f";
    if (!io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_H, false)) shortcut = "h";
    if (io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_O, false))
      show_file_dialog(FileDialog::Purpose::open, file_line_);
    if (io.KeyCtrl && io.KeyShift && ImGui::IsKeyPressed(GLFW_KEY_S, false))
      show_file_dialog(FileDialog::Purpose::save_as, file_line_);
    if (shortcut)
      if (Status st = press(shortcut, 0.0f); !st) report(st.error().to_string());
  }
  if (viewport_hovered_ && io.KeyAlt && ImGui::IsMouseDown(ImGuiMouseButton_Left) &&
      (io.MouseDelta.x != 0.0f || io.MouseDelta.y != 0.0f)) {
    if (Status st = orbit(-io.MouseDelta.x * 0.008f, io.MouseDelta.y * 0.008f); !st)
      report(st.error().to_string());
  }
  if (viewport_hovered_ && ImGui::IsMouseDown(ImGuiMouseButton_Right)) {
    const float radians_per_pixel = 0.004f;
    camera_.yaw += io.MouseDelta.x * radians_per_pixel;
    camera_.pitch = std::clamp(camera_.pitch - io.MouseDelta.y * radians_per_pixel, -1.55f, 1.55f);
    const float step = dt * (io.KeyShift ? 4.0f : 1.0f);
    static constexpr std::pair<int, const char*> kFly[] = {
        {GLFW_KEY_W, "w"}, {GLFW_KEY_A, "a"}, {GLFW_KEY_S, "s"},
        {GLFW_KEY_D, "d"}, {GLFW_KEY_Q, "q"}, {GLFW_KEY_E, "e"}};
    for (const auto& [glfw_key, name] : kFly)
      if (ImGui::IsKeyDown(glfw_key)) (void)press(name, step);
    if (io.MouseDelta.x != 0.0f || io.MouseDelta.y != 0.0f) write_camera();
  }
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

int Editor::run() {
  GLFWwindow* window = player_.context->window();
  const std::vector<ScriptAction>& script = script_;
  std::size_t next = 0;
  int frames_left = 0;
  // `input SECONDS`: until then the window takes real input and no script action runs.
  std::optional<std::chrono::steady_clock::time_point> input_until;
  int input_phases = 0;
  auto last = std::chrono::steady_clock::now();
  auto last_reload_check = last;
  for (;;) {
    glfwPollEvents();
    // Shader hot reload, twice a second: a failed compile keeps the last good program and its
    // log (mapped to file:line) stays shown until a later save fixes it.
    if (std::chrono::steady_clock::now() - last_reload_check > std::chrono::milliseconds(500)) {
      last_reload_check = std::chrono::steady_clock::now();
      const auto before = player_.renderer->shaders().stats().reloads;
      for (const auto& e : player_.renderer->shaders().reload_changed()) report(e.to_string());
      if (player_.renderer->shaders().stats().reloads > before) message_.clear();
    }
    bool quit = false;
    if (!opt_.script.empty()) {
      // Script actions run between frames; `frames N` lets N frames render, and a screenshot
      // after a change first renders the frame that shows it.
      if (input_until && std::chrono::steady_clock::now() >= *input_until) {
        input_until.reset();
        std::printf("kaskad edit: input %d ended\n", input_phases);
        std::fflush(stdout);
      }
      while (!input_until && frames_left == 0 && ui_steps_.empty() && next < script.size()) {
        const ScriptAction& a = script[next];
        if (a.kind == ActionKind::screenshot && changed_since_frame_) {
          frames_left = 1;
          break;
        }
        if (Status st = run_action(a, quit); !st) {
          Error e = st.error();
          const std::string where = "line " + std::to_string(a.line);
          std::fprintf(stderr, "kaskad edit: error: %s: %s: %s\n", opt_.script.string().c_str(),
                       where.c_str(), e.to_string().c_str());
          return 1;
        }
        ++next;
        if (a.kind == ActionKind::frames) frames_left = std::stoi(a.args[0]);
        if (a.kind == ActionKind::window_screenshot) frames_left = 1;
        if (a.kind == ActionKind::input) {
          input_until =
              std::chrono::steady_clock::now() + std::chrono::seconds(std::stoi(a.args[0]));
          // Flushed: a test driving the window with real events waits for this line.
          std::printf("kaskad edit: input %d for %s s\n", ++input_phases, a.args[0].c_str());
          std::fflush(stdout);
        }
        if (quit) break;
      }
      if (!quit && !input_until && frames_left == 0 && ui_steps_.empty() && next == script.size()) {
        std::fprintf(stderr, "kaskad edit: error: %s: the script ended without quit or quit!\n",
                     opt_.script.string().c_str());
        return 1;
      }
    } else if (glfwWindowShouldClose(window)) {
      if (!dirty()) quit = true;
      else {
        glfwSetWindowShouldClose(window, false);
        ask_quit_ = true;
      }
    }
    if (quit) break;

    int w = 0, h = 0;
    glfwGetFramebufferSize(window, &w, &h);
    if (w <= 0 || h <= 0) continue;  // minimised
    const Layout l = layout_for(w, h, left_w_, right_w_, panels_hidden_);
    if (l.view_w > 0 && l.view_h > 0) {
      if (Status st = render_viewport(l.view_w, l.view_h); !st) {
        if (!opt_.script.empty()) {
          std::fprintf(stderr, "kaskad edit: error: %s\n", st.error().to_string().c_str());
          return 1;
        }
        // A scene that cannot be drawn (its camera deleted, say) is shown as an error until an
        // edit or an undo fixes it; the window stays.
        if (message_ != st.error().to_string()) report(st.error().to_string());
      }
    }
    if (frames_left > 0) --frames_left;

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    // A script's clicks and typing, between the backend's input and Dear ImGui's frame.
    if (!opt_.script.empty() && !input_until) {
      if (Status st = feed_ui_step(); !st) {
        std::fprintf(stderr, "kaskad edit: error: %s\n", st.error().to_string().c_str());
        return 1;
      }
    }
    ImGui::NewFrame();
    const auto now = std::chrono::steady_clock::now();
    const float dt = std::min(std::chrono::duration<float>(now - last).count(), 0.1f);
    last = now;
    if (opt_.script.empty() || input_until) interactive_input(dt);
    draw_ui(w, h);
    // A number being typed whose field was not drawn again (a click on another entity's row
    // changed the inspector): the click ended the typing, which applies it.
    if (!typed_.first.empty() && !ImGui::IsAnyItemActive()) {
      requests_.emplace_back(typed_.second, false);
      typed_ = {};
    }
    ImGui::Render();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, w, h);
    glClearColor(0.1f, 0.1f, 0.1f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (!window_shot_.empty()) {
      if (Status st = save_image(window_shot_, read_window(w, h)); !st) {
        std::fprintf(stderr, "kaskad edit: error: %s\n", st.error().to_string().c_str());
        return 1;
      }
      std::printf("kaskad edit: wrote %s\n", window_shot_.string().c_str());
      window_shot_.clear();
    }
    player_.context->swap_buffers();

    // Edits from the panels, in the order made; a rejected one shows its error and changes nothing.
    for (const auto& [assignment, merge] : requests_) {
      // A drag the readers refuse at every step says so once.
      if (Status st = edit(assignment, merge); !st) {
        if (st.error().to_string() != message_) report(st.error().to_string());
      } else {
        message_.clear();
      }
    }
    requests_.clear();
    for (const auto& op : operations_) {
      if (Status st = op(); !st) report(st.error().to_string());
      else message_.clear();
    }
    operations_.clear();
  }
  return gpu::exit_status_for_gl_errors("kaskad edit");
}

}  // namespace

int run_edit(const EditOptions& options) {
  // Whole lines: the frame lines (stdout) and errors (stderr) do not cut into each other.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  Options opt = options;
  if (opt.scene.empty()) opt.scene = content_dir() / "scenes" / "default.json";
  std::vector<ScriptAction> script;
  if (!opt.script.empty()) {
    auto parsed = parse_script(opt.script);
    if (!parsed) {
      std::fprintf(stderr, "kaskad edit: error: %s\n", parsed.error().to_string().c_str());
      return 1;
    }
    script = std::move(parsed.value());
  }
  auto scene = load_scene(opt.scene, opt.sets);
  if (!scene) {
    std::fprintf(stderr, "kaskad edit: error: %s\n", scene.error().to_string().c_str());
    return 1;
  }
  if (!gpu::display_available()) {
    std::fprintf(stderr, "kaskad edit: error: no display (DISPLAY or WAYLAND_DISPLAY): the editor "
                         "needs a window; under CI run it with xvfb-run -a\n");
    return 1;
  }
  gpu::ContextOptions copt;
  copt.headless = false;
  copt.window_width = opt.width;
  copt.window_height = opt.height;
  copt.title = "Kaskad editor - " + opt.scene.string();
  auto player = Player::create(copt);
  if (!player) {
    std::fprintf(stderr, "kaskad edit: error: %s\n", player.error().to_string().c_str());
    return 1;
  }
  GLFWwindow* window = player->context->window();
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini dropped into the working directory
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 450 core");
  int status = 0;
  {
    Editor editor(std::move(opt), std::move(scene.value()), player.value(), std::move(script));
    status = editor.run();
  }
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  return status;
}

}  // namespace kaskad::editor
