// Reflection probes (S3): what a capture costs and where a cube map is wrong.
//   probe_bench [frames=120] [runs=3]   (build/release/tests/probe_bench)
// 1. Capture cost per face: GL_TIME_ELAPSED of the probe pass divided by the faces it rendered
//    (content/scenes/reflections.json, both probes captured every frame at 128^2), against the
//    forward pass of the main view rendered at the same 128^2 resolution.
// 1b. The pbr model's prefiltering per cube: the probe pass with pbr reflectors minus with s3.
// 2. Frame time (CPU wall, GPU finished) over `frames` frames at 640x360, both probes every_n 10:
//    all six faces at once against time slicing (one face a frame): median and max per run.
// 3. Reflection error: RMSE of the `reflection` AOV (C_t) of a mirror sphere against the Embree
//    mirror-ray reference, in a near room (walls 2.5 m away, the sphere's radius 0.5 m) and a
//    far one (250 m, 100x larger, so the camera image is the same); cube maps assume a distant
//    environment, so only the far room should be nearly exact; and the near room again with box
//    projection onto the room's inner walls.
// Absolute times mean little on llvmpipe: compare the ratios.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/core/median.h"
#include "runtime/app/player.h"
#include "runtime/gpu/context.h"
#include "runtime/reference/reflection_reference.h"
#include "systems/frame.h"

using namespace kaskad;
namespace fs = std::filesystem;

