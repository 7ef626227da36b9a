// The runner: plays one playback file frame by frame (timeline, frame, outputs and checks, a
// CSV row), then each file of a shard in turn with one GL context.
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "components/camera.h"
#include "components/transform.h"
#include "runtime/app/bench.h"
#include "runtime/app/playback.h"
#include "runtime/app/playback_checks.h"
#include "runtime/app/playback_internal.h"
#include "runtime/app/player.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/scene_io.h"
#include "runtime/core/atomic_file.h"
#include "runtime/gpu/context.h"
#include "runtime/gpu/gl_handles.h"
#include "systems/camera_system.h"
#include "systems/transform_system.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace playback_detail;

// Resident set size of this process, MiB (Linux /proc/self/statm; 0 elsewhere).
double resident_mib() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  if (!(statm >> pages_total >> pages_resident)) return 0.0;
  return double(pages_resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

// Loads the scene of `pb` with its sets and size, and checks every timeline event and track
// against a second copy first, so that a bad key fails before the first frame. With a
// renderer, every state the timeline reaches is pre-warmed on that copy: toggles mid-run
// compile nothing.
Result<Scene> load_checked(const Playback& pb, render::Renderer* prewarm = nullptr,
                           const FrameContext* ctx = nullptr) {
  std::vector<std::string> sets = pb.sets;
  sets.push_back("render.width=" + std::to_string(pb.width));
  sets.push_back("render.height=" + std::to_string(pb.height));
  auto scene = load_scene(pb.scene, sets);
  if (!scene) {
    Error e = scene.error();
    e.message += " (the scene of " + pb.file.string() + ", /scene)";
    return e;
  }
  auto trial = load_scene(pb.scene, sets);
  if (!trial) return trial.error();
  const bool points = bool(pb.flicker);  // the flicker gate reads the points pass
  if (prewarm) KASKAD_TRY(prewarm_frame(*trial, *prewarm, *ctx, {}, points));
  // A setting given again right after itself (an event that repeats every frame with nothing
  // between) reaches no new state: it is checked and pre-warmed once. Long timelines show
  // progress.
  CheckProgress progress(pb.events.size(), pb.file.filename().string() + ": timeline");
  const SetEvent* last = nullptr;
  for (std::size_t i = 0; i < pb.events.size(); ++i) {
    const SetEvent& ev = pb.events[i];
    if ((i & 255) == 0) progress.update(i);
    if (last && !ev.assignment.empty() && ev.assignment == last->assignment) continue;
    last = &ev;
    if (auto st = apply_event(*trial, ev, pb.file); !st) {
      Error e = st.error();
      e.message += " (timeline event at frame " + std::to_string(ev.frame) +
                   (e.file == pb.file.string() ? "" : " of " + pb.file.string()) + ")";
      return e;
    }
    if (prewarm) KASKAD_TRY(prewarm_frame(*trial, *prewarm, *ctx, {}, points));
  }
  for (const Track& tr : pb.tracks)
    if (!find_named(scene->world, tr.entity).valid())
      return Error{pb.file.string(), "/timeline", "no entity named '" + tr.entity + "' in " +
                                                      pb.scene.string()};
  if (pb.camera) {
    const CameraState cam = select_camera(scene->world, 1.0f);
    if (!cam.entity.valid()) return Error{pb.file.string(), "/camera", "the scene has no camera"};
    if (scene->world.get<Transform>(cam.entity).parent.valid())
      return Error{pb.file.string(), "/camera", "the camera has a parent; keys move root cameras"};
  }
  return scene;
}

// The file's own output folder, made, without the captures and diff images of an earlier run of
// this file (they would pass for this run's).
Status prepare_output(const fs::path& out) {
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) return Error{out.string(), "", "cannot create the output folder: " + ec.message()};
  static const std::regex earlier(R"((frame|diff)_\d{4}\.png|aov_\d{4}\.exr)");
  for (const auto& entry : fs::directory_iterator(out, ec))
    if (entry.is_regular_file(ec) && std::regex_match(entry.path().filename().string(), earlier))
      fs::remove(entry.path(), ec);
  return {};
}

// Every program made from here on counts, compiled or loaded from the binary cache: either is a
// hitch in the middle of the run.
int programs_made(render::Renderer& renderer) {
  const render::ShaderStats& s = renderer.shaders().stats();
  return s.programs_compiled + s.cache_hits;
}

