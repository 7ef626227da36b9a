// `kaskad edit --script FILE`: UI actions replayed one per line, for tests and demos. The language
// is documented in docs/guide/editor.md ("Scripts"); parsing is pure (no window, no scene).
#pragma once

#include <filesystem>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "runtime/result/result.h"

namespace kaskad::editor {

enum class ActionKind {
  set, choices, choose, select, create, import, remove, duplicate, rename, parent, camera, orbit,
  key, click, ctrl_click, double_click, drag, type, view, frames, screenshot, window_screenshot,
  input, open, save, save_as, undo, redo, quit, force_quit
};

/// What the viewport shows: the colour, or as a debug view one of the frame's AOVs
/// (docs/guide/cli.md, "AOV contract"), the shadow map (its layers stacked), a reflection
/// probe's six cube faces (the selected entity's probe, else the first; +X -X +Y -Y +Z -Z left
/// to right) or its sphere map (S3 eq. (2), made for the current camera; a probe of cube maps
/// has none: the colour shows),
/// or the soft-shadow technique's own maps (lom: each layer's occlusion factors of its first
/// peel; vsm/evsm: the first moment, scaled to its largest value; other techniques have none:
/// the colour shows). position and reflection are AOVs too: the world position spanning the
/// visible positions, S3's C_t where a reflection map shades the surface.
enum class View {
  colour, visibility, cascade, normal, depth, position, reflection, shadow_map, probe_faces,
  sphere_map, soft_maps
};
/// The views' names, in View order: the viewport's combo and the script's `view NAME`.
inline constexpr const char* kViewNames[] = {"colour",     "visibility", "cascade",    "normal",
                                             "depth",      "position",   "reflection", "shadow_map",
                                             "probe_faces", "sphere_map", "soft_maps"};
/// Whether the view is made from the frame's AOVs (docs/guide/cli.md, "AOV contract").
inline bool is_aov_view(View v) {
  return v == View::visibility || v == View::cascade || v == View::normal || v == View::depth ||
         v == View::position || v == View::reflection;
}
inline std::optional<View> view_named(const std::string& name) {
  for (std::size_t i = 0; i < std::size(kViewNames); ++i)
    if (name == kViewNames[i]) return View(i);
  return std::nullopt;
}

struct ScriptAction {
  ActionKind kind = ActionKind::frames;
  std::vector<std::string> args;  ///< checked by parse_script: counts and numbers are valid
  int line = 0;                   ///< 1-based line in the script, for messages
};

/// The names `key` takes (the same keys a user presses): w a s d q e (one fly step of 1/30 s),
/// f (frame the selection), h (hide or show the panels), ctrl+z, ctrl+y, ctrl+s, and enter and
/// escape (to the panels: they end the typing in a field).
inline constexpr const char* kScriptKeys[] = {"w", "a", "s", "d", "q", "e", "f", "h", "ctrl+z",
                                              "ctrl+y", "ctrl+s", "enter", "escape"};
bool is_script_key(const std::string& name);


/// Parses a whole script before anything runs, so a bad line fails before the first frame.
/// Blank lines and lines starting with '#' are skipped. Errors name the file and the line.
Result<std::vector<ScriptAction>> parse_script(const std::filesystem::path& file);

/// parse_script() of text already read (`file` only names it in messages).
Result<std::vector<ScriptAction>> parse_script_text(const std::string& text,
                                                    const std::filesystem::path& file);

}  // namespace kaskad::editor
