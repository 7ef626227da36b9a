// Frame cost against object count, and what a still camera saves (docs/design/shadow_cost.md).
//   scaling_bench [frames=8] [max_instances=100000] [scenes=default,terrain]
//   (build/release/tests/scaling_bench; max_instances 0 runs part 2 alone, scenes "" part 1 alone)
// 1. Scaling: generated scenes of 100, 1,000, 10,000 and 100,000 instances of three meshes
//    (box, sphere, the glTF Box model) with three materials on a ground plane, under a sun with 4
//    stable cascades, 640x360, the camera orbiting slowly (every frame is a new view, so no
//    shadow layer is kept). Per count: CPU ms per phase, GPU ms of the shadow and forward passes,
//    draws per pass, and the median frame (CPU wall, GPU finished).
// 2. Still against moving: the default and terrain scenes at their own size, `frames` frames with
//    the camera still and with it moving, and the sun's shadows off: median frame, shadow GPU ms
//    of the first frame against the median of the others, layers re-rendered.
// Absolute times mean little on llvmpipe (and less on a loaded machine): compare the ratios.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "components/camera.h"
#include "components/transform.h"
#include "runtime/core/median.h"
#if __has_include("runtime/core/memory.h")  // trees from before it build without it
#include "runtime/core/memory.h"
#define SCALING_BENCH_KEEPS_MEMORY 1
#endif
#include "runtime/app/player.h"
#include "runtime/gpu/context.h"
#include "systems/frame.h"

using namespace kaskad;
namespace fs = std::filesystem;

namespace {

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "scaling_bench: %s\n", what.c_str());
  std::exit(1);
}

