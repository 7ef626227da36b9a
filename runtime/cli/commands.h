// The commands whose work lives in kaskad::app (play, envmap) and kaskad::editor (edit): their
// options, read into the option structs those layers run (cli::Command, runtime/cli/options.h).
#pragma once

#include "runtime/cli/options.h"

namespace kaskad::cli {

/// `kaskad envmap IN [options]`: run_envmap() (runtime/app/envmap_command.h).
RunCommand add_envmap_command(CLI::App& cmd);

/// `kaskad play FILE|DIR... [options]`: run_play() (runtime/app/playback.h).
RunCommand add_play_command(CLI::App& cmd);

/// `kaskad edit [SCENE] [options]`: editor::run_edit() (editor/editor.h); in a build without the
/// editor, a usage error that says so.
RunCommand add_edit_command(CLI::App& cmd);

}  // namespace kaskad::cli
