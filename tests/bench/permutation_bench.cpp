// Shader permutations against the über-shader oracle, and shader start-up cold against warm.
//   permutation_bench [rounds=5] [frames=15] [objects=240]
// A generated scene: a ground plane and `objects` primitives over 8 materials with different
// features (6 material files from content/materials, 2 inline). Each round renders `frames`
// frames with each renderer, interleaved, and reports median frame times and their ratio; the
// summary is the median over rounds. Start-up: programs built from source (empty binary cache,
// Mesa's own shader cache off) against programs loaded from Kaskad's binary cache.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "runtime/core/median.h"
#include "runtime/app/player.h"
#include "runtime/gpu/context.h"
#include "systems/frame.h"

using namespace kaskad;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

fs::path write_scene(int objects) {
  const fs::path materials = fs::absolute(content_dir() / "materials");
  const char* files[] = {"painted_checker.json", "bumpy_metal.json", "glowing.json",
                         "foliage_card.json",    "textured_bumpy.json", "plain_white.json"};
  const char* shapes[] = {"box", "sphere", "cylinder", "cone"};
  nlohmann::json doc = {{"kaskad_scene", 1},
                        {"render", {{"width", 640}, {"height", 360}}},
                        {"entities", nlohmann::json::array()}};
  auto& ents = doc["entities"];
  ents.push_back({{"name", "ground"}, {"transform", {{"scale", {60, 1, 60}}}},
                  {"primitive", {{"shape", "plane"}}}, {"material", {{"roughness", 0.9}}}});
  const int side = int(std::ceil(std::sqrt(double(objects))));
  for (int i = 0; i < objects; ++i) {
    const int m = i % 8;
    nlohmann::json e = {{"name", "obj" + std::to_string(i)},
                        {"transform", {{"translation", {(i % side - side / 2) * 1.6, 0.5, (i / side - side / 2) * 1.6}},
                                       {"euler_deg", {0, (i * 37) % 360, 0}}}},
                        {"primitive", {{"shape", shapes[i % 4]}, {"segments", 16}}}};
    if (m < 6) e["material"] = {{"file", (materials / files[m]).string()}};
    else if (m == 6) e["material"] = {{"base_color", {0.2, 0.5, 0.8, 1}}, {"metallic", 0.5}};
    else e["material"] = {{"base_color", {0.9, 0.9, 0.2, 1}}, {"emissive", {0.3, 0.3, 0.0}}};
    ents.push_back(e);
  }
  ents.push_back({{"name", "sun"}, {"transform", {{"direction", {0.4, -0.7, -0.55}}}},
                  {"light", {{"type", "directional"}, {"intensity", 1.8}, {"cast_shadows", true}}}});
  ents.push_back({{"name", "camera"}, {"transform", {{"translation", {0, 14, 22}}, {"look_at", {0, 0, 0}}}},
                  {"camera", {{"fov_y_deg", 50}, {"near", 0.5}, {"far", 200}, {"active", true}}}});
  const fs::path out = fs::temp_directory_path() / "kaskad_permutation_bench.json";
  std::ofstream(out) << doc.dump(1);
  return out;
}

std::unique_ptr<render::Renderer> make(bool oracle, const fs::path& cache) {
  render::RendererOptions o;
  o.uber_oracle = oracle;
  o.shader_cache_dir = cache;
  auto r = render::Renderer::create(content_dir() / "shaders", o);
  if (!r) {
    std::fprintf(stderr, "permutation_bench: %s\n", r.error().to_string().c_str());
    std::exit(1);
  }
  return std::move(r.value());
}

}  // namespace

