// The `kaskad` command line: render scenes headless (or in a window), write images and AOVs,
// and save canonical scene files. Run `kaskad --help`.
#include <algorithm>
#include <cctype>
#include <bit>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "components/camera.h"
#include "components/light.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/name.h"
#include "components/reflector.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "runtime/core/file_io.h"
#include "runtime/assets/env_map.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/scene_io.h"
#include "runtime/app/bench.h"
#include "runtime/app/envmap_command.h"
#include "runtime/app/schema_command.h"
#include "runtime/app/playback.h"
#include "runtime/app/player.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/log.h"
#include "runtime/core/memory.h"
#include "runtime/gpu/context.h"
#ifdef KASKAD_HAS_EDITOR
#include "editor/editor.h"
#endif

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

namespace fs = std::filesystem;
using namespace kaskad;

namespace {

constexpr const char* kUsage = R"(kaskad - real-time shadows and reflections, headless or windowed

usage:
  kaskad render [SCENE] [options]   render a scene (default: content/scenes/default.json)
  kaskad save SCENE -o OUT.json [--set key=value]...
                                    write the canonical scene file (after overrides)
  kaskad variants [SCENE] [--set key=value]... [--aov]
                                    list the shader variants (pass, key, defines) the scene needs
  kaskad bench [SCENE]... [--sweep SPEC] [--out DIR] [--frames N] [--size WxH] [--no-chart]
               [--stability-frames N] [--shard i/n]
  kaskad bench --merge SHARD_OUT_DIR... [--out DIR] [--no-chart]
                                    sweep settings, write DIR/bench.csv and one speed-vs-accuracy
                                    chart per scene (default sweep: see README; --sweep soft:
                                    the soft-shadow techniques and kernels); flicker at fixed
                                    points over an N-frame camera path (default 16, 0 = off)
  kaskad envmap IN [--layout L] [--3dsmax] [--face-size N] [--faces OUT] [--sphere OUT.png]
                [--sphere-size N]
                                    load an environment map (IN: a file, a face pattern sky_*.png
                                    or a folder of faces; L: auto, faces, horizontal_cross,
                                    vertical_cross, equirect, sphere), print what was found, write
                                    its faces (OUT: a pattern with * or a folder) or S3 sphere map
  kaskad play FILE|DIR... [--out DIR] [--update-goldens] [--shard i/n | --jobs N]
                                    replay playback files (camera keys, timeline, captures) and
                                    check their expectations (README "Scene playback"); writes
                                    DIR/<file>/frame_NNNN.png, frames.csv, diffs, DIR/summary.json
  kaskad edit [SCENE] [--set key=value]... [--size WxH] [--script FILE]
                                    the editor: a window with an entity list, inspectors, a
                                    fly camera, undo and saving; --script replays actions
                                    (README "Editor: kaskad edit"); needs a display (xvfb-run -a)
  kaskad info [SCENE] [--set K=V]   print the OpenGL context kaskad gets on this machine; with
                                    a SCENE, its entities instead (name, parent, components): the
                                    names --set addresses, a glTF file's own nodes included

render options:
  -o, --output FILE      colour image (PNG, JPEG, EXR, ...); default out/<scene>.png
  --size WxH             output size in pixels (default: the scene's render.width/height)
  --frames N             frames to render; times are the median of frames 2..N (default 10)
  --set KEY=VALUE        override a setting or component field, e.g. shadow.map_size=4096,
                         sun.light.intensity=3, camera.camera.fov_y_deg=40 (repeatable)
  --aov FILE.exr         write the AOVs of the last frame (P, N, Z, visibility, mask, cascade)
  --shadow-map FILE      write the shadow map depth of the last frame
  --probe-maps DIR       write each reflection probe's visible cube faces (NAME_px.png ...
                         NAME_nz.png) and, for sphere probes, NAME_sphere.png into DIR
  --reflection-reference FILE.exr
                         ray-traced reflected radiance C_t of every pixel (README "Environment maps")
  --env PATH             environment map for the reflection reference's misses (any layout)
  --shadow-reference FILE.exr
                         the ray-traced visibility of the light the visibility AOV shows (area
                         lights sampled), the AOV's, and their difference, per pixel; prints
                         RMSE and MAE over the receivers (README "Soft shadows")
  --headless             never open a window (default when there is no display)
  --window               open a window even if --headless would be the default
  -v, --verbose          debug logging (GL debug messages of every severity)
)";

