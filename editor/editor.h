// `kaskad edit`: the windowed editor (GLFW + Dear ImGui) over the same runtime, frame loop and
// renderer as the headless player. Controls and the script language: README.md ("Editor").
#pragma once

namespace kaskad::editor {

/// `kaskad edit [SCENE] [--set k=v]... [--size WxH] [--script FILE]`; argv[1] is "edit".
/// Returns the process exit status: 0 done, 1 an error (scene, script line, GL errors), 2 usage.
int run_edit_command(int argc, char** argv);

}  // namespace kaskad::editor