int main(int argc, char** argv) {
  const int rounds = argc > 1 ? std::atoi(argv[1]) : 5;
  const int frames = argc > 2 ? std::atoi(argv[2]) : 15;
  const int objects = argc > 3 ? std::atoi(argv[3]) : 240;
  gpu::ContextOptions opt;
  opt.headless = true;
  auto ctx = gpu::Context::create(opt);
  if (!ctx) {
    std::fprintf(stderr, "permutation_bench: %s\n", ctx.error().to_string().c_str());
    return 1;
  }
  auto scene = load_scene(write_scene(objects));
  if (!scene) {
    std::fprintf(stderr, "permutation_bench: %s\n", scene.error().to_string().c_str());
    return 1;
  }
  FrameContext fc;
  fc.width = scene->render.width;
  fc.height = scene->render.height;
  fc.write_aovs = false;
  const auto requests = render::required_programs(plan_frame(*scene, fc));
  std::printf("scene: %d objects + ground, 8 materials, %zu programs (forward + depth), %dx%d, %s\n",
              objects, requests.size(), fc.width, fc.height, (*ctx)->description().c_str());

  // 1. Frame time: variants vs the über-shader oracle, interleaved rounds.
  {
  auto variants = make(false, {});
  auto oracle = make(true, {});
  auto frame_ms = [&](render::Renderer& r) {
    std::vector<double> ms;
    SystemState systems;
    FrameReport rep;
    for (int i = 0; i < frames; ++i) {
      fc.index = std::uint64_t(i);
      const auto t0 = Clock::now();
      if (auto st = run_frame(*scene, r, fc, systems, rep); !st) {
        std::fprintf(stderr, "permutation_bench: %s\n", st.error().to_string().c_str());
        std::exit(1);
      }
      r.finish();
      if (i > 0) ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    }
    return median(ms);
  };
  frame_ms(*variants);  // warm-up: compiles, uploads
  frame_ms(*oracle);
  std::vector<double> ratios, vms, oms;
  for (int round = 0; round < rounds; ++round) {
    const double v = frame_ms(*variants), o = frame_ms(*oracle);
    vms.push_back(v);
    oms.push_back(o);
    ratios.push_back(v / o);
    std::printf("round %d: permutations %.2f ms, uber oracle %.2f ms, ratio %.3f\n", round + 1, v, o, v / o);
  }
  std::printf("frame time: permutations %.2f ms, uber oracle %.2f ms (medians); ratio median %.3f\n",
              median(vms), median(oms), median(ratios));
  }

  // 2. Start-up: programs from source (cold) vs from the binary cache (warm). Mesa keeps its own
  // on-disk shader cache, read when a context is made: each round makes a fresh context with an
  // empty Mesa cache folder, so "cold" is cold. (MESA_SHADER_CACHE_DISABLE would also turn off
  // llvmpipe's program binaries.)
  ctx->reset();
  const fs::path cache = fs::temp_directory_path() / "kaskad_permutation_bench_cache";
  std::vector<double> cold, warm, startup_ratios;
  for (int round = 0; round < rounds; ++round) {
    const fs::path mesa_cache = fs::temp_directory_path() / ("kaskad_bench_mesa_" + std::to_string(getpid()));
    fs::remove_all(mesa_cache);
    fs::remove_all(cache);
    setenv("MESA_SHADER_CACHE_DIR", mesa_cache.c_str(), 1);
    auto round_ctx = gpu::Context::create(opt);
    if (!round_ctx) return 1;
    auto c = make(false, cache);
    auto t0 = Clock::now();
    (void)prewarm_frame(*scene, *c, fc);
    const double cold_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    auto w = make(false, cache);
    t0 = Clock::now();
    (void)prewarm_frame(*scene, *w, fc);
    const double warm_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (w->stats().shaders.cache_hits != int(requests.size()))
      std::printf("warning: warm run had %d cache hits of %zu programs\n", w->stats().shaders.cache_hits, requests.size());
    std::printf("start-up round %d: cold %.1f ms (%d compiled), warm %.1f ms (%d from cache)\n", round + 1,
                cold_ms, c->stats().shaders.programs_compiled, warm_ms, w->stats().shaders.cache_hits);
    cold.push_back(cold_ms);
    warm.push_back(warm_ms);
    startup_ratios.push_back(cold_ms / warm_ms);
    c.reset();
    w.reset();
    fs::remove_all(mesa_cache);
  }
  fs::remove_all(cache);
  std::printf("shader start-up: cold %.1f ms, warm %.1f ms (medians); cold/warm ratio median %.2f\n",
              median(cold), median(warm), median(startup_ratios));
  return 0;
}