struct Args {
  std::string command;
  std::string scene;
  std::vector<std::string> more_scenes;  ///< bench: every SCENE after the first
  int shard_index = 0, shard_count = 1;  ///< bench --shard i/n
  bool merge = false;                    ///< bench --merge: the SCENEs are shard folders
  std::string sweep;
  std::string out_dir;
  bool chart = true;
  int stability_frames = -1;  ///< bench: -1 = default
  std::string output;
  std::string aov;
  std::string shadow_map;
  std::string probe_maps;
  std::string reflection_reference;  ///< render: reference EXR to write
  std::string shadow_reference;      ///< render: shadow visibility reference EXR to write
  std::string env;                   ///< render: environment map of the reflection reference
  std::vector<std::string> sets;
  int width = 0, height = 0, frames = 10;
  bool headless = !gpu::display_available();
};

[[noreturn]] void usage_error(const std::string& msg) {
  std::fprintf(stderr, "kaskad: %s\n(run `kaskad --help` for usage)\n", msg.c_str());
  std::exit(2);
}

int parse_int(const std::string& flag, const std::string& v, int lo, int hi) {
  try {
    std::size_t used = 0;
    const long n = std::stol(v, &used);
    if (used != v.size() || n < lo || n > hi) throw std::out_of_range(v);
    return int(n);
  } catch (const std::exception&) {
    usage_error(flag + " expects an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                "], got '" + v + "'");
  }
}

Args parse_args(int argc, char** argv) {
  Args a;
  if (argc < 2) usage_error("missing command");
  a.command = argv[1];
  if (a.command == "--help" || a.command == "-h" || a.command == "help") {
    std::fputs(kUsage, stdout);
    std::exit(0);
  }
  if (a.command != "render" && a.command != "save" && a.command != "info" &&
      a.command != "variants" && a.command != "bench")
    usage_error("unknown command '" + a.command + "'");
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage_error(arg + " needs a value");
      // `--set -o x.png`: the option's value is missing, not "-o" (a negative number is left to
      // the value's own check; a file named -x is ./-x).
      const std::string v = argv[i + 1];
      if (v.size() > 1 && v[0] == '-' && !std::isdigit(static_cast<unsigned char>(v[1])))
        usage_error(arg + " needs a value, got the option '" + v + "'");
      return argv[++i];
    };
    if (arg == "-h" || arg == "--help") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (arg == "-o" || arg == "--output") {
      a.output = value();
    } else if (arg == "--aov" && a.command == "variants") {
      a.aov = "yes";
    } else if (arg == "--aov") {
      a.aov = value();
    } else if (arg == "--shadow-map") {
      a.shadow_map = value();
    } else if (arg == "--probe-maps") {
      a.probe_maps = value();
    } else if (arg == "--reflection-reference") {
      a.reflection_reference = value();
    } else if (arg == "--env") {
      a.env = value();
    } else if (arg == "--shadow-reference" && a.command == "render") {
      a.shadow_reference = value();
    } else if (arg == "--sweep" && a.command == "bench") {
      a.sweep = value();
      if (a.sweep.empty())
        usage_error("--sweep needs a sweep (e.g. shadow.map_size=1024,2048, or soft); without "
                    "--sweep, bench runs the default one");
    } else if (arg == "--out" && a.command == "bench") {
      a.out_dir = value();
    } else if ((arg == "--out" || arg == "--sweep") && a.command == "render") {
      usage_error(arg + " is a bench option; kaskad render writes its image to -o FILE");
    } else if (arg == "--stability-frames" && a.command == "bench") {
      a.stability_frames = parse_int(arg, value(), 0, 10000);
    } else if (arg == "--shard" && a.command == "bench") {
      const std::string v = value();
      const auto slash = v.find('/');
      if (slash == std::string::npos) usage_error("--shard expects i/n, e.g. 0/4, got '" + v + "'");
      a.shard_count = parse_int("--shard n", v.substr(slash + 1), 1, 100000);
      a.shard_index = parse_int("--shard i", v.substr(0, slash), 0, a.shard_count - 1);
    } else if (arg == "--merge" && a.command == "bench") {
      a.merge = true;
    } else if (arg == "--no-chart" && a.command == "bench") {
      a.chart = false;
    } else if (arg == "--set") {
      a.sets.push_back(value());
    } else if (arg == "--frames") {
      a.frames = parse_int(arg, value(), 1, 100000);
    } else if (arg == "--size") {
      const std::string v = value();
      const auto x = v.find('x');
      if (x == std::string::npos) usage_error("--size expects WxH, e.g. 1280x720, got '" + v + "'");
      a.width = parse_int("--size width", v.substr(0, x), 1, 16384);
      a.height = parse_int("--size height", v.substr(x + 1), 1, 16384);
    } else if (arg == "--headless") {
      a.headless = true;
    } else if (arg == "--window") {
      a.headless = false;
    } else if (arg == "-v" || arg == "--verbose") {
      log::set_level(log::Level::debug);
    } else if (!arg.empty() && arg[0] == '-') {
      usage_error("unknown option '" + arg + "'");
    } else if (a.scene.empty()) {
      a.scene = arg;
    } else if (a.command == "bench") {
      a.more_scenes.push_back(arg);
    } else {
      usage_error("unexpected argument '" + arg + "'");
    }
  }
  return a;
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