/// An entity a track moves, with its transform at load.
struct Moved {
  ecs::Entity entity;
  const Track* track;
  Transform start;
};

// One file's run: what its steps read, and what they carry from frame to frame.
struct Run {
  const Playback& pb;
  const PlayOptions& options;
  const fs::path& out;  ///< the file's own output folder
  Player& player;
  Scene& scene;
  FrameContext& ctx;
  ecs::Entity camera = ecs::kNullEntity;  ///< the camera track's, when there is one
  Transform camera_start;
  std::vector<Moved> moved;
  SystemState systems;  // this run's: a fresh scene, frames from 0
  FrameReport report;
  std::size_t next_event = 0;
  std::set<int> capture;  ///< frames whose colour image is written
  std::set<int> checked;  ///< frames misclassified_pct checks
  int compiles_before = 0;
  int captured = 0;
  FlickerSamples flicker;
  RunRecord record;
  Failures failures;
};

/// What a frame's CSV row holds besides the frame report.
struct FrameRow {
  int frame = 0;
  double t = 0.0, frame_ms = 0.0;
  int compiles = 0;  ///< programs built after pre-warm, so far
  double misclassified_pct = -1.0;
  double rss_mib = 0.0;
  long gl_objects = 0;
};

// The camera and the entities the tracks move, with their transforms at load.
void find_movers(Run& run) {
  const Playback& pb = run.pb;
  ecs::World& w = run.scene.world;
  if (pb.camera) {
    run.camera = select_camera(w, 1.0f).entity;
    run.camera_start = w.get<Transform>(run.camera);
  }
  for (const Track& tr : pb.tracks) {
    const ecs::Entity e = find_named(w, tr.entity);
    run.moved.push_back({e, &tr, w.get<Transform>(e)});
  }
}

// 1. Timeline: events due now, then the tracks' poses.
Status apply_timeline(Run& run, int f, double t) {
  const Playback& pb = run.pb;
  Scene& scene = run.scene;
  for (; run.next_event < pb.events.size() && pb.events[run.next_event].frame <= f; ++run.next_event)
    KASKAD_TRY(apply_event(scene, pb.events[run.next_event], pb.file));
  if (pb.camera) {
    apply_pose(scene.world, run.camera, *pb.camera, sample_track(*pb.camera, t), run.camera_start);
    // An auto_frame camera's planes were fitted from where the load put it; as in the
    // editor, they follow the keys, or a camera moved in would clip what it moves up to.
    if (Camera& c = scene.world.get<Camera>(run.camera); c.auto_frame) {
      const Aabb bounds = scene_bounds(scene.world);
      if (!bounds.empty())
        fit_planes_to_bounds(c, scene.world.get<Transform>(run.camera).translation, bounds);
    }
  }
  for (const Moved& m : run.moved)
    apply_pose(scene.world, m.entity, *m.track, sample_track(*m.track, t), m.start);
  return {};
}

