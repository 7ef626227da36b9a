#include "runtime/cli/commands.h"

#include <cstdio>
#include <string>
#include <vector>
#include <memory>

#include "runtime/app/envmap_command.h"
#include "runtime/app/playback.h"
#include "runtime/gpu/context.h"
#ifdef KASKAD_HAS_EDITOR
#include "editor/editor.h"
#endif

namespace kaskad::cli {

RunCommand add_envmap_command(CLI::App& cmd) {
  auto o = std::make_shared<EnvmapOptions>();
  cmd.add_option("IN", o->input,
                 "a file, a face pattern sky_*.png or a folder of faces")
      ->type_name("PATH")
      ->required();
  std::vector<std::string> layouts;
  for (EnvLayout l : {EnvLayout::auto_detect, EnvLayout::faces, EnvLayout::horizontal_cross,
                      EnvLayout::vertical_cross, EnvLayout::equirect, EnvLayout::sphere})
    layouts.emplace_back(env_layout_name(l));
  cmd.add_option_function<std::string>(
         "--layout",
         [o](const std::string& name) {
           for (int l = 0; l <= int(EnvLayout::sphere); ++l)
             if (name == env_layout_name(EnvLayout(l))) o->load.layout = EnvLayout(l);
         },
         "the layout of IN (default auto: detected)")
      ->type_name("L")
      ->allow_extra_args(false)
      ->check(CLI::IsMember(layouts));
  cmd.add_flag("--3dsmax", o->load.z_up_3dsmax,
               "the faces were authored in 3ds Max (Z up): convert them to Y up");
  add_integer_option(cmd, "--face-size", o->load.face_size, 1, 8192,
                     "resample the faces to N^2 pixels");
  add_output_option(cmd, "--faces", o->faces_out, OutputKind::faces,
                   "write the six faces: a pattern with * (sky_*.png) or a folder")
      ->type_name("OUT");
  add_output_option(cmd, "--sphere", o->sphere_out, OutputKind::image, "write the S3 sphere map")
      ->type_name("OUT.png");
  add_integer_option(cmd, "--sphere-size", o->sphere_size, 1, 8192,
                     "the sphere map's size in pixels (default: twice the face size)");
  return [o] { return run_envmap(*o); };
}

RunCommand add_play_command(CLI::App& cmd) {
  auto o = std::make_shared<PlayCommandOptions>();
  o->run.headless = !gpu::display_available();
  cmd.add_option("FILE", o->inputs,
                 "playback files, or folders standing for their *.json files; with --merge, "
                 "the shards' output folders")
      ->type_name("FILE|DIR");
  CLI::Option* out = add_output_option(cmd, "--out", o->run.out_dir, OutputKind::folder,
                                      "DIR/<file>/frame_NNNN.png, frames.csv, diffs, "
                                      "DIR/summary.json (default out/play)")
                         ->type_name("DIR");
  cmd.add_flag("--update-goldens", o->run.update_goldens,
               "write the captured frames as the new golden images");
  add_shard_option(cmd, o->run.shard_index, o->run.shard_count,
                   "run files i, i + n, ... (in sorted order)");
  add_jobs_option(cmd, o->jobs, "run N shard processes into DIR/shard-i, then merge their summaries");
  cmd.add_flag("--merge", o->merge,
               "combine the summary.json of the shard folders named into DIR/summary.json");
  add_window_flags(cmd, o->run.headless);
  cmd.footer("Checks the files' expectations (docs/guide/playback.md); exit status 1 when one "
             "failed.");
  return [o, out] {
    o->out_given = out->count() > 0;
    return run_play(*o);
  };
}

RunCommand add_edit_command(CLI::App& cmd) {
#ifdef KASKAD_HAS_EDITOR
  auto o = std::make_shared<editor::EditOptions>();
  cmd.add_option("SCENE", o->scene,
                 "a scene file (.json, .gltf, .glb); default content/scenes/default.json")
      ->type_name("FILE");
  add_value_option(cmd, "--set", o->sets, "an override, as for `kaskad render` (repeatable)")
      ->type_name("KEY=VALUE");
  add_size_option(cmd, o->width, o->height, 1, 16384, "the window size (default 1280x720)");
  add_value_option(cmd, "--script", o->script,
                   "replay actions, one per line (docs/guide/editor.md)")
      ->type_name("FILE");
  cmd.footer("Needs a display (under CI: xvfb-run -a).");
  return [o] { return editor::run_edit(*o); };
#else
  cmd.allow_extras();
  cmd.footer("This build has no editor (configure with -DKASKAD_BUILD_EDITOR=ON).");
  return [] {
    std::fprintf(stderr, "kaskad: this build has no editor (configure with "
                         "-DKASKAD_BUILD_EDITOR=ON: GLFW and Dear ImGui)\n");
    return 2;
  };
#endif
}

}  // namespace kaskad::cli