namespace {

Scene load_or_die(const fs::path& file, const std::vector<std::string>& sets) {
  auto s = load_scene(file, sets);
  if (!s) {
    std::fprintf(stderr, "probe_bench: %s\n", s.error().to_string().c_str());
    std::exit(1);
  }
  return std::move(s.value());
}

RenderTimings render_or_die(Player& player, Scene& scene, const RenderRun& run) {
  auto t = render_frames(player, scene, run);
  if (!t) {
    std::fprintf(stderr, "probe_bench: %s\n", t.error().to_string().c_str());
    std::exit(1);
  }
  return std::move(t.value());
}

// A mirror sphere (radius 0.5) in a room of half-size `d` whose six walls are 2x2 tiles of
// distinct emissive colours (unlit: ambient 0, no lights, so the reference shades exactly what
// the rasteriser does). The camera is 2 m from the sphere in both rooms.
fs::path room_scene(float d, bool box, const fs::path& dir) {
  std::string ents;
  const float t = 0.01f * d;  // wall thickness
  int tile = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (int sign = -1; sign <= 1; sign += 2)
      for (int u = 0; u < 2; ++u)
        for (int v = 0; v < 2; ++v, ++tile) {
          float pos[3], size[3];
          const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
          pos[axis] = float(sign) * d;
          size[axis] = t;
          pos[a1] = (float(u) - 0.5f) * d;
          pos[a2] = (float(v) - 0.5f) * d;
          size[a1] = size[a2] = d;
          const float r = float((tile * 37) % 11) / 10.0f, g = float((tile * 53) % 7) / 6.0f,
                      b = float((tile * 71) % 5) / 4.0f;
          char buf[400];
          std::snprintf(buf, sizeof buf,
                        R"({"transform": {"translation": [%g, %g, %g], "scale": [%g, %g, %g]},
                           "primitive": {"shape": "box"}, "renderer": {"cast_shadows": false},
                           "material": {"base_color": [0, 0, 0, 1], "emissive": [%g, %g, %g]}},)",
                        double(pos[0]), double(pos[1]), double(pos[2]), double(size[0]),
                        double(size[1]), double(size[2]), double(r), double(g), double(b));
          ents += buf;
        }
  ents += R"({"name": "mirror", "primitive": {"shape": "sphere", "segments": 128},
              "material": {"base_color": [0, 0, 0, 1], "k_s": 1},
              "reflector": {"update": "first_frame", "resolution": 256, "near": 0.01, "far": 1000)";
  if (box) {
    const float inner = 0.995f * d;  // the walls' inner faces
    char buf[160];
    std::snprintf(buf, sizeof buf, R"(, "box": {"min": [%g, %g, %g], "max": [%g, %g, %g]})",
                  double(-inner), double(-inner), double(-inner), double(inner), double(inner),
                  double(inner));
    ents += buf;
  }
  ents += R"(}},
             {"name": "camera", "transform": {"translation": [0.3, 0.4, 1.93], "look_at": [0, 0, 0]},
              "camera": {"fov_y_deg": 30, "near": 0.05, "far": 2000, "active": true}})";
  const fs::path file = dir / ("room_" + std::to_string(int(d)) + (box ? "_box" : "") + ".json");
  std::ofstream(file) << R"({"kaskad_scene": 1, "render": {"width": 320, "height": 320,
      "ambient": [0, 0, 0], "clear_color": [0, 0, 0], "exposure": 1}, "entities": [)"
                      << ents << "]}";
  return file;
}

}  // namespace

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::max(3, std::atoi(argv[1])) : 120;
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 3;
  gpu::ContextOptions opt;
  opt.headless = true;
  auto player = Player::create(opt);
  if (!player) {
    std::fprintf(stderr, "probe_bench: %s\n", player.error().to_string().c_str());
    return 1;
  }
  const fs::path scene_file = content_dir() / "scenes" / "reflections.json";

  // 1. Capture cost per face against the main view at the face resolution.
  {
    std::vector<double> per_face, main_view;
    for (int r = 0; r < runs; ++r) {
      Scene s = load_or_die(scene_file, {"mirror_sphere.reflector.every_n=1",
                                         "mirror_plane.reflector.every_n=1",
                                         "mirror_plane.reflector.faces_per_frame=6"});
      RenderRun run;
      run.frames = 8;
      run.write_aovs = false;
      const RenderTimings t = render_or_die(*player, s, run);
      const auto& st = t.last.stats;
      per_face.push_back(st.probe_gpu_ms / std::max(1, st.probe_faces_timed));
      Scene m = load_or_die(scene_file, {"render.width=128", "render.height=128",
                                         "mirror_sphere.reflector.update=first_frame",
                                         "mirror_plane.reflector.update=first_frame"});
      const RenderTimings tm = render_or_die(*player, m, run);
      main_view.push_back(tm.last.stats.forward_gpu_ms);
    }
    std::printf("capture   GPU per face %.3f ms (128^2, 2 probes x 6 faces a frame); main view "
                "forward pass at 128x128 %.3f ms; ratio %.2f (medians of %d runs)\n",
                median(per_face), median(main_view), median(per_face) / median(main_view), runs);
  }

  // 1b. The pbr reflection model's prefiltering (SH and GGX levels after each capture): the
  // probe pass's GPU time with both reflectors captured every frame, s3 against pbr.
  {
    std::vector<double> s3_ms, pbr_ms;
    int prefilters = 0;
    for (int r = 0; r < runs; ++r)
      for (const char* model : {"s3", "pbr"}) {
        const std::string m = model;
        Scene s = load_or_die(scene_file, {"mirror_sphere.reflector.every_n=1",
                                           "mirror_plane.reflector.every_n=1",
                                           "mirror_plane.reflector.faces_per_frame=6",
                                           "mirror_sphere.material.reflection_model=" + m,
                                           "mirror_plane.material.reflection_model=" + m});
        RenderRun run;
        run.frames = 8;
        run.write_aovs = false;
        const RenderTimings t = render_or_die(*player, s, run);
        (m == "s3" ? s3_ms : pbr_ms).push_back(t.last.stats.probe_gpu_ms);
        if (m == "pbr") prefilters = t.last.stats.probe_prefilters;
      }
    std::printf("prefilter probe pass GPU %.3f ms with s3, %.3f ms with pbr (%d cubes of 128^2 "
                "prefiltered a frame): %.3f ms per cube (medians of %d runs, interleaved)\n",
                median(s3_ms), median(pbr_ms), prefilters,
                (median(pbr_ms) - median(s3_ms)) / std::max(1, prefilters), runs);
  }

  // 2. every_n 10: six faces at once against one face a frame. Frames are run one by one so each
  // frame's time can be put beside the faces it captured.
  for (const int per_frame : {6, 1}) {
    std::vector<double> medians, maxima, p95s, capture_medians;
    for (int r = 0; r < runs; ++r) {
      const std::string fpf = std::to_string(per_frame);
      Scene s = load_or_die(scene_file, {"mirror_sphere.reflector.faces_per_frame=" + fpf,
                                         "mirror_plane.reflector.faces_per_frame=" + fpf});
      FrameContext ctx;
      ctx.width = s.render.width;
      ctx.height = s.render.height;
      ctx.write_aovs = false;
      if (!prewarm_frame(s, *player->renderer, ctx)) return 1;
      SystemState systems;
      FrameReport report;
      std::vector<double> all, capturing;
      for (int k = 0; k < frames; ++k) {
        ctx.index = std::uint64_t(k);
        const auto t0 = std::chrono::steady_clock::now();
        if (!run_frame(s, *player->renderer, ctx, systems, report)) return 1;
        player->renderer->finish();
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        if (k < 2) continue;  // uploads and first-use costs
        all.push_back(ms);
        if (report.stats.probe_faces > 0) capturing.push_back(ms);
      }
      medians.push_back(median(all));
      maxima.push_back(*std::max_element(all.begin(), all.end()));
      std::vector<double> sorted = all;
      std::sort(sorted.begin(), sorted.end());
      p95s.push_back(sorted[std::size_t(0.95 * double(sorted.size() - 1))]);
      capture_medians.push_back(median(capturing));
    }
    std::printf("every_n10 faces_per_frame %d: frame median %.2f ms, p95 %.2f ms, max %.2f ms; "
                "median of frames that captured %.2f ms (frames 2..%d, medians of %d runs; per run "
                "max:",
                per_frame, median(medians), median(p95s), median(maxima), median(capture_medians),
                frames - 1, runs);
    for (double m : maxima) std::printf(" %.1f", m);
    std::printf(")\n");
  }

  // 3. Reflection error against the ray-traced reference, near and far environment.
  const fs::path dir = fs::temp_directory_path() / "kaskad_probe_bench";
  fs::create_directories(dir);
  for (const auto& [d, box] : {std::pair(2.5f, false), std::pair(2.5f, true), std::pair(250.0f, false)}) {
    Scene s = load_or_die(room_scene(d, box, dir), {});
    RenderRun run;
    run.frames = 2;
    const RenderTimings t = render_or_die(*player, s, run);
    const Image aov = player->renderer->read_aovs();
    auto tracer = reference::RayTracer::build(s);
    if (!tracer) {
      std::fprintf(stderr, "probe_bench: %s\n", tracer.error().to_string().c_str());
      return 1;
    }
    auto ref = reference::reflection_reference(*tracer, aov, reference::reflection_scene(s),
                                               t.last.camera.position);
    if (!ref) {
      std::fprintf(stderr, "probe_bench: %s\n", ref.error().to_string().c_str());
      return 1;
    }
    auto err = reference::compare_reflections(aov, ref->image);
    if (!err) {
      std::fprintf(stderr, "probe_bench: %s\n", err.error().to_string().c_str());
      return 1;
    }
    std::printf("reflection walls at %6.1f m%s (mirror radius 0.5 m, cube 256^2): RMSE %.4f, mean "
                "abs %.4f, max abs %.3f over %zu mirror pixels\n",
                double(d), box ? ", box-projected" : "", err->rmse, err->mean_abs_error, err->max_abs_error, err->pixels);
  }
  return gpu::debug_error_count() > 0 ? 1 : 0;
}