// 2. The frame, timed with the GPU waited on; returns its milliseconds.
Result<double> render_frame(Run& run, int f) {
  run.ctx.index = std::uint64_t(f);
  const auto t0 = std::chrono::steady_clock::now();
  KASKAD_TRY(run_frame(run.scene, *run.player.renderer, run.ctx, run.systems, run.report));
  run.player.renderer->finish();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// 3a. A captured frame's colour image (and AOVs), checked against its golden.
Status capture_frame(Run& run, int f) {
  const Playback& pb = run.pb;
  render::Renderer& renderer = *run.player.renderer;
  const fs::path png = run.out / frame_name("frame", f, "png");
  KASKAD_TRY(save_image(png, renderer.read_color()));
  ++run.captured;
  if (pb.capture_aovs) KASKAD_TRY(save_image(run.out / frame_name("aov", f, "exr"), renderer.read_aovs()));
  if (pb.golden) KASKAD_TRY(check_golden(pb, f, png, run.out, run.options.update_goldens, run.failures));
  return {};
}

// 3b. The outputs and the expectations of this frame, in the order their failures are listed.
Status check_frame(Run& run, int f, FrameRow& row) {
  const Playback& pb = run.pb;
  if (run.capture.count(f)) KASKAD_TRY(capture_frame(run, f));
  if (run.checked.count(f)) {
    auto pct = check_misclassified(pb, f, run.scene, *run.player.renderer, run.report, run.failures);
    if (!pct) return pct.error();
    row.misclassified_pct = *pct;
  }
  if (pb.flicker)
    KASKAD_TRY(check_flicker(pb, f, *run.player.renderer, run.report, run.flicker, run.failures));
  row.rss_mib = resident_mib();
  row.gl_objects = gpu::live_gl_objects();
  if (pb.flat_resources) sample_resources(pb, f, row.rss_mib, row.gl_objects, run.record.resources);
  return {};
}

// Rows are kept in memory and written atomically at the end (and when a run fails midway,
// nothing half-written is left behind).

// The columns of frames.csv, once: each name with the value it writes (docs/guide/playback.md).
struct CsvColumn {
  const char* name;
  std::string (*value)(const FrameRow&, const FrameReport&);
};
std::string number(double v, const char* format = "%.4f") {
  char text[64];
  std::snprintf(text, sizeof text, format, v);
  return text;
}
std::string count(long long v) { return std::to_string(v); }
constexpr CsvColumn kCsvColumns[] = {
    {"frame", [](const FrameRow& r, const FrameReport&) { return count(r.frame); }},
    {"t", [](const FrameRow& r, const FrameReport&) { return number(r.t, "%.6g"); }},
    {"frame_ms", [](const FrameRow& r, const FrameReport&) { return number(r.frame_ms); }},
    {"cpu_animation_ms", [](const FrameRow&, const FrameReport& f) { return number(f.animation_ms); }},
    {"cpu_transforms_ms", [](const FrameRow&, const FrameReport& f) { return number(f.transforms_ms); }},
    {"cpu_camera_ms", [](const FrameRow&, const FrameReport& f) { return number(f.camera_ms); }},
    {"cpu_shadows_ms", [](const FrameRow&, const FrameReport& f) { return number(f.shadows_ms); }},
    {"cpu_probes_ms", [](const FrameRow&, const FrameReport& f) { return number(f.probes_ms); }},
    {"cpu_draw_list_ms", [](const FrameRow&, const FrameReport& f) { return number(f.draw_list_ms); }},
    {"cpu_render_ms", [](const FrameRow&, const FrameReport& f) { return number(f.render_ms); }},
    {"gpu_shadow_ms", [](const FrameRow&, const FrameReport& f) { return number(f.stats.shadow_gpu_ms); }},
    {"gpu_forward_ms", [](const FrameRow&, const FrameReport& f) { return number(f.stats.forward_gpu_ms); }},
    {"gpu_probe_ms", [](const FrameRow&, const FrameReport& f) { return number(f.stats.probe_gpu_ms); }},
    {"draw_calls", [](const FrameRow&, const FrameReport& f) { return count(f.stats.draw_calls); }},
    {"shadow_draw_calls", [](const FrameRow&, const FrameReport& f) { return count(f.stats.shadow_draw_calls); }},
    {"shadow_triangles", [](const FrameRow&, const FrameReport& f) { return count((long long)f.stats.shadow_triangles); }},
    {"probe_faces", [](const FrameRow&, const FrameReport& f) { return count(f.stats.probe_faces); }},
    {"probe_captures", [](const FrameRow&, const FrameReport& f) { return count(f.probes.captures_this_frame); }},
    {"compiles_after_prewarm", [](const FrameRow& r, const FrameReport&) { return count(r.compiles); }},
    {"misclassified_pct", [](const FrameRow& r, const FrameReport&) {
       return r.misclassified_pct < 0 ? std::string() : number(r.misclassified_pct, "%.6f"); }},
    {"rss_mib", [](const FrameRow& r, const FrameReport&) { return number(r.rss_mib, "%.2f"); }},
    {"gl_objects", [](const FrameRow& r, const FrameReport&) { return count(r.gl_objects); }},
    {"mesh_draws", [](const FrameRow&, const FrameReport& f) { return count(f.stats.mesh_draws); }},
    {"shadow_mesh_draws", [](const FrameRow&, const FrameReport& f) { return count(f.stats.shadow_mesh_draws); }},
    {"shadow_layers_rendered", [](const FrameRow&, const FrameReport& f) {
       return count(std::popcount(f.stats.shadow_layers_rendered)); }},
    {"shadow_layers_scrolled", [](const FrameRow&, const FrameReport& f) {
       return count(std::popcount(f.stats.shadow_layers_scrolled)); }},
    {"shadow_layers_patched", [](const FrameRow&, const FrameReport& f) {
       return count(std::popcount(f.stats.shadow_layers_patched)); }},
    {"shadow_texels_drawn", [](const FrameRow&, const FrameReport& f) { return count(f.stats.shadow_texels_drawn); }},
    {"deformed_meshes", [](const FrameRow&, const FrameReport& f) { return count(f.stats.deformed_meshes); }},
    // render.visibility_cache: how the forward pass got each pixel's shadow visibility.
    {"visibility", [](const FrameRow&, const FrameReport& f) {
       const auto& s = f.stats;
       return std::string(s.visibility_reused        ? "loaded"
                          : s.visibility_reprojected ? "reprojected"
                          : s.visibility_stored      ? "looked_up_stored"
                                                     : "looked_up");
     }},
};

std::string csv_header() {
  std::string line;
  for (const CsvColumn& c : kCsvColumns) {
    if (&c != kCsvColumns) line += ',';
    line += c.name;
  }
  return line + "\n";
}

// 4. The frame's row of frames.csv.
std::string csv_row(const FrameRow& row, const FrameReport& report) {
  std::string line;
  for (const CsvColumn& c : kCsvColumns) {
    if (&c != kCsvColumns) line += ',';
    line += c.value(row, report);
  }
  return line + "\n";
}

struct FileResult {
  std::vector<PlayFailure> failures;
  int frames = 0;
  double wall_s = 0.0;
  int captured = 0;
};

// Plays `pb` into its own output folder `out`: load and check, then per frame the timeline,
// the frame, its outputs and checks and its CSV row; then the whole-run expectations.
Result<FileResult> play_one(Player& player, const Playback& pb, const PlayOptions& options,
                            const fs::path& out) {
  const auto t_start = std::chrono::steady_clock::now();
  FrameContext ctx;
  ctx.width = pb.width;
  ctx.height = pb.height;
  // AOVs for every frame when any frame needs them: one program set, no compiles mid-run.
  ctx.write_aovs = pb.capture_aovs || pb.misclassified || pb.flicker;
  const int gl_errors_before = gpu::debug_error_count();
  auto scene = load_checked(pb, player.renderer.get(), &ctx);
  if (!scene) return scene.error();
  KASKAD_TRY(prepare_output(out));
  // The output size the camera allows (an own aspect fits inside the playback's size).
  ctx.width = scene->render.width;
  ctx.height = scene->render.height;
  ctx.dt = pb.dt;  // frame n shows the scene's clips n * dt seconds in, as the timeline counts
  player.renderer->shaders().first_frame_done();

  Run run{pb, options, out, player, *scene, ctx};
  run.compiles_before = programs_made(*player.renderer);
  find_movers(run);
  run.capture = std::set<int>(pb.capture.begin(), pb.capture.end());
  if (pb.misclassified)
    run.checked = std::set<int>(pb.misclassified->frames.begin(), pb.misclassified->frames.end());
  run.failures.file = pb.file.string();

  std::ostringstream csv;
  csv << csv_header();
  for (int f = 0; f < pb.frames; ++f) {
    FrameRow row;
    row.frame = f;
    row.t = f * pb.dt;
    KASKAD_TRY(apply_timeline(run, f, row.t));
    auto ms = render_frame(run, f);
    if (!ms) return ms.error();
    row.frame_ms = *ms;
    run.record.frame_ms.push_back(row.frame_ms);
    row.compiles = programs_made(*player.renderer) - run.compiles_before;
    if (run.report.probes.captures_this_frame > 0) run.record.probe_capture_frames.push_back(f);
    KASKAD_TRY(check_frame(run, f, row));
    csv << csv_row(row, run.report);
    print_progress(std::size_t(f + 1), std::size_t(pb.frames),
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count(),
                   pb.file.filename().string());
  }
  end_progress();
  KASKAD_TRY(write_file_atomic(out / "frames.csv", csv.str()));

  run.record.compiles = programs_made(*player.renderer) - run.compiles_before;
  run.record.gl_errors = gpu::debug_error_count() - gl_errors_before;
  run.record.probe_captures = run.report.probes.captures_total;
  check_run(pb, run.record, run.failures);

  FileResult result;
  result.failures = std::move(run.failures.list);
  result.captured = run.captured;
  result.frames = pb.frames;
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return result;
}

}  // namespace