// A field of `n` instances on a square grid (spacing 1.5 m), cycling box, sphere and glTF box,
// three materials (the glTF box keeps its own), varied heights and turns from the index; the ground under them.
fs::path write_field(int n, const fs::path& dir) {
  const int side = int(std::ceil(std::sqrt(double(n))));
  const double half = 0.75 * side;
  const fs::path file = dir / ("field_" + std::to_string(n) + ".json");
  std::ofstream out(file);
  out << R"({ "kaskad_scene": 1,
  "render": { "width": 640, "height": 360, "ambient": [0.06, 0.07, 0.09], "ground": "none" },
  "shadow": { "map_size": 2048, "cascade_count": 4, "fit_mode": "stable", "filter": "pcf3x3" },
  "entities": [
    { "name": "ground", "transform": { "scale": [)"
      << 2 * half + 4 << ", 1, " << 2 * half + 4 << R"(] }, "primitive": { "shape": "plane" },
      "material": { "base_color": [0.6, 0.6, 0.55, 1], "roughness": 0.9 } },
    { "name": "sun", "transform": { "direction": [0.5, -0.6, -0.45] },
      "light": { "type": "directional", "intensity": 1.7, "cast_shadows": true } },
    { "name": "camera", "transform": { "translation": [0, 10, 20], "look_at": [0, 0, 0] },
      "camera": { "fov_y_deg": 50, "near": 0.1, "far": 200, "active": true } })";
  const char* colours[3] = {"[0.75, 0.25, 0.2, 1]", "[0.2, 0.45, 0.75, 1]", "[0.3, 0.7, 0.35, 1]"};
  for (int i = 0; i < n; ++i) {
    const double x = -half + 1.5 * (i % side) + 0.75, z = -half + 1.5 * (i / side) + 0.75;
    const double y = 0.5 + 0.3 * ((i * 7919) % 5);
    out << ",\n    { \"transform\": { \"translation\": [" << x << ", " << y << ", " << z
        << "], \"euler_deg\": [0, " << (i * 37) % 360 << ", 0], \"scale\": [0.8, 0.8, 0.8] }, ";
    if (i % 3 == 2) {
      out << "\"model\": { \"path\": \"" << (content_dir() / "models/Box/glTF-Binary/Box.glb").string()
          << "\" }";
    } else {
      out << "\"primitive\": { \"shape\": \"" << (i % 3 == 0 ? "box" : "sphere")
          << "\", \"segments\": 12 }";
    }
    if (i % 3 != 2) out << ", \"material\": { \"base_color\": " << colours[(i / 3) % 3] << " }";
    out << " }";
  }
  out << "\n  ]\n}\n";
  return file;
}

struct RunResult {
  double frame_ms = 0, first_frame_ms = 0;
  double transforms_ms = 0, camera_ms = 0, shadows_ms = 0, probes_ms = 0, draw_list_ms = 0,
         render_ms = 0;
  double shadow_gpu_ms = 0, forward_gpu_ms = 0, first_shadow_gpu_ms = 0;
  int draws = 0, shadow_draws = 0, layers = 0, layers_rendered = 0;
};

// `frames` frames of `scene`; `moving` turns the camera about the origin a little every frame.
// Frames go through render_frames() one at a time (the player's frame loop and timing), so this
// file builds against older trees too, for before/after runs.
RunResult run(Player& player, Scene& scene, int frames, bool moving) {
  ecs::Entity camera = ecs::kNullEntity;
  scene.world.view<Camera, Transform>().each(
      [&](ecs::Entity e, const Camera& c, const Transform&) {
        if (c.active && !camera.valid()) camera = e;
      });
  const Transform start = scene.world.get<Transform>(camera);
  RunResult r;
  std::vector<double> ms, phases[6], shadow_gpu, forward_gpu;
  // GPU times arrive a frame late and from frame 1 on: render two more frames than asked.
  for (int f = 0; f < frames + 2; ++f) {
    if (moving) {
      Transform& t = scene.world.get<Transform>(camera);
      const glm::mat4 turn = glm::rotate(glm::mat4(1.0f), 0.01f * float(f), glm::vec3(0, 1, 0));
      t.translation = glm::vec3(turn * glm::vec4(start.translation, 1.0f));
      t.rotation = glm::quat_cast(glm::mat3(turn)) * start.rotation;
    }
    RenderRun one;
    one.frames = 1;
    one.write_aovs = false;
    one.prewarm = f == 0;
    auto t = render_frames(player, scene, one);
    if (!t) die(t.error().to_string());
    const double frame = t->first_frame_ms;
    const FrameReport& report = t->last;
    const render::FrameStats& s = report.stats;
    if (f == 0) r.first_frame_ms = frame;
    if (f == 2) r.first_shadow_gpu_ms = s.shadow_gpu_ms;  // frame 1's (frame 0 times uploads)
    if (f < 2) continue;
    ms.push_back(frame);
    const double p[6] = {report.transforms_ms, report.camera_ms,    report.shadows_ms,
                         report.probes_ms,     report.draw_list_ms, report.render_ms};
    for (int i = 0; i < 6; ++i) phases[i].push_back(p[i]);
    if (f > 2) shadow_gpu.push_back(s.shadow_gpu_ms);
    forward_gpu.push_back(s.forward_gpu_ms);
    r.draws = s.draw_calls;
    r.shadow_draws = s.shadow_draw_calls;
    r.layers = s.shadow_layers;
    r.layers_rendered = __builtin_popcount(s.shadow_layers_rendered);
  }
  r.frame_ms = median(ms);
  r.transforms_ms = median(phases[0]);
  r.camera_ms = median(phases[1]);
  r.shadows_ms = median(phases[2]);
  r.probes_ms = median(phases[3]);
  r.draw_list_ms = median(phases[4]);
  r.render_ms = median(phases[5]);
  r.shadow_gpu_ms = median(shadow_gpu);
  r.forward_gpu_ms = median(forward_gpu);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
#ifdef SCALING_BENCH_KEEPS_MEMORY
  keep_freed_memory();  // as `kaskad` does
#endif
  const int frames = argc > 1 ? std::max(3, std::atoi(argv[1])) : 8;
  const int max_instances = argc > 2 ? std::atoi(argv[2]) : 100000;
  gpu::ContextOptions opt;
  opt.headless = true;
  auto player = Player::create(opt);
  if (!player) die(player.error().to_string());
  const fs::path scenes = fs::temp_directory_path() / "kaskad_scaling_bench";
  fs::create_directories(scenes);

  std::printf("1. scaling (640x360, sun with 4 stable cascades, camera orbiting; medians of %d "
              "frames)\n",
              frames);
  std::printf("%9s %9s %8s %8s %8s %8s %9s %9s %8s %8s %9s\n", "instances", "frame ms",
              "xform ms", "shadow", "drawlist", "render", "GPU shad", "GPU fwd", "draws",
              "shd draws", "load s");
  double at_1000 = 0.0;
  for (int n : {100, 1000, 10000, 100000}) {
    if (n > max_instances) break;
    const fs::path file = write_field(n, scenes);
    const auto t0 = std::chrono::steady_clock::now();
    auto scene = load_scene(file);
    if (!scene) die(scene.error().to_string());
    const double load_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const RunResult r = run(*player, *scene, n >= 100000 ? std::min(frames, 3) : frames, true);
    std::printf("%9d %9.1f %8.2f %8.2f %8.2f %8.2f %9.2f %9.2f %8d %8d %9.1f\n", n, r.frame_ms,
                r.transforms_ms, r.shadows_ms, r.draw_list_ms, r.render_ms, r.shadow_gpu_ms,
                r.forward_gpu_ms, r.draws, r.shadow_draws, load_s);
    if (n == 1000) at_1000 = r.frame_ms;
    if (n == 10000 && at_1000 > 0)
      std::printf("          10,000 / 1,000 instances: frame %.2fx (asked: at most 2x)\n",
                  r.frame_ms / at_1000);
    std::fflush(stdout);
  }

  std::printf("\n2. still camera against moving camera (own size; medians of %d frames)\n", frames);
  std::printf("%-9s %-19s %9s %14s %14s %9s\n", "scene", "camera", "frame ms", "GPU shadow 1st",
              "GPU shadow med", "layers");
  std::vector<std::string> names;
  for (std::string list = argc > 3 ? argv[3] : "default,terrain"; !list.empty();) {
    const size_t comma = list.find(',');
    if (comma != 0) names.push_back(list.substr(0, comma));
    list = comma == std::string::npos ? "" : list.substr(comma + 1);
  }
  for (const std::string& name : names) {
    const fs::path file = content_dir() / "scenes" / (name + ".json");
    if (!fs::exists(file)) die("no scene " + file.string());
    double off = 0.0, moving = 0.0, still = 0.0;
    for (const char* mode : {"still", "still, no vis. cache", "moving", "shadows off"}) {
      const bool shadows = std::string(mode) != "shadows off";
      const bool uncached = std::string(mode) == "still, no vis. cache";
      auto scene = load_scene(file, shadows ? uncached ? std::vector<std::string>{"render.visibility_cache=false"}
                                                       : std::vector<std::string>{}
                                            : std::vector<std::string>{"sun.light.cast_shadows=false"});
      if (!scene && uncached) continue;  // a tree from before render.visibility_cache
      if (!scene) die(scene.error().to_string());
      const RunResult r = run(*player, *scene, frames, std::string(mode) == "moving");
      std::printf("%-9s %-20s %8.1f %14.2f %14.2f %6d/%d\n", name.c_str(), mode, r.frame_ms,
                  r.first_shadow_gpu_ms, r.shadow_gpu_ms, r.layers_rendered, r.layers);
      if (std::string(mode) == "still") still = r.frame_ms;
      if (std::string(mode) == "moving") moving = r.frame_ms;
      if (!shadows) off = r.frame_ms;
      std::fflush(stdout);
    }
    std::printf("          %s: moving / shadows off %.2fx (asked: at most 2x), still / shadows "
                "off %.2fx (asked: at most 1.2x)\n",
                name.c_str(), moving / off, still / off);
  }
  return 0;
}
