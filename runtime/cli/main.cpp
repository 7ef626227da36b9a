// The `kaskad` command line: render scenes headless (or in a window), write images and AOVs,
// and save canonical scene files. Run `kaskad --help`.
#include <algorithm>
#include <bit>
#include <chrono>
#include <cctype>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "components/animation.h"
#include "components/camera.h"
#include "components/light.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/name.h"
#include "components/reflector.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "runtime/core/file_io.h"
#include "runtime/core/output_paths.h"
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
#include "runtime/cli/commands.h"
#include "systems/animation_system.h"
#include "runtime/cli/options.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

namespace fs = std::filesystem;
using namespace kaskad;

namespace {

// The options of each command, as the command line gives them (add_*_command() declares them).

struct RenderArgs {
  std::string scene;   ///< empty: content/scenes/default.json
  std::string output;  ///< empty: out/<scene>.png
  std::string aov;
  std::string shadow_map;
  std::string probe_maps;
  std::string reflection_reference;  ///< reference EXR to write
  std::string shadow_reference;      ///< shadow visibility reference EXR to write
  std::string env;                   ///< environment map of the reflection reference
  std::vector<std::string> sets;
  int width = 0, height = 0;  ///< 0: the scene's render.width/height
  int frames = 10;
  double time = -1.0;  ///< --time: the animation clock at the first frame; < 0: as loaded (0)
  double dt = 0.0;     ///< --dt: seconds the clock moves on per frame
  bool headless = !gpu::display_available();
};

struct SaveArgs {
  std::string scene, output;
  std::vector<std::string> sets;
};

struct VariantsArgs {
  std::string scene;  ///< empty: content/scenes/default.json
  std::vector<std::string> sets;
  bool aovs = false;
};

struct InfoArgs {
  std::string scene;  ///< empty: print the OpenGL context instead
  std::vector<std::string> sets;
  bool headless = !gpu::display_available();
};

struct BenchArgs {
  BenchOptions bench;
  bool merge = false;  ///< --merge: the SCENEs are shard output folders
};

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

int fail(const Error& e) {
  std::fprintf(stderr, "kaskad: error: %s\n", e.to_string().c_str());
  return 1;
}

int run_info(const InfoArgs& a) {
  if (a.scene.empty() && !a.sets.empty())
    throw cli::UsageError("info --set needs a SCENE (without one, info prints the OpenGL context)");
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
      if (const auto* an = w.try_get<Animator>(e)) {
        parts += " animation (clips:";
        for (const std::string& clip : an->names) {
          parts += ' ';
          parts += clip;
        }
        parts += ")";
      }
      if (const auto* d = w.try_get<Deformer>(e))
        parts += d->skin != Deformer::kNoSkin ? " skinned" : " morphed";
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

int run_save(const SaveArgs& a) {
  if (lowercase_extension(a.output) != ".json")
    throw cli::UsageError("save writes a scene file: -o needs a .json path, got '" + a.output + "'");
  auto scene = read_scene(a.scene, a.sets);
  if (!scene) return fail(scene.error());
  if (auto st = save_scene(a.output, *scene); !st) return fail(st.error());
  std::printf("wrote %s\n", a.output.c_str());
  return 0;
}

int run_variants(const VariantsArgs& a) {
  const fs::path scene_path =
      a.scene.empty() ? content_dir() / "scenes" / "default.json" : fs::path(a.scene);
  auto scene = load_scene(scene_path, a.sets);
  if (!scene) return fail(scene.error());
  auto manifest = render::FeatureManifest::load(content_dir() / "shaders" / "features.json");
  if (!manifest) return fail(manifest.error());
  FrameContext ctx;
  ctx.width = scene->render.width;
  ctx.height = scene->render.height;
  ctx.write_aovs = a.aovs;
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

int run_bench_command(const BenchArgs& a) {
  if (a.merge) {
    if (a.bench.scenes.empty()) throw cli::UsageError("bench --merge needs the shards' --out folders");
    std::set<std::string> seen;
    for (const std::filesystem::path& dir : a.bench.scenes) {
      std::error_code ec;
      const std::filesystem::path same = std::filesystem::weakly_canonical(dir, ec);
      if (!seen.insert((ec ? dir : same).string()).second)
        throw cli::UsageError("--merge: the shard folder " + dir.string() + " is named twice");
    }
    if (auto st = merge_bench(a.bench.scenes, a.bench.out_dir, a.bench.chart); !st)
      return fail(st.error());
    return 0;
  }
  if (auto st = run_bench(a.bench); !st) return fail(st.error());
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
  KASKAD_TRY(check_output_folder_to_make(dir));
  std::error_code ec;
  if (!fs::exists(dir, ec)) {
    fs::create_directory(dir, ec);
    if (ec) return Error{dir.string(), "", "cannot make this folder: " + ec.message()};
  }
  return check_output_folder(dir);
}

/// The start of a probe's file names in --probe-maps: its entity's name with every character
/// but letters, digits, '-', '_' and '.' made '_' (an imported name may hold a '/' or be "..", and
/// must not reach outside the folder), or probeN for an unnamed one.
std::string probe_file_stem(const std::string& name, ecs::Entity e) {
  if (name.empty()) return "probe" + std::to_string(e.index);
  std::string stem = name;
  for (char& c : stem)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  if (stem.front() == '.') stem.front() = '_';
  return stem;
}

/// Every output of `kaskad render`, checked before the scene is loaded or a frame rendered:
/// writable, not a folder, a format we can write. The default colour output out/<scene>.png
/// (docs/guide/bad_input.md, "Outputs") is the one folder made for the user.
Status check_render_outputs(const RenderArgs& a, const fs::path& out) {
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
  std::vector<NamedPath> named = {{"-o", out}};
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
  std::vector<NamedPath> inputs;
  if (!a.scene.empty()) inputs.push_back({"SCENE", a.scene});
  if (!a.env.empty()) inputs.push_back({"--env", a.env});
  KASKAD_TRY(check_distinct_outputs(named, inputs));
  if (!a.probe_maps.empty()) KASKAD_TRY(make_named_folder(a.probe_maps));
  return {};
}

int run_render(RenderArgs a) {
  const fs::path scene_path =
      a.scene.empty() ? content_dir() / "scenes" / "default.json" : fs::path(a.scene);
  const fs::path out = a.output.empty() ? fs::path("out") / (scene_path.stem().string() + ".png")
                                        : fs::path(a.output);
  if (!a.env.empty() && a.reflection_reference.empty())
    throw cli::UsageError("--env is the environment of --reflection-reference; a scene's own is "
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

  if (a.time >= 0.0) set_animation_time(scene->world, scene->assets, a.time);
  RenderRun run;
  run.frames = a.frames;
  run.dt = a.dt;
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
    if (st.shadow_layers_patched != 0)
      std::printf("          shadow layers patched: %d (casters moved under the same matrix: "
                  "only their texels were drawn again; render.shadow_cache)\n",
                  std::popcount(st.shadow_layers_patched));
    if (st.shadow_texels_drawn > 0)
      std::printf("          shadow texels drawn: %.2f M\n", double(st.shadow_texels_drawn) * 1e-6);
    if (st.shadow_rect_culled > 0)
      std::printf("          %d caster instances left out of layers drawn in part: their boxes "
                  "miss the texels drawn (shadow.scissor_to_receivers)\n",
                  st.shadow_rect_culled);
    if (st.visibility_reused)
      std::printf("          shadow visibility read back from the frame before (nothing it "
                  "depends on changed; render.visibility_cache)\n");
    if (st.visibility_reprojected)
      std::printf("          shadow visibility reprojected from the frame before where it held "
                  "(the camera alone moved; render.visibility_reproject)\n");
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
  // What can still refuse the run is settled before the first write: a failing run leaves every
  // earlier output as it was.
  ecs::Entity reference_light = ecs::kNullEntity;
  if (!a.shadow_reference.empty()) {
    const std::vector<ShadowData>& shadows = timings->last.shadows;
    if (!shadows.empty())
      reference_light = shadows[std::size_t(aov_shadow_index(*scene, shadows.size()))].light;
    if (!reference_light.valid())
      return fail(Error{"", "--shadow-reference", "the scene has no shadowed light"});
  }
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
    if (auto s = write_shadow_reference(*scene, player->renderer->read_aovs(), reference_light,
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
    std::set<std::string> stems;
    for (const ProbeData::Entry& p : timings->last.probes.probes) {
      const Name* name = scene->world.try_get<Name>(p.entity);
      std::string stem = probe_file_stem(name ? name->value : std::string(), p.entity);
      if (!stems.insert(stem).second) stem += "_" + std::to_string(p.entity.index);
      stems.insert(stem);
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

// The commands' options. Each add_*_command() declares one command's options, bound to the
// options struct its returned function owns and runs (cli::Command, runtime/cli/options.h).

/// `[SCENE]` and `--set KEY=VALUE`..., the scene every scene command reads.
void add_scene_options(CLI::App& cmd, std::string& scene, std::vector<std::string>& sets,
                       const std::string& scene_description) {
  cmd.add_option("SCENE", scene, scene_description)->type_name("FILE");
  cli::add_value_option(cmd, "--set", sets,
                        "override a setting or component field, e.g. shadow.map_size=4096, "
                        "sun.light.intensity=3, camera.camera.fov_y_deg=40 (repeatable)")
      ->type_name("KEY=VALUE");
}

cli::RunCommand add_render_command(CLI::App& cmd) {
  auto a = std::make_shared<RenderArgs>();
  add_scene_options(cmd, a->scene, a->sets,
                    "a scene file (.json, .gltf, .glb); default content/scenes/default.json");
  cli::add_output_option(cmd, "-o,--output", a->output, cli::OutputKind::image,
                         "colour image (PNG, JPEG, EXR, ...); default out/<scene>.png")
      ->type_name("FILE");
  cli::add_size_option(cmd, a->width, a->height, 1, 16384,
                       "output size in pixels (default: the scene's render.width/height)");
  cli::add_frames_option(cmd, a->frames,
                         "frames to render; times are the median of frames 2..N (default 10)");
  cli::add_number_option(cmd, "--time", a->time, 0.0, 1.0e6,
                         "seconds of animation played before the first frame: every playing "
                         "clip starts there (times its speed)");
  cli::add_number_option(cmd, "--dt", a->dt, 0.0, 10.0,
                         "seconds the animation clock moves on per frame (default 0: every "
                         "frame shows the same moment; the image is the last frame's)");
  cli::add_output_option(cmd, "--aov", a->aov, cli::OutputKind::image,
                        "write the AOVs of the last frame (P, N, Z, visibility, mask, cascade)")
      ->type_name("FILE.exr");
  cli::add_output_option(cmd, "--shadow-map", a->shadow_map, cli::OutputKind::image,
                        "write the shadow map depth of the last frame")
      ->type_name("FILE.exr");
  cli::add_output_option(cmd, "--probe-maps", a->probe_maps, cli::OutputKind::folder,
                        "write each reflection probe's visible cube faces (NAME_px.png ... "
                        "NAME_nz.png) and, for sphere probes, NAME_sphere.png into DIR")
      ->type_name("DIR");
  cli::add_output_option(cmd, "--reflection-reference", a->reflection_reference,
                         cli::OutputKind::image,
                        "ray-traced reflected radiance C_t of every pixel (docs/guide/envmaps.md)")
      ->type_name("FILE.exr");
  cli::add_value_option(cmd, "--env", a->env,
                        "environment map for the reflection reference's misses (any layout)")
      ->type_name("PATH");
  cli::add_output_option(cmd, "--shadow-reference", a->shadow_reference, cli::OutputKind::image,
                        "the ray-traced visibility of the light the visibility AOV shows (area "
                        "lights sampled), the AOV's, and their difference, per pixel; prints RMSE "
                        "and MAE over the receivers (docs/design/soft_shadows.md)")
      ->type_name("FILE.exr");
  cli::add_window_flags(cmd, a->headless);
  cli::add_verbose_flag(cmd);
  // bench's output options, refused with a pointer to -o instead of "unknown option" (hidden
  // from the help: an option without a group has no name to print, so the names are kept here).
  const std::pair<const char*, CLI::Option*> bench_only[] = {
      {"--out", cmd.add_option("--out")->group("")},
      {"--sweep", cmd.add_option("--sweep")->group("")}};
  return [a, out = bench_only[0], sweep = bench_only[1]] {
    for (const auto& [name, o] : {out, sweep})
      if (o->count() > 0)
        throw cli::UsageError(std::string(name) +
                              " is a bench option; kaskad render writes its image to -o FILE");
    return run_render(*a);
  };
}

cli::RunCommand add_save_command(CLI::App& cmd) {
  auto a = std::make_shared<SaveArgs>();
  add_scene_options(cmd, a->scene, a->sets, "the scene file to read (.json, .gltf, .glb)");
  cmd.get_option("SCENE")->required();
  cli::add_output_option(cmd, "-o,--output", a->output, cli::OutputKind::file,
                         "the canonical scene file to write")
      ->type_name("OUT.json")
      ->required();
  cli::add_verbose_flag(cmd);
  return [a] { return run_save(*a); };
}

cli::RunCommand add_variants_command(CLI::App& cmd) {
  auto a = std::make_shared<VariantsArgs>();
  add_scene_options(cmd, a->scene, a->sets,
                    "a scene file (.json, .gltf, .glb); default content/scenes/default.json");
  cmd.add_flag("--aov", a->aovs, "the programs of a frame that writes AOVs");
  cli::add_verbose_flag(cmd);
  return [a] { return run_variants(*a); };
}

cli::RunCommand add_info_command(CLI::App& cmd) {
  auto a = std::make_shared<InfoArgs>();
  add_scene_options(cmd, a->scene, a->sets,
                    "a scene file: print its entities (name, parent, components), the names "
                    "--set addresses, a glTF file's own nodes included; without one, print the "
                    "OpenGL context kaskad gets on this machine");
  cli::add_window_flags(cmd, a->headless);
  cli::add_verbose_flag(cmd);
  return [a] { return run_info(*a); };
}

cli::RunCommand add_bench_command(CLI::App& cmd) {
  auto a = std::make_shared<BenchArgs>();
  BenchOptions& o = a->bench;
  cmd.add_option("SCENE", o.scenes,
                 "scene files (default: content/scenes/default.json); with --merge, the shards' "
                 "--out folders")
      ->type_name("FILE");
  cli::add_value_option(cmd, "--sweep", o.sweep,
                        "the settings to sweep, key=a,b;key2=c,d, or soft (the soft-shadow "
                        "techniques and kernels); default: docs/guide/bench.md")
      ->type_name("SPEC")
      ->check(CLI::Validator(
          [](const std::string& v) -> std::string {
            return v.empty() ? "needs a sweep (e.g. shadow.map_size=1024,2048, or soft); without "
                               "--sweep, bench runs the default one"
                             : "";
          },
          ""));
  cli::add_output_option(cmd, "--out", o.out_dir, cli::OutputKind::folder,
                         "where bench.csv and the charts go (default out/bench)")
      ->type_name("DIR");
  cli::add_frames_option(cmd, o.frames, "timed frames per configuration (default 10)");
  cli::add_size_option(cmd, o.width, o.height, 1, 16384, "output size in pixels (default 640x360)");
  cmd.add_flag_callback("--no-chart", [a] { a->bench.chart = false; },
                        "no speed-vs-accuracy chart (scripts/bench_chart.py)");
  cli::add_integer_option(cmd, "--stability-frames", o.stability_frames, 0, 10000,
                          "flicker at fixed points over an N-frame camera path (default 16, 0 = "
                          "off)");
  cli::add_shard_option(cmd, o.shard_index, o.shard_count,
                        "run part i of n of the scene x configuration list (for a CI matrix); "
                        "--merge joins the parts' CSVs");
  cmd.add_flag("--merge", a->merge,
               "merge the bench.csv of the shard folders named as SCENEs into --out");
  cli::add_verbose_flag(cmd);
  cmd.footer("Writes DIR/bench.csv and one speed-vs-accuracy chart per scene.");
  return [a] { return run_bench_command(*a); };
}

cli::RunCommand add_schema_command(CLI::App& cmd) {
  auto out = std::make_shared<std::filesystem::path>(content_dir().parent_path() / "docs" /
                                                     "reference");
  auto check = std::make_shared<bool>(false);
  cli::add_value_option(cmd, "--out", *out,
                        "where scene.schema.json, material.schema.json and settings.md go "
                        "(default docs/reference beside content/)")
      ->type_name("DIR");
  cmd.add_flag("--check", *check,
               "write nothing; fail if the files in DIR differ from what the field tables give");
  return [out, check] {
    // As every output folder (add_output_option): one level made, in a folder that exists. Only
    // when writing: --check reads the folder.
    if (!*check)
      if (const std::string why = cli::output_problem(out->string(), cli::OutputKind::folder);
          !why.empty())
        throw cli::UsageError("--out: " + why);
    return run_schema_command(*out, *check);
  };
}

}  // namespace

/// Every command, in the order `kaskad --help` lists them; the play, envmap and edit commands are
/// declared in runtime/cli/commands.cpp.
const cli::Command kCommands[] = {
    {"render", "render a scene (headless or in a window), write images, AOVs and references",
     add_render_command},
    {"save", "write the canonical scene file (after overrides)", add_save_command},
    {"variants", "list the shader variants (pass, key, defines) the scene needs",
     add_variants_command},
    {"bench", "sweep settings; write bench.csv and speed-vs-accuracy charts", add_bench_command},
    {"envmap", "load an environment map, print what was found, write its faces or sphere map",
     cli::add_envmap_command},
    {"play", "replay playback files (camera keys, timeline, captures) and check their expectations",
     cli::add_play_command},
    {"edit", "the editor: a window with an entity list, inspectors, a fly camera, undo, saving",
     cli::add_edit_command},
    {"info", "print the OpenGL context, or with a SCENE its entities", add_info_command},
    {"schema", "write the scene and material JSON schemas and the settings reference",
     add_schema_command},
};

int run_command(int argc, char** argv) {
  CLI::App app("kaskad - real-time shadows and reflections, headless or windowed", "kaskad");
  app.require_subcommand(1);
  // An option given twice takes its last value (`-o a.png -o b.png` writes b.png), as scripts
  // that append to a base command line expect; repeatable options (--set) keep every value.
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  std::vector<std::pair<CLI::App*, cli::RunCommand>> commands;
  for (const cli::Command& c : kCommands) {
    CLI::App* cmd = app.add_subcommand(c.name, c.summary);
    // Left-over arguments are reported below, in the old words ("unknown option '--x'").
    cmd->allow_extras();
    commands.emplace_back(cmd, c.add(*cmd));
  }
  // After the commands: a subcommand starts with its parent's footer.
  app.footer("Run `kaskad COMMAND --help` for a command's options.");
  // Before CLI11, which would say "A subcommand is required" of both.
  if (argc < 2) return cli::print_usage_error("", "missing command");
  const std::string first = argv[1];
  if (first == "help") {
    std::fputs(app.help().c_str(), stdout);
    return 0;
  }
  if (first.empty() || first[0] != '-') {
    bool known = false;
    for (const cli::Command& c : kCommands) known |= first == c.name;
    if (!known) return cli::print_usage_error("", "unknown command '" + first + "'");
  }
  std::string command;
  try {
    app.parse(argc, argv);
    for (auto& [cmd, run] : commands) {
      if (!cmd->parsed()) continue;
      command = cmd->get_name();
      for (const std::string& extra : cmd->remaining())
        throw cli::UsageError(extra.size() > 1 && extra[0] == '-'
                                  ? "unknown option '" + extra + "'"
                                  : "unexpected argument '" + extra + "'");
      return run();
    }
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    if (command.empty() && !app.get_subcommands().empty())
      command = app.get_subcommands().front()->get_name();
    return cli::print_usage_error(command, e.what());
  }
  return cli::print_usage_error("", "missing command");
}

int main(int argc, char** argv) {
  keep_freed_memory();  // frames reuse their memory instead of faulting it in again
  // A file-size limit (`ulimit -f`) or a full disk must fail the write with an error, not kill
  // the process: write() then returns EFBIG and the atomic writer keeps the previous file.
  std::signal(SIGXFSZ, SIG_IGN);
  // The last line of defence (docs/guide/bad_input.md, "How files are read"): every reader turns library exceptions into
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
