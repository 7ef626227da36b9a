// `kaskad edit --script FILE`: UI actions replayed one per line, for tests and demos. The language
// is documented in README.md ("Editor: kaskad edit"); parsing is pure (no window, no scene).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "runtime/core/result.h"

namespace kaskad::editor {

enum class ActionKind {
  set, select, camera, key, frames, screenshot, window_screenshot, save, undo, redo, quit, force_quit
};

struct ScriptAction {
  ActionKind kind = ActionKind::frames;
  std::vector<std::string> args;  ///< checked by parse_script: counts and numbers are valid
  int line = 0;                   ///< 1-based line in the script, for messages
};

/// The names `key` takes (the same keys a user presses): w a s d q e (one fly step of 1/30 s),
/// f (frame the selection), ctrl+z, ctrl+y, ctrl+s.
bool is_script_key(const std::string& name);

/// Parses a whole script before anything runs, so a bad line fails before the first frame.
/// Blank lines and lines starting with '#' are skipped. Errors name the file and the line.
Result<std::vector<ScriptAction>> parse_script(const std::filesystem::path& file);

/// parse_script() of text already read (`file` only names it in messages).
Result<std::vector<ScriptAction>> parse_script_text(const std::string& text,
                                                    const std::filesystem::path& file);

}  // namespace kaskad::editor