Result<std::vector<PlayFailure>> run_playbacks(const std::vector<fs::path>& files,
                                               const PlayOptions& options) {
  if (options.shard_count < 1 || options.shard_index < 0 ||
      options.shard_index >= options.shard_count)
    return Error{"--shard", "", "expected i/n with 0 <= i < n"};
  std::vector<fs::path> sorted = files;
  std::sort(sorted.begin(), sorted.end());
  std::vector<PlayFailure> failures;
  json summary = {
      {"kaskad_play_summary", 1},
      {"shard", std::to_string(options.shard_index) + "/" + std::to_string(options.shard_count)},
      {"files", json::array()}};
  // A file that cannot be read or run fails on its own: it is reported at once and recorded in
  // the summary, and the other files still run.
  auto fail_file = [&](const fs::path& file, const Error& error) {
    end_progress();
    std::fprintf(stderr, "kaskad: error: %s\n", error.to_string().c_str());
    std::printf("play      %-40s %6d frames %8.1f s  FAILED (cannot run)\n",
                file.filename().string().c_str(), 0, 0.0);
    failures.push_back({file.string(), -1, error.to_string()});
    summary["files"].push_back(
        {{"file", file.string()},
         {"frames", 0},
         {"captured", 0},
         {"wall_s", 0.0},
         {"ok", false},
         {"failures", json::array({{{"frame", -1}, {"message", error.to_string()}}})}});
  };
  // Every file of the shard is read before anything renders: a bad file fails at once.
  std::vector<Playback> playbacks;
  for (std::size_t i : shard_files(sorted.size(), options.shard_index, options.shard_count)) {
    auto pb = read_playback(sorted[i]);
    if (pb)
      playbacks.push_back(std::move(pb.value()));
    else
      fail_file(sorted[i], pb.error());
  }
  // Output folders by file name; files of the same name from different folders get their
  // folder's name in front. Two files that still meet (p/x.json and p_x.json, or one file named
  // twice) are refused before anything runs: one would write over the other's captures.
  std::vector<std::string> names;
  for (const Playback& pb : playbacks) {
    std::string name = pb.file.stem().string();
    for (const Playback& other : playbacks)
      if (&other != &pb && other.file.stem() == pb.file.stem()) {
        name = pb.file.parent_path().filename().string() + "_" + name;
        break;
      }
    for (std::size_t j = 0; j < names.size(); ++j)
      if (names[j] == name)
        return Error{pb.file.string(), "",
                     "writes to the same output folder as " + playbacks[j].file.string() + " (" +
                         (options.out_dir / name).string() + "); rename one of them"};
    names.push_back(name);
  }
  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec) return Error{options.out_dir.string(), "", "cannot create the output folder: " + ec.message()};
  std::optional<Player> player;
  if (!playbacks.empty()) {
    gpu::ContextOptions opt;
    opt.headless = options.headless;
    auto made = Player::create(opt);
    if (!made) return made.error();
    player.emplace(std::move(made.value()));
  }

  for (std::size_t i = 0; i < playbacks.size(); ++i) {
    const Playback& pb = playbacks[i];
    auto r = play_one(*player, pb, options, options.out_dir / names[i]);
    if (!r) {
      fail_file(pb.file, r.error());
      continue;
    }
    json failed = json::array();
    for (const PlayFailure& f : r->failures) {
      failed.push_back({{"frame", f.frame}, {"message", f.message}});
      failures.push_back(f);
    }
    summary["files"].push_back({{"file", pb.file.string()},
                                {"frames", r->frames},
                                {"captured", r->captured},
                                {"wall_s", r->wall_s},
                                {"ok", r->failures.empty()},
                                {"failures", failed}});
    std::printf("play      %-40s %6d frames %8.1f s  %s\n", pb.file.filename().string().c_str(),
                r->frames, r->wall_s,
                r->failures.empty() ? "ok" : ("FAILED (" + std::to_string(r->failures.size()) + ")").c_str());
    for (const PlayFailure& f : r->failures)
      std::printf("  %s%s: %s\n", f.file.c_str(),
                  f.frame >= 0 ? (" frame " + std::to_string(f.frame)).c_str() : "", f.message.c_str());
  }
  KASKAD_TRY(write_file_atomic(options.out_dir / "summary.json", summary.dump(2) + "\n"));
  return failures;
}

}  // namespace kaskad
