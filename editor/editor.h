// `kaskad edit`: the windowed editor (GLFW + Dear ImGui) over the same runtime, frame loop and
// renderer as the headless player. Controls and the script language: docs/guide/editor.md
// ("Controls", "Scripts").
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kaskad::editor {

/// What `kaskad edit` was asked for (runtime/cli/ reads it from the command line).
struct EditOptions {
  std::filesystem::path scene;    ///< .json, .gltf or .glb; empty: content/scenes/default.json
  std::vector<std::string> sets;  ///< overrides, as for `kaskad render --set`
  int width = 1280, height = 720;  ///< the window's size in pixels, each in [1, 16384]
  std::filesystem::path script;   ///< actions to replay, one per line; empty: interactive
};

/// `kaskad edit`: opens the editor on the scene. Returns the process exit status: 0 done, 1 an
/// error (scene, script line, no display, GL errors).
int run_edit(const EditOptions& options);

}  // namespace kaskad::editor