int fail(const Error& e) {
  std::fprintf(stderr, "kaskad: error: %s\n", e.to_string().c_str());
  return 1;
}

int run_info(const Args& a) {
  if (a.scene.empty() && !a.sets.empty())
    usage_error("info --set needs a SCENE (without one, info prints the OpenGL context)");
  if (!a.scene.empty()) {
    auto scene = load_scene(a.scene, a.sets);
    if (!scene) return fail(scene.error());
    const ecs::World& w = scene->world;
    std::vector<ecs::Entity> all;
    w.view<Transform>().each([&](ecs::Entity e, const Transform&) { all.push_back(e); });
    std::sort(all.begin(), all.end(), [](ecs::Entity x, ecs::Entity y) { return x.index < y.index; });
    std::printf("%s: %zu entities (--set NAME.SECTION.FIELD=VALUE addresses them by name)\n",
                a.scene.c_str(), all.size());
    for (ecs::Entity e : all) {
      const auto* n = w.try_get<Name>(e);
      std::string parts;
      if (w.has<Light>(e)) parts += " light";
      if (w.has<ShadowSettings>(e)) parts += " shadow";
      if (w.has<Camera>(e)) parts += " camera";
      if (w.has<MeshRenderer>(e)) parts += " renderer";
      if (w.has<Reflector>(e)) parts += " reflector";
      if (w.has<ModelRef>(e)) parts += " model";
      if (w.has<PrimitiveMesh>(e)) parts += " primitive";
      const Transform& t = w.get<Transform>(e);
      const auto* pn = t.parent.valid() && w.alive(t.parent) ? w.try_get<Name>(t.parent) : nullptr;
      std::printf("  %-32s transform%s%s%s%s\n", n ? n->value.c_str() : "(unnamed)", parts.c_str(),
                  pn ? "  (parent " : "", pn ? pn->value.c_str() : "", pn ? ")" : "");
    }
    return 0;
  }
  gpu::ContextOptions opt;
  opt.headless = a.headless;
  auto ctx = gpu::Context::create(opt);
  if (!ctx) return fail(ctx.error());
  std::printf("platform: %s\nOpenGL:   %s\n", (*ctx)->platform().c_str(),
              (*ctx)->description().c_str());
  return 0;
}

int run_save(const Args& a) {
  if (a.scene.empty()) usage_error("save needs a SCENE");
  if (a.output.empty()) usage_error("save needs -o OUT.json");
  if (lowercase_extension(a.output) != ".json")
    usage_error("save writes a scene file: -o needs a .json path, got '" + a.output + "'");
  auto scene = read_scene(a.scene, a.sets);
  if (!scene) return fail(scene.error());
  if (auto st = save_scene(a.output, *scene); !st) return fail(st.error());
  std::printf("wrote %s\n", a.output.c_str());
  return 0;
}

