#include "runtime/app/bench.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>

#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "runtime/assets/scene_io.h"
#include "runtime/app/player.h"
#include "runtime/app/stability.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"
#include "runtime/core/hash.h"
#include "runtime/reference/ray_tracer.h"
#include "runtime/reference/shadow_metrics.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) { g_interrupted = true; }

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  std::istringstream in(s);
  while (std::getline(in, cur, sep)) out.push_back(cur);
  if (!s.empty() && s.back() == sep) out.push_back("");
  return out;
}

std::string trim(std::string s) {
  const auto b = s.find_first_not_of(" \t");
  const auto e = s.find_last_not_of(" \t");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

std::string csv_quote(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string clock_text(double seconds) {
  const int s = int(seconds + 0.5);
  char buf[16];
  std::snprintf(buf, sizeof buf, "%02d:%02d", s / 60, s % 60);
  return buf;
}

// A terminal gets one line rewritten in place; a log (CI) a plain line every 10 s and at the end.
bool g_progress_open = false;  // a bar on the terminal waits for its newline
double g_progress_logged_s = -1.0;

void progress_line(std::size_t done, std::size_t total, double elapsed_s, const std::string& what) {
  const int width = 28;
  const int filled = total ? int(double(done) / double(total) * width) : width;
  const double eta = done ? elapsed_s / double(done) * double(total - done) : 0.0;
  const bool terminal = isatty(STDERR_FILENO);
  if (!terminal) {
    if (elapsed_s < g_progress_logged_s) g_progress_logged_s = -1.0;  // a new run
    if (done < total && g_progress_logged_s >= 0.0 && elapsed_s - g_progress_logged_s < 10.0)
      return;
    g_progress_logged_s = elapsed_s;
  }
  std::fprintf(stderr,
               terminal ? "\r[%s%s] %zu/%zu  elapsed %s  ETA %s  %-40.40s"
                        : "[%s%s] %zu/%zu  elapsed %s  ETA %s  %s\n",
               std::string(std::size_t(filled), '#').c_str(),
               std::string(std::size_t(width - filled), '-').c_str(), done, total,
               clock_text(elapsed_s).c_str(), done ? clock_text(eta).c_str() : "--:--",
               what.c_str());
  g_progress_open = terminal;
  std::fflush(stderr);
}

// What the reference BVH depends on: every MeshRenderer's mesh, flags and world matrix, its
// material's alpha cut-out (the tracer copies it), and the meshes' sizes. Configurations of one scene usually differ in settings only, so the BVH is
// rebuilt only when this changes (a --set may move or hide geometry).
std::uint64_t geometry_signature(const Scene& scene) {
  Hash h;
  auto mix = [&](const void* data, std::size_t n) { h.add_bytes(data, n); };
  scene.world.view<const MeshRenderer, const WorldTransform>().each(
      [&](ecs::Entity e, const MeshRenderer& mr, const WorldTransform& wt) {
        const std::uint32_t id = e.index;
        const std::uint8_t flags = std::uint8_t(mr.cast_shadows) | std::uint8_t(mr.receive_shadows << 1);
        mix(&id, sizeof id);
        mix(&mr.mesh, sizeof mr.mesh);
        mix(&flags, 1);
        mix(&wt.matrix, sizeof wt.matrix);
        if (const Material* m = scene.world.try_get<Material>(e); m && m->alpha_mode != AlphaMode::opaque) {
          const float cut[2] = {m->alpha_cutoff, m->base_color.a};
          mix(cut, sizeof cut);
          mix(&m->base_color_texture, sizeof m->base_color_texture);
        }
      });
  for (const auto& m : scene.assets.meshes) {
    const std::size_t sizes[2] = {m.positions.size(), m.indices.size()};
    mix(sizes, sizeof sizes);
  }
  return h.value();
}

}  // namespace

// scripts/bench_chart.py over a bench CSV: one chart per scene into `out_dir`. Started without a
// shell (paths with quotes or spaces are arguments as they are).
static Status draw_charts(const fs::path& csv_path, const fs::path& out_dir) {
  const fs::path script = content_dir().parent_path() / "scripts" / "bench_chart.py";
  // Debian's python3, which has python3-matplotlib, whatever else is first on PATH.
  const char* python = "/usr/bin/python3";
  std::vector<std::string> args = {python, script.string(), csv_path.string(), out_dir.string()};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  // The script's stderr comes back through a pipe: its last line is the error shown.
  int pipe_fds[2];
  if (pipe(pipe_fds) != 0)
    return Error{script.string(), "", std::string("cannot start the chart script: ") + std::strerror(errno)};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addclose(&actions, pipe_fds[0]);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDERR_FILENO);
  posix_spawn_file_actions_addclose(&actions, pipe_fds[1]);
  pid_t pid = 0;
  const int err = posix_spawn(&pid, python, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(pipe_fds[1]);
  if (err != 0) {
    close(pipe_fds[0]);
    return Error{script.string(), "", std::string("cannot start ") + python + ": " + std::strerror(err)};
  }
  std::string errors;
  char buf[4096];
  for (;;) {
    const ssize_t n = read(pipe_fds[0], buf, sizeof buf);
    if (n > 0) {
      errors.append(buf, std::size_t(n));
      if (errors.size() > (1u << 16)) errors.erase(0, errors.size() - (1u << 15));  // keep the tail
    } else if (n == 0 || errno != EINTR) {
      break;
    }
  }
  close(pipe_fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return Error{script.string(), "", "lost the chart script's exit status"};
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    std::fputs(errors.c_str(), stderr);  // warnings, passed on
    return {};
  }
  while (!errors.empty() && (errors.back() == '\n' || errors.back() == ' ')) errors.pop_back();
  const std::string last = errors.substr(errors.find_last_of('\n') == std::string::npos
                                             ? 0
                                             : errors.find_last_of('\n') + 1);
  const bool no_matplotlib = last.find("matplotlib") != std::string::npos &&
                             (last.find("ModuleNotFoundError") != std::string::npos ||
                              last.find("ImportError") != std::string::npos);
  std::string why = WIFEXITED(status) ? "chart script failed"
                                      : "chart script killed by signal " + std::to_string(WTERMSIG(status));
  if (!last.empty()) why += ": " + last;
  if (no_matplotlib) why += " (install python3-matplotlib)";
  return Error{script.string(), "", why};
}

void print_progress(std::size_t done, std::size_t total, double elapsed_s,
                    const std::string& what) {
  progress_line(done, total, elapsed_s, what);
}

void end_progress() {
  if (g_progress_open) std::fprintf(stderr, "\n");
  g_progress_open = false;
}

void CheckProgress::update(std::size_t done) {
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (!shown_ && s < 2.0) return;
  shown_ = true;
  print_progress(done, total_, s, what_);
}

std::string default_sweep() {
  // Cascade count x fit x map size x filter: 24 configurations, the trade-offs that matter most.
  return "shadow.cascade_count=1,2,4;shadow.fit_mode=stable,crop;shadow.map_size=1024,2048;"
         "shadow.filter=none,pcf3x3";
}

std::string soft_sweep() {
  // Every configuration redraws its shadow maps each frame (shadow_cache off), as under a moving
  // camera or light: lom's pass 1 is most of its cost, and a still camera would keep it.
  const char* configurations[] = {
      "shadow.technique=pcf;shadow.pcf_kernel=3,5,9",
      "shadow.technique=pcf;shadow.pcf_kernel=poisson;shadow.pcf_taps=16,32",
      "shadow.technique=pcss;shadow.pcf_taps=16,32",
      "shadow.technique=backprojection",
      "shadow.technique=lom;shadow.map_size=1024;shadow.lom_layers=4,8",
      "shadow.technique=vsm,evsm"};
  std::string out;
  for (const char* c : configurations) {
    if (!out.empty()) out += '|';
    out.append("render.shadow_cache=false;").append(c);
  }
  return out;
}

namespace {

// One cartesian product: "key=v1,v2;key2=w1,w2".
Result<std::vector<BenchConfig>> parse_product(const std::string& spec) {
  std::vector<BenchConfig> configs{{"", {}}};
  std::set<std::string> keys;
  for (const std::string& part_raw : split(spec, ';')) {
    const std::string part = trim(part_raw);
    if (part.empty()) continue;
    const auto eq = part.find('=');
    if (eq == std::string::npos || eq == 0)
      return Error{"--sweep", part, "expected key=value1,value2,... (e.g. shadow.map_size=1024,2048)"};
    const std::string key = trim(part.substr(0, eq));
    if (!keys.insert(key).second) return Error{"--sweep", key, "key given twice"};
    std::vector<std::string> values;
    for (const auto& v : split(part.substr(eq + 1), ','))
      if (!trim(v).empty()) values.push_back(trim(v));
    if (values.empty()) return Error{"--sweep", key, "no values"};
    if (configs.size() * values.size() > kMaxSweepConfigurations)
      return Error{"--sweep", key,
                   "the sweep expands to more than " + std::to_string(kMaxSweepConfigurations) +
                       " configurations (" + std::to_string(configs.size()) + " x " +
                       std::to_string(values.size()) + " values of " + key + ")"};
    std::vector<BenchConfig> next;
    for (const auto& c : configs)
      for (const auto& v : values) {
        BenchConfig n = c;
        n.sets.push_back(key + "=" + v);
        // Appended piecewise: `a + b + c` on strings trips GCC 12's false -Wrestrict (PR 105651).
        if (!n.label.empty()) n.label += ' ';
        n.label += key.substr(key.rfind('.') + 1);
        n.label += '=';
        n.label += v;
        next.push_back(std::move(n));
      }
    configs = std::move(next);
  }
  if (configs.size() == 1 && configs[0].label.empty()) configs[0].label = "scene settings";
  return configs;
}

}  // namespace

Result<std::vector<BenchConfig>> parse_sweep(const std::string& spec) {
  // Alternatives separated by '|' are concatenated: "a=1;b=2 | a=0;b=0" is two configurations.
  std::vector<BenchConfig> all;
  for (const std::string& product : split(spec, '|')) {
    auto configs = parse_product(product);
    if (!configs) return configs.error();
    if (all.size() + configs->size() > kMaxSweepConfigurations)
      return Error{"--sweep", "", "the sweep expands to more than " +
                                      std::to_string(kMaxSweepConfigurations) + " configurations"};
    all.insert(all.end(), configs->begin(), configs->end());
  }
  return all;
}

std::vector<std::string> bench_csv_columns() {
  return {"scene", "config", "settings", "width", "height", "frames", "frame_ms", "frame_ms_min",
          "frame_ms_max", "cpu_transforms_ms", "cpu_camera_ms", "cpu_shadows_ms",
          "cpu_draw_list_ms", "cpu_render_ms", "gpu_shadow_ms", "gpu_forward_ms", "draw_calls",
          "shadow_draw_calls", "shadow_triangles", "scene_triangles", "shadow_map_mib",
          "receiver_pixels", "misclassified_pct", "false_shadow_pct", "false_light_pct", "rmse",
          "mae", "misclassified_pct_noedge", "false_shadow_pct_noedge", "false_light_pct_noedge",
          "rmse_noedge", "mae_noedge", "reference_mrays_per_s", "stability_points",
          "stability_frames", "stability_step_m", "flicker", "flicker_changed_pct", "mesh_draws",
          "shadow_mesh_draws"};
}

Status run_bench(const BenchOptions& options) {
  auto configs = parse_sweep(options.sweep.empty()    ? default_sweep()
                             : options.sweep == "soft" ? soft_sweep()
                                                       : options.sweep);
  if (!configs) return configs.error();
  std::vector<fs::path> scenes = options.scenes;
  if (scenes.empty()) scenes.push_back(content_dir() / "scenes" / "default.json");
  // Before the first frame: each scene is loaded as it is (its models and textures imported, so
  // a missing or broken asset fails at once), then read with every configuration of the sweep,
  // so a bad value in the sweep fails at once too, named as the sweep's.
  for (const fs::path& scene_path : scenes) {
    const std::vector<std::string> size = {"render.width=" + std::to_string(options.width),
                                           "render.height=" + std::to_string(options.height)};
    if (auto loaded = load_scene(scene_path, size); !loaded) return loaded.error();
    CheckProgress progress(configs->size(), scene_path.filename().string() + ": configurations");
    for (const BenchConfig& config : *configs) {
      progress.update(std::size_t(&config - configs->data()));
      std::vector<std::string> sets = config.sets;
      sets.insert(sets.end(), size.begin(), size.end());
      if (auto checked = read_scene(scene_path, sets); !checked) {
        Error e = checked.error();
        e.message += " (--sweep configuration " + config.label + ")";
        return e;
      }
    }
  }
  // The output folder is the one the user named (--out, or out/bench): made when missing, one
  // level only.
  std::error_code ec;
  if (options.out_dir == BenchOptions{}.out_dir) {
    fs::create_directories(options.out_dir, ec);  // the documented default, out/bench
  } else {
    KASKAD_TRY(check_output_folder_to_make(options.out_dir));  // one level, the one named
    if (!fs::exists(options.out_dir, ec)) fs::create_directory(options.out_dir, ec);
  }
  KASKAD_TRY(check_output_folder(options.out_dir));
  const fs::path csv_path = options.out_dir / "bench.csv";
  // The CSV is rewritten atomically after every row (atomic_file.h): rows survive Ctrl-C and
  // crashes, and the file is never half-written. A run that fails before its first row leaves
  // the folder's previous bench.csv as it was.
  KASKAD_TRY(check_output_path(csv_path));
  std::string csv;
  const auto columns = bench_csv_columns();
  for (std::size_t i = 0; i < columns.size(); ++i) csv += (i ? "," : "") + columns[i];
  csv += "\n";

  gpu::ContextOptions copt;
  copt.headless = true;
  auto player = Player::create(copt);
  if (!player) return player.error();

  if (options.shard_count < 1 || options.shard_index < 0 || options.shard_index >= options.shard_count)
    return Error{"--shard", "", "expected i/n with 0 <= i < n"};
  g_interrupted = false;
  auto previous = std::signal(SIGINT, on_sigint);
  // This shard's runs: i, i + n, ... of the scene x configuration list.
  const std::size_t all_runs = scenes.size() * configs->size();
  std::size_t total = 0;
  for (std::size_t k = std::size_t(options.shard_index); k < all_runs; k += std::size_t(options.shard_count))
    ++total;
  std::size_t run_index = 0;
  std::size_t done = 0;
  const auto t0 = Clock::now();
  std::fprintf(stderr, "kaskad bench: %zu scene(s) x %zu configuration(s), %d frames each at %dx%d -> %s\n",
               scenes.size(), configs->size(), options.frames, options.width, options.height,
               csv_path.string().c_str());
  Status result;
  std::optional<reference::RayTracer> tracer;  // reused while the geometry stays the same
  std::uint64_t tracer_signature = 0;
  for (const fs::path& scene_path : scenes) {
    for (const BenchConfig& config : *configs) {
      if (g_interrupted) break;
      if (run_index++ % std::size_t(options.shard_count) != std::size_t(options.shard_index))
        continue;  // another shard's
      progress_line(done, total, std::chrono::duration<double>(Clock::now() - t0).count(),
               scene_path.stem().string() + ": " + config.label);
      std::vector<std::string> sets = config.sets;
      sets.push_back("render.width=" + std::to_string(options.width));
      sets.push_back("render.height=" + std::to_string(options.height));
      auto scene = load_scene(scene_path, sets);
      if (!scene) {
        result = scene.error();
        break;
      }
      // 1. Timing: warm-up frame + `frames` timed frames, AOVs off (as a game would render).
      RenderRun run;
      run.frames = options.frames + 1;
      run.write_aovs = false;
      auto timing = render_frames(*player, *scene, run);
      if (!timing) {
        result = timing.error();
        break;
      }
      // 2. Accuracy: one more frame with AOVs, against the Embree reference.
      RenderRun aov_run;
      aov_run.frames = 1;
      aov_run.prewarm = true;
      auto with_aovs = render_frames(*player, *scene, aov_run);
      if (!with_aovs) {
        result = with_aovs.error();
        break;
      }
      const Image aov = player->renderer->read_aovs();
      const FrameReport& rep = timing->last;
      std::size_t scene_triangles = 0;
      for (const auto& m : scene->assets.meshes) scene_triangles += m.triangle_count();
      double map_mib = 0.0;
      reference::ShadowMetrics metrics;
      double mrays = 0.0;
      // The light whose visibility the AOV shows.
      const std::vector<ShadowData>& views = with_aovs->last.shadows;
      const ecs::Entity light =
          views.empty() ? ecs::kNullEntity : views[std::size_t(aov_shadow_index(*scene, views.size()))].light;
      if (light.valid()) {
        if (const auto* s = scene->world.try_get<ShadowSettings>(light)) {
          const double bytes = s->depth_format == DepthFormat::d16 ? 2.0 : 4.0;
          // Every layer of the array: cascades (or spot map, cube faces, hemispheres) of every
          // shadow view.
          int layers = 0;
          for (const ShadowData& v : views) layers += v.cascade_count;
          map_mib = double(s->map_size) * s->map_size * bytes * layers / (1024.0 * 1024.0);
        }
        const std::uint64_t signature = geometry_signature(*scene);
        if (!tracer || signature != tracer_signature) {
          tracer.reset();
          auto built = reference::RayTracer::build(*scene);
          if (!built) {
            result = built.error();
            break;
          }
          tracer.emplace(std::move(built.value()));
          tracer_signature = signature;
        }
        const auto rlight = reference::reference_light(scene->world, light);
        auto ref = tracer->shadow_reference(aov, rlight, {});
        if (!ref) {
          result = ref.error();
          break;
        }
        mrays = ref->rays_per_second() * 1e-6;
        auto m = reference::compare_shadows(aov, ref->image);
        if (!m) {
          result = m.error();
          break;
        }
        metrics = *m;
      }
      // 3. Stability: fixed receiver points from that AOV, the camera on its path.
      reference::StabilityStats stability;
      StabilityRun stab_run;
      std::size_t stab_points = 0;
      if (options.stability_frames > 1) {
        auto points = stability_points(aov, options.stability_points);
        if (!points) {
          result = points.error();
          break;
        }
        stab_points = points->positions.size();
        CameraPath path;
        path.frames = options.stability_frames;
        auto measured = measure_stability(*player, *scene, *points, path);
        if (!measured) {
          result = measured.error();
          break;
        }
        stab_run = std::move(measured.value());
        stability = stab_run.stats;
      }
      const bool has_stability = options.stability_frames > 1;
      const double nan = std::numeric_limits<double>::quiet_NaN();
      auto metric = [&](double v) { return light.valid() ? fmt(v) : fmt(nan); };
      std::string settings;
      for (const auto& s : config.sets) {
        if (!settings.empty()) settings += ';';
        settings += s;
      }
      const auto& st = rep.stats;
      std::vector<std::string> row = {
          scene_path.stem().string(), config.label, settings, std::to_string(options.width),
          std::to_string(options.height), std::to_string(options.frames),
          fmt(timing->median_ms()),
          fmt(*std::min_element(timing->frame_ms.begin(), timing->frame_ms.end())),
          fmt(*std::max_element(timing->frame_ms.begin(), timing->frame_ms.end())),
          fmt(rep.transforms_ms), fmt(rep.camera_ms), fmt(rep.shadows_ms), fmt(rep.draw_list_ms),
          fmt(rep.render_ms), fmt(st.shadow_gpu_ms), fmt(st.forward_gpu_ms),
          std::to_string(st.draw_calls), std::to_string(st.shadow_draw_calls),
          std::to_string(st.shadow_triangles), std::to_string(scene_triangles), fmt(map_mib),
          std::to_string(metrics.all.pixels), metric(metrics.all.misclassified_pct),
          metric(metrics.all.false_shadow_pct), metric(metrics.all.false_light_pct),
          metric(metrics.all.rmse), metric(metrics.all.mean_abs_error),
          metric(metrics.outside_edges.misclassified_pct),
          metric(metrics.outside_edges.false_shadow_pct),
          metric(metrics.outside_edges.false_light_pct), metric(metrics.outside_edges.rmse),
          metric(metrics.outside_edges.mean_abs_error), fmt(mrays), std::to_string(stab_points),
          std::to_string(has_stability ? options.stability_frames : 0),
          has_stability ? fmt(stab_run.step) : fmt(nan),
          has_stability ? fmt(stability.flicker) : fmt(nan),
          has_stability ? fmt(stability.changed_pct) : fmt(nan),
          std::to_string(st.mesh_draws), std::to_string(st.shadow_mesh_draws)};
      for (std::size_t i = 0; i < row.size(); ++i) csv += (i ? "," : "") + csv_quote(row[i]);
      csv += "\n";
      if (auto st = write_file_atomic(csv_path, csv); !st) {
        result = st.error();
        break;
      }
      ++done;
    }
    if (!result.ok() || g_interrupted) break;
  }
  std::signal(SIGINT, previous);
  progress_line(done, total, std::chrono::duration<double>(Clock::now() - t0).count(),
           g_interrupted ? "interrupted" : "done");
  end_progress();
  if (done > 0) {
    std::printf("wrote     %s (%zu row%s%s)\n", fs::absolute(csv_path).string().c_str(), done,
                done == 1 ? "" : "s",
                !result.ok() ? ", then failed" : g_interrupted ? ", interrupted" : "");
    // The runs that finished are charted even when a later one failed.
    if (options.chart) {
      const Status charted = draw_charts(csv_path, options.out_dir);
      if (result.ok()) KASKAD_TRY(charted);
    }
  }
  return result;
}

namespace {

// One CSV record: its fields (quotes removed) and the line it starts on (1-based).
struct CsvRecord {
  std::vector<std::string> fields;
  std::size_t line = 0;
};

// The records of a CSV as csv_quote() writes it (RFC 4180: a field with a comma, quote or newline
// is quoted, a quote inside doubled; lines end in \n or \r\n). Blank lines are skipped.
Result<std::vector<CsvRecord>> read_csv_records(const std::string& text, const std::string& file) {
  std::vector<CsvRecord> records;
  std::size_t line = 1, i = 0;
  const auto at = [&](std::size_t n) { return "line " + std::to_string(n); };
  while (i < text.size()) {
    if (text[i] == '\n' || (text[i] == '\r' && i + 1 < text.size() && text[i + 1] == '\n')) {
      i += text[i] == '\r' ? 2 : 1;  // a blank line
      ++line;
      continue;
    }
    CsvRecord rec{{}, line};
    std::string field;
    for (;;) {
      if (i < text.size() && text[i] == '"') {  // a quoted field, to its closing quote
        const std::size_t opened = line;
        for (++i;; ++i) {
          if (i >= text.size())
            return Error{file, at(opened), "a quoted field is not closed (no closing '\"')"};
          if (text[i] == '"') {
            if (i + 1 < text.size() && text[i + 1] == '"') {
              field += '"';
              ++i;
              continue;
            }
            ++i;
            break;
          }
          if (text[i] == '\n') ++line;
          field += text[i];
        }
        if (i < text.size() && text[i] != ',' && text[i] != '\n' &&
            !(text[i] == '\r' && i + 1 < text.size() && text[i + 1] == '\n'))
          return Error{file, at(line), "text after a quoted field's closing quote"};
      } else {
        while (i < text.size() && text[i] != ',' && text[i] != '\n' &&
               !(text[i] == '\r' && i + 1 < text.size() && text[i + 1] == '\n')) {
          if (text[i] == '"') return Error{file, at(line), "a '\"' inside an unquoted field"};
          field += text[i++];
        }
      }
      rec.fields.push_back(std::move(field));
      field.clear();
      if (i < text.size() && text[i] == ',') {
        ++i;
        continue;
      }
      break;  // the end of the line or of the text
    }
    if (i < text.size()) {
      i += text[i] == '\r' ? 2 : 1;
      ++line;
    }
    records.push_back(std::move(rec));
  }
  return records;
}

// What a bench.csv column holds, as run_bench writes it (change together with its row).
enum class ColumnKind {
  text,        // scene, config, settings
  count,       // a non-negative integer (std::to_string of a count or size)
  number,      // a finite number (fmt())
  measurement  // a finite number, or nan where it was not measured (no light, no stability)
};

ColumnKind column_kind(const std::string& name) {
  if (name == "scene" || name == "config" || name == "settings") return ColumnKind::text;
  static const std::set<std::string> counts = {
      "width", "height", "frames", "draw_calls", "shadow_draw_calls", "shadow_triangles",
      "scene_triangles", "receiver_pixels", "stability_points", "stability_frames", "mesh_draws",
      "shadow_mesh_draws"};
  if (counts.count(name)) return ColumnKind::count;
  static const std::set<std::string> measurements = {
      "misclassified_pct", "false_shadow_pct", "false_light_pct", "rmse", "mae",
      "misclassified_pct_noedge", "false_shadow_pct_noedge", "false_light_pct_noedge",
      "rmse_noedge", "mae_noedge", "stability_step_m", "flicker", "flicker_changed_pct"};
  return measurements.count(name) ? ColumnKind::measurement : ColumnKind::number;
}

// Why `value` cannot be in column `name`, "" when it can. Empty numeric fields are allowed.
std::string field_problem(const std::string& name, const std::string& value) {
  for (unsigned char c : value)
    if (c < 0x20 || c == 0x7f) return "a control character in column '" + name + "'";
  if (name == "scene") {
    // The scene names a chart file, DIR/<scene>.png: a plain file-name stem only.
    if (value.empty()) return "column 'scene' is empty";
    if (value.find_first_of("/\\") != std::string::npos || value.front() == '.')
      return "column 'scene' is '" + value +
             "', not a file-name stem (no '/', '\\' or leading '.'; it names DIR/<scene>.png)";
    if (value.size() > 200) return "column 'scene' is longer than 200 bytes";
    return {};
  }
  const ColumnKind kind = column_kind(name);
  if (kind == ColumnKind::text || value.empty()) return {};
  if (kind == ColumnKind::measurement && (value == "nan" || value == "-nan")) return {};
  if (kind == ColumnKind::count) {
    if (value.find_first_not_of("0123456789") == std::string::npos && value.size() <= 19) return {};
    return "column '" + name + "' is '" + value + "', not a non-negative integer";
  }
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(value.c_str(), &end);
  const bool whole = end == value.c_str() + value.size() && !std::isspace((unsigned char)value[0]);
  if (!whole || !std::isfinite(v) || errno == ERANGE)
    return "column '" + name + "' is '" + value + "', not a finite number" +
           (kind == ColumnKind::measurement ? " (or nan: not measured)" : "");
  return {};
}

}  // namespace

Status merge_bench(const std::vector<fs::path>& dirs, const fs::path& out_dir, bool chart) {
  // Every shard is read and checked before anything is written: a bad row fails the merge with
  // the folder's previous bench.csv and charts as they were.
  const std::vector<std::string> known = bench_csv_columns();
  std::vector<std::string> header;
  fs::path header_file;
  std::string rows;
  std::size_t count = 0;
  for (const fs::path& dir : dirs) {
    const fs::path file = dir / "bench.csv";
    const std::string name = file.string();
    if (std::string why = special_file_error(file); !why.empty()) return Error{name, "", why};
    std::error_code ec;
    if (!fs::is_regular_file(file, ec))
      return Error{name, "", "cannot open (is this a kaskad bench --out folder?)"};
    if (fs::file_size(file, ec) == 0) return Error{name, "line 1", "empty: no header"};
    auto bytes = read_file_bytes(file, std::uintmax_t(1) << 30);
    if (!bytes) return bytes.error();
    const std::string text(bytes->begin(), bytes->end());
    if (const auto nul = text.find('\0'); nul != std::string::npos)
      return Error{name, "line " + std::to_string(1 + std::count(text.begin(), text.begin() + long(nul), '\n')),
                   "a NUL byte: not a text CSV"};
    auto records = read_csv_records(text, name);
    if (!records) return records.error();
    if (records->empty()) return Error{name, "line 1", "empty: no header"};
    const CsvRecord& head = records->front();
    if (header.empty()) {
      std::set<std::string> names;
      for (const std::string& column : head.fields) {
        if (std::find(known.begin(), known.end(), column) == known.end())
          return Error{name, "line " + std::to_string(head.line),
                       "unknown column '" + column + "' (the columns: docs/guide/bench.md)"};
        if (!names.insert(column).second)
          return Error{name, "line " + std::to_string(head.line), "column '" + column + "' twice"};
      }
      if (!names.count("scene")) return Error{name, "line " + std::to_string(head.line), "no 'scene' column"};
      header = head.fields;
      header_file = file;
    } else if (head.fields != header) {
      return Error{name, "line " + std::to_string(head.line), "columns differ from " + header_file.string()};
    }
    for (std::size_t r = 1; r < records->size(); ++r) {
      const CsvRecord& rec = (*records)[r];
      const std::string where = "line " + std::to_string(rec.line);
      if (rec.fields == header) return Error{name, where, "the header repeated as a data row"};
      if (rec.fields.size() != header.size())
        return Error{name, where, std::to_string(rec.fields.size()) + " columns, the header has " +
                                      std::to_string(header.size())};
      for (std::size_t c = 0; c < header.size(); ++c)
        if (std::string why = field_problem(header[c], rec.fields[c]); !why.empty())
          return Error{name, where, why};
      for (std::size_t c = 0; c < rec.fields.size(); ++c) rows += (c ? "," : "") + csv_quote(rec.fields[c]);
      rows += "\n";
      ++count;
    }
  }
  std::string csv;
  for (std::size_t c = 0; c < header.size(); ++c) csv += (c ? "," : "") + header[c];
  csv += "\n" + rows;
  const fs::path csv_path = out_dir / "bench.csv";
  std::error_code ec;
  if (out_dir == BenchOptions{}.out_dir) {
    fs::create_directories(out_dir, ec);  // the documented default, out/bench
  } else {
    KASKAD_TRY(check_output_folder_to_make(out_dir));  // one level, the one named
    if (!fs::exists(out_dir, ec)) fs::create_directory(out_dir, ec);
  }
  KASKAD_TRY(check_output_folder(out_dir));
  KASKAD_TRY(check_output_path(csv_path));
  // The charts are drawn from a copy first: a chart that fails leaves bench.csv as it was.
  if (chart && count > 0) {
    const fs::path draft = out_dir / (".bench.csv.merging." + std::to_string(getpid()));
    KASKAD_TRY(write_file_atomic(draft, csv));
    const Status charted = draw_charts(draft, out_dir);
    fs::remove(draft, ec);
    KASKAD_TRY(charted);
  }
  KASKAD_TRY(write_file_atomic(csv_path, csv));
  std::printf("merged    %zu shard CSVs, %zu rows -> %s\n", dirs.size(), count, csv_path.string().c_str());
  return {};
}

}  // namespace kaskad