int run_variants(const Args& a) {
  const fs::path scene_path =
      a.scene.empty() ? content_dir() / "scenes" / "default.json" : fs::path(a.scene);
  auto scene = load_scene(scene_path, a.sets);
  if (!scene) return fail(scene.error());
  auto manifest = render::FeatureManifest::load(content_dir() / "shaders" / "features.json");
  if (!manifest) return fail(manifest.error());
  FrameContext ctx;
  ctx.width = scene->render.width;
  ctx.height = scene->render.height;
  ctx.write_aovs = !a.aov.empty();
  const auto requests = render::required_programs(plan_frame(*scene, ctx));
  std::printf("%s: %zu programs (%s AOVs)\n", scene_path.string().c_str(), requests.size(),
              ctx.write_aovs ? "with" : "without");
  for (const auto& r : requests) {
    std::printf("\n%-7s key 0x%012llx  %s\n", render::pass_name(r.pass),
                static_cast<unsigned long long>(r.key.bits()), manifest->describe(r.key).c_str());
    std::string defs;
    for (const auto& f : manifest->features())
      defs += " " + f.define + "=" + std::to_string(manifest->value(f, r.key));
    std::printf("        defines:%s\n", defs.c_str());
  }
  return 0;
}

int run_bench_command(const Args& a, bool frames_given) {
  BenchOptions o;
  if (!a.scene.empty()) o.scenes.push_back(a.scene);
  for (const auto& s : a.more_scenes) o.scenes.push_back(s);
  o.sweep = a.sweep;
  if (!a.out_dir.empty()) o.out_dir = a.out_dir;
  if (frames_given) o.frames = a.frames;
  if (a.width > 0) {
    o.width = a.width;
    o.height = a.height;
  }
  o.chart = a.chart;
  if (a.stability_frames >= 0) o.stability_frames = a.stability_frames;
  o.shard_index = a.shard_index;
  o.shard_count = a.shard_count;
  if (a.merge) {
    if (o.scenes.empty()) usage_error("bench --merge needs the shards' --out folders");
    if (auto st = merge_bench(o.scenes, o.out_dir, o.chart); !st) return fail(st.error());
    return 0;
  }
  if (auto st = run_bench(o); !st) return fail(st.error());
  return 0;
}

// The share of a map_size^2 layer that `r` (FrameStats::layer_rect) covers, in percent.
double rect_percent(const glm::ivec4& r, int map_size) {
  if (r.x >= r.z || r.y >= r.w) return 0.0;
  return 100.0 * double(r.z - r.x) * double(r.w - r.y) / (double(map_size) * double(map_size));
}

// Per-layer stats of one shadow view: world units per texel, casters drawn, their triangles, the
// share of the layer the depth pass draws (its read rectangle),
// receiver pixels (AOV pixels shaded from that cascade, for the view the AOV shows; 0 without
// AOVs or for the other views).
void print_layer_table(const render::FrameStats& st, const ShadowData& sh, bool shown_in_aov) {
  std::printf("          layer  m/texel   casters  triangles  drawn  receiver px\n");
  for (int i = 0; i < sh.cascade_count; ++i) {
    const auto c = std::size_t(i), l = std::size_t(sh.first_layer + i);
    std::printf("          %-5zu  %-8.3g  %-7d  %-9zu  %4.0f%%  %zu%s\n", l,
                double(st.layer_texel_size[l]), st.layer_casters[l], st.layer_triangles[l],
                rect_percent(st.layer_rect[l], sh.settings.map_size),
                shown_in_aov ? st.cascade_receiver_pixels[c] : std::size_t(0),
                sh.skipped[c] ? "  (skipped)"
                : (sh.held >> i) & 1u ? "  (held: far_cascade_interval)"
                                      : "");
  }
}

/// A folder the user named for outputs (--probe-maps DIR): made when missing, but only that one
/// level; its parent must exist.
Status make_named_folder(const fs::path& dir) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) {
    const fs::path parent = folder_of(dir);
    if (!fs::is_directory(parent, ec))
      return Error{dir.string(), "", "cannot make this folder: '" + parent.string() +
                                         "' does not exist (kaskad makes only the folder named)"};
    fs::create_directory(dir, ec);
    if (ec) return Error{dir.string(), "", "cannot make this folder: " + ec.message()};
  }
  return check_output_folder(dir);
}

/// Every output of `kaskad render`, checked before the scene is loaded or a frame rendered:
/// writable, not a folder, a format we can write. The default colour output out/<scene>.png
/// (README) is the one folder made for the user.
Status check_render_outputs(const Args& a, const fs::path& out) {
  std::error_code ec;
  if (a.output.empty() && !fs::exists(out.parent_path(), ec)) {
    // out/ is made just before writing; here only that it can be made.
    KASKAD_TRY(check_output_path(out.parent_path()));
  } else {
    KASKAD_TRY(check_image_output(out));
  }
  // The data outputs hold named float channels (AOVs, references' errors, depths): OpenEXR only,
  // where another format would drop channels or clip them to 8 bits.
  const std::pair<const char*, const std::string*> data_outputs[] = {
      {"--aov", &a.aov},
      {"--shadow-map", &a.shadow_map},
      {"--reflection-reference", &a.reflection_reference},
      {"--shadow-reference", &a.shadow_reference}};
  std::vector<std::pair<std::string, fs::path>> named = {{"-o", out}};
  for (const auto& [flag, file] : data_outputs) {
    if (file->empty()) continue;
    KASKAD_TRY(check_image_output(*file));
    if (lowercase_extension(*file) != ".exr")
      return Error{*file, "", std::string(flag) +
                                  " writes named float channels: it needs an OpenEXR file "
                                  "(.exr), which other formats would cut to 8 bits or fewer "
                                  "channels"};
    named.emplace_back(flag, *file);
  }
  // Two outputs of one path: the second would replace the first.
  for (std::size_t i = 0; i < named.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (fs::weakly_canonical(named[i].second, ec) == fs::weakly_canonical(named[j].second, ec))
        return Error{named[i].second.string(), "",
                     named[j].first + " and " + named[i].first +
                         " name the same file: one would replace the other"};
  if (!a.probe_maps.empty()) KASKAD_TRY(make_named_folder(a.probe_maps));
  return {};
}

int run_render(Args a) {
  const fs::path scene_path =
      a.scene.empty() ? content_dir() / "scenes" / "default.json" : fs::path(a.scene);
  const fs::path out = a.output.empty() ? fs::path("out") / (scene_path.stem().string() + ".png")
                                        : fs::path(a.output);
  if (!a.env.empty() && a.reflection_reference.empty())
    usage_error("--env is the environment of --reflection-reference; a scene's own is "
                "render.environment (--set render.environment=FILE)");
  if (auto st = check_render_outputs(a, out); !st) return fail(st.error());
  if (!a.env.empty()) {
    // An input read only after the frames: checked before them, so a bad map fails before any
    // output is written.
    if (auto env = load_cube_map(a.env); !env) return fail(env.error());
  }
  if (a.width > 0) {
    a.sets.push_back("render.width=" + std::to_string(a.width));
    a.sets.push_back("render.height=" + std::to_string(a.height));
  }
  auto t0 = std::chrono::steady_clock::now();
  auto scene = load_scene(scene_path, a.sets);
  if (!scene) return fail(scene.error());
  const double load_ms = ms_since(t0);
  std::size_t triangles = 0;
  for (const auto& m : scene->assets.meshes) triangles += m.triangle_count();
  std::printf("scene     %s: %zu entities, %zu meshes, %zu triangles in assets (load %.1f ms)\n",
              scene_path.string().c_str(), scene->world.size(), scene->assets.meshes.size(),
              triangles, load_ms);

  gpu::ContextOptions opt;
  opt.headless = a.headless;
  opt.window_width = scene->render.width;
  opt.window_height = scene->render.height;
  t0 = std::chrono::steady_clock::now();
  auto player = Player::create(opt);
  if (!player) return fail(player.error());
  std::printf("context   %s, %s (%.1f ms)\n", player->context->platform().c_str(),
              player->context->description().c_str(), ms_since(t0));

  RenderRun run;
  run.frames = a.frames;
  // The AOV targets cost fill rate: only when asked for.
  run.write_aovs =
      !a.aov.empty() || !a.reflection_reference.empty() || !a.shadow_reference.empty();
  auto timings = render_frames(*player, *scene, run);
  if (!timings) return fail(timings.error());
  if (!player->context->headless()) {
    int w = 0, h = 0;
    glfwGetFramebufferSize(player->context->window(), &w, &h);
    player->renderer->present(w, h);
    player->context->swap_buffers();
  }
  const auto& st = timings->last.stats;
  const std::string msaa =
      st.msaa_samples > 1 ? ", " + std::to_string(st.msaa_samples) + "x MSAA" : std::string();
  if (a.frames > 1) {
    std::printf("frames    %d at %dx%d%s: first %.1f ms, median %.2f ms (frames 2..%d)\n",
                a.frames, scene->render.width, scene->render.height, msaa.c_str(),
                timings->first_frame_ms, timings->median_ms(), a.frames);
  } else {  // the first frame alone (it compiles programs and uploads assets): no median
    std::printf("frames    1 at %dx%d%s: %.1f ms\n", scene->render.width, scene->render.height,
                msaa.c_str(), timings->first_frame_ms);
  }
  std::printf(
      "last      %d objects in %d draw calls of %d meshes (%d outside the view, "
      "culled), %zu triangles; shadow pass %d caster instances in %d draw calls of %d "
      "meshes%s, %zu triangles; GPU shadow %.2f ms, forward %.2f ms; %d program and %d "
      "material switches\n",
      st.instances, st.draw_calls, st.mesh_draws, st.frustum_culled, st.triangles,
      st.shadow_instances, st.shadow_draw_calls, st.shadow_mesh_draws,
      st.shadow_layers > 0 && st.shadow_layers_rendered == 0 ? " (every layer kept its depth)"
                                                             : "",
      st.shadow_triangles,
      st.shadow_gpu_ms, st.forward_gpu_ms, st.program_switches, st.material_switches);
  if (st.probe_gpu_ms > 0 || st.lom_gpu_ms > 0 || st.moments_gpu_ms > 0)
    std::printf("          GPU parts: probe captures %.2f ms (prefiltering %.2f ms of it), lom "
                "%.2f ms and moments %.2f ms (of the shadow pass's)\n",
                st.probe_gpu_ms, st.prefilter_gpu_ms, st.lom_gpu_ms, st.moments_gpu_ms);
  if (st.shadow_layers > 0) {
    const int drawn = std::popcount(st.shadow_layers_rendered);
    std::printf("          shadow layers re-rendered in the last frame: %d of %d", drawn,
                st.shadow_layers);
    if (drawn > 0 && drawn < st.shadow_layers) {
      std::printf(" (");
      for (int l = 0, n = 0; l < st.shadow_layers; ++l)
        if (st.shadow_layers_rendered & (1u << l)) std::printf(n++ ? " %d" : "%d", l);
      std::printf(")");
    }
    std::printf("%s\n", drawn < st.shadow_layers ? "; the others kept their depth (same matrix "
                                                    "and casters)" : "");
    if (st.shadow_layers_scrolled != 0)
      std::printf("          shadow layers scrolled: %d (moved by whole texels, they kept their "
                  "depth and drew only what came into view; render.shadow_scroll)\n",
                  std::popcount(st.shadow_layers_scrolled));
    if (st.shadow_texels_drawn > 0)
      std::printf("          shadow texels drawn: %.2f M\n", double(st.shadow_texels_drawn) * 1e-6);
    if (st.shadow_rect_culled > 0)
      std::printf("          %d caster instances left out of layers drawn in part: their boxes "
                  "miss the texels drawn (shadow.scissor_to_receivers)\n",
                  st.shadow_rect_culled);
    if (st.visibility_reused)
      std::printf("          shadow visibility read back from the frame before (nothing it "
                  "depends on changed; render.visibility_cache)\n");
    // The first shadowed light's technique is every view's (for_each_shared_field()).
    if (!timings->last.shadows.empty() &&
        timings->last.shadows.front().settings.technique == ShadowTechnique::lom)
      std::printf("          lom: %d of %d layers peeled and their occlusion recomputed; %lld "
                  "texels with more light-facing surfaces than lom_layers (read as umbra "
                  "below them)\n",
                  std::popcount(st.lom_layers_computed), st.shadow_layers,
                  static_cast<long long>(st.lom_overflow_texels));
  }
  const std::vector<ShadowData>& views = timings->last.shadows;
  const std::size_t aov_view = std::size_t(aov_shadow_index(*scene, views.size()));
  for (std::size_t k = 0; k < views.size(); ++k) {
    const ShadowData& sh = views[k];
    const auto* name = scene->world.try_get<Name>(sh.light);
    std::printf("shadow    view %zu: light %s (entity %u), layers %d..%d of the %d^2 map%s\n", k,
                name ? ("'" + name->value + "'").c_str() : "-", sh.light.index, sh.first_layer,
                sh.first_layer + sh.cascade_count - 1, sh.settings.map_size,
                views.size() > 1 && k == aov_view ? " (the AOV shows it)" : "");
    if (sh.projection != ShadowProjection::ortho) {
      const char* kinds[] = {"", "spot or area: 1 perspective map", "point: 6 cube faces",
                             "point: 2 paraboloid hemispheres"};
      std::printf("          %s, near %.3g m, far %.3g m from the light\n", kinds[int(sh.projection)],
                  double(sh.splits[0]), double(sh.splits[1]));
    } else {
      const char* fits[] = {"crop", "stable", "scene"};
      std::printf("          %d cascades (%s fit)", sh.cascade_count, fits[int(sh.settings.fit_mode)]);
      if (sh.settings.fit_mode != FitMode::scene) {
        std::printf("; splits");
        for (int i = 0; i <= sh.cascade_count; ++i)
          std::printf(" %.3g", double(sh.splits[std::size_t(i)]));
        std::printf(" m; the visible receivers' depths");
        if (sh.near_used > sh.near_requested)
          std::printf(" moved the first split out from %.3g m", double(sh.near_requested));
        if (sh.far_used < sh.far_requested)
          std::printf("%s pulled the last split in from %.3g m",
                      sh.near_used > sh.near_requested ? " and" : "", double(sh.far_requested));
        if (!(sh.near_used > sh.near_requested) && !(sh.far_used < sh.far_requested))
          std::printf(" fill [camera near, %.3g m]", double(sh.far_requested));
      }
      std::printf("\n");
    }
    print_layer_table(st, sh, k == aov_view);
  }
  if (const ProbeData& pd = timings->last.probes; !pd.probes.empty()) {
    std::printf("probes    %zu reflectors: %llu captures, %llu faces since load; last frame %d "
                "faces, %d objects in %d draw calls into them (%d culled by the face frusta), "
                "%d cubes prefiltered for the pbr model (%d faces)\n",
                pd.probes.size(), static_cast<unsigned long long>(pd.captures_total),
                static_cast<unsigned long long>(pd.faces_total), st.probe_faces,
                st.probe_instances, st.probe_draw_calls, st.probe_culled, st.probe_prefilters,
                st.probe_prefilter_faces);
    if (timings->first_probe_rounds > 1)
      std::printf("          first frame: %d capture rounds (render.probe_bounces), %d faces\n",
                  timings->first_probe_rounds, timings->first_probe_faces);
  }
  std::printf("shaders   %d compiled, %d from the binary cache, %.1f ms (prewarm %.1f ms); "
              "%d compiled after the first frame\n",
              st.shaders.programs_compiled, st.shaders.cache_hits, st.shaders.compile_ms,
              timings->prewarm_ms, st.shaders.runtime_compiles);

  // A frame with GL errors is not written over a previous good image.
  if (gpu::debug_error_count() > 0)
    return gpu::exit_status_for_gl_errors("kaskad", "; no output written");
  if (a.output.empty()) {
    std::error_code ec;
    fs::create_directory(out.parent_path(), ec);  // the documented default, out/<scene>.png
  }
  if (auto s = save_image(out, player->renderer->read_color()); !s) return fail(s.error());
  std::printf("wrote     %s\n", fs::absolute(out).string().c_str());
  if (!a.aov.empty()) {
    if (auto s = save_image(a.aov, player->renderer->read_aovs()); !s) return fail(s.error());
    std::printf("wrote     %s (AOVs: P.X P.Y P.Z N.X N.Y N.Z Z visibility mask cascade)\n",
                fs::absolute(a.aov).string().c_str());
  }
  if (!a.reflection_reference.empty()) {
    if (auto s = write_reflection_reference(*scene, player->renderer->read_aovs(),
                                            timings->last.camera.position, a.env,
                                            a.reflection_reference);
        !s)
      return fail(s.error());
  }
  if (!a.shadow_reference.empty()) {
    const std::vector<ShadowData>& shadows = timings->last.shadows;
    const ecs::Entity light =
        shadows.empty() ? ecs::kNullEntity
                        : shadows[std::size_t(aov_shadow_index(*scene, shadows.size()))].light;
    if (!light.valid())
      return fail(Error{"", "--shadow-reference", "the scene has no shadowed light"});
    if (auto s = write_shadow_reference(*scene, player->renderer->read_aovs(), light,
                                        a.shadow_reference);
        !s)
      return fail(s.error());
  }
  if (!a.shadow_map.empty()) {
    if (auto s = save_image(a.shadow_map, player->renderer->read_shadow_map()); !s)
      return fail(s.error());
    std::printf("wrote     %s (shadow map depth)\n", fs::absolute(a.shadow_map).string().c_str());
  }
  if (!a.probe_maps.empty()) {
    for (const ProbeData::Entry& p : timings->last.probes.probes) {
      const Name* name = scene->world.try_get<Name>(p.entity);
      const std::string stem =
          name ? name->value : "probe" + std::to_string(p.entity.index);
      const fs::path dir(a.probe_maps);
      const CubeMap cube = player->renderer->read_probe_cube(p.job.handle, p.job.visible);
      if (cube.size == 0) continue;
      if (auto s = save_cube_faces(cube, dir / (stem + "_*.png")); !s) return fail(s.error());
      std::printf("wrote     %s (probe faces)\n", fs::absolute(dir / (stem + "_*.png")).string().c_str());
      if (p.sphere) {
        const fs::path file = dir / (stem + "_sphere.png");
        if (auto s = save_sphere_map(player->renderer->read_probe_sphere(p.job.handle), file); !s)
          return fail(s.error());
        std::printf("wrote     %s (sphere map)\n", fs::absolute(file).string().c_str());
      }
    }
  }
  return gpu::exit_status_for_gl_errors("kaskad");
}

}  // namespace

int run_command(int argc, char** argv) {
  if (argc >= 2 && std::strcmp(argv[1], "envmap") == 0) return run_envmap_command(argc, argv);
  if (argc >= 2 && std::strcmp(argv[1], "play") == 0) return run_play_command(argc, argv);
  if (argc >= 2 && std::strcmp(argv[1], "schema") == 0) {
    std::filesystem::path out = content_dir().parent_path() / "docs" / "reference";
    bool check = false;
    for (int i = 2; i < argc; ++i) {
      if (std::strcmp(argv[i], "--check") == 0) check = true;
      else if (std::strcmp(argv[i], "--out") == 0 && i + 1 < argc) out = argv[++i];
      else usage_error(std::string("schema: unknown option '") + argv[i] + "'");
    }
    return run_schema_command(out, check);
  }
  if (argc >= 2 && std::strcmp(argv[1], "edit") == 0) {
#ifdef KASKAD_HAS_EDITOR
    return editor::run_edit_command(argc, argv);
#else
    std::fprintf(stderr, "kaskad: this build has no editor (configure with "
                         "-DKASKAD_BUILD_EDITOR=ON: GLFW and Dear ImGui)\n");
    return 2;
#endif
  }
  const Args a = parse_args(argc, argv);
  if (a.command == "info") return run_info(a);
  if (a.command == "save") return run_save(a);
  if (a.command == "variants") return run_variants(a);
  if (a.command == "bench") {
    bool frames_given = false;
    for (int i = 2; i < argc; ++i) frames_given |= std::strcmp(argv[i], "--frames") == 0;
    return run_bench_command(a, frames_given);
  }
  return run_render(a);
}

int main(int argc, char** argv) {
  keep_freed_memory();  // frames reuse their memory instead of faulting it in again
  // A file-size limit (`ulimit -f`) or a full disk must fail the write with an error, not kill
  // the process: write() then returns EFBIG and the atomic writer keeps the previous file.
  std::signal(SIGXFSZ, SIG_IGN);
  // The last line of defence (README "Bad input"): every reader turns library exceptions into
  // content errors; anything that still escapes is an error exit with a message, never an abort.
  try {
    return run_command(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "kaskad: error: out of memory\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kaskad: error: unexpected failure: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "kaskad: error: unexpected failure (unknown exception)\n");
  }
  return 1;
}
