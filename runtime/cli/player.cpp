#include "runtime/cli/player.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>

#include "runtime/assets/scene_io.h"
#include "systems/camera_system.h"
#include "systems/transform_system.h"

#ifndef KASKAD_CONTENT_DIR
#error "KASKAD_CONTENT_DIR must be defined by the build"
#endif

namespace kaskad {

std::filesystem::path content_dir() {
  if (const char* env = std::getenv("KASKAD_CONTENT_DIR"); env && *env) return env;
  return KASKAD_CONTENT_DIR;
}

Result<Scene> load_scene(const std::filesystem::path& file,
                         const std::vector<std::string>& overrides) {
  auto scene = read_scene(file, overrides);
  if (!scene) return scene.error();
  auto manifest = render::FeatureManifest::load(content_dir() / "shaders" / "features.json");
  if (!manifest) return manifest.error();
  KASKAD_TRY(instantiate_scene(*scene, &manifest.value()));
  update_transforms(scene->world, scene->assets);
  frame_auto_cameras(scene->world, scene_bounds(scene->world),
                     float(scene->render.width) / float(scene->render.height));
  return scene;
}

render::RendererOptions Player::defaults() {
  render::RendererOptions o;
  o.shader_cache_dir = render::default_shader_cache_dir();
  return o;
}

Result<Player> Player::create(const gpu::ContextOptions& options,
                              const render::RendererOptions& renderer_options) {
  Player p;
  auto ctx = gpu::Context::create(options);
  if (!ctx) return ctx.error();
  p.context = std::move(ctx.value());
  auto r = render::Renderer::create(content_dir() / "shaders", renderer_options);
  if (!r) return r.error();
  p.renderer = std::move(r.value());
  return p;
}

double RenderTimings::median_ms() const {
  if (frame_ms.empty()) return first_frame_ms;
  std::vector<double> v = frame_ms;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

Result<RenderTimings> render_frames(Player& player, Scene& scene, const RenderRun& run) {
  RenderTimings t;
  FrameContext ctx;
  ctx.width = run.width > 0 ? run.width : scene.render.width;
  ctx.height = run.height > 0 ? run.height : scene.render.height;
  ctx.write_aovs = run.write_aovs;
  KASKAD_TRY(player.renderer->check_target_size(ctx.width, ctx.height, run.write_aovs));
  if (run.prewarm) {
    const auto t0 = std::chrono::steady_clock::now();
    KASKAD_TRY(prewarm_frame(scene, *player.renderer, ctx));
    t.prewarm_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  t.last.shadow_state = std::move(player.shadow_state);
  for (int i = 0; i < std::max(1, run.frames); ++i) {
    ctx.index = std::uint64_t(i);
    const auto t0 = std::chrono::steady_clock::now();
    const Status st = run_frame(scene, *player.renderer, ctx, t.last);
    player.shadow_state = t.last.shadow_state;
    KASKAD_TRY(st);
    player.renderer->finish();
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (i == 0) {
      player.renderer->shaders().first_frame_done();
      t.first_frame_ms = ms;
    } else {
      t.frame_ms.push_back(ms);
    }
  }
  if (run.write_aovs)
    t.last.stats.cascade_receiver_pixels = player.renderer->cascade_pixel_counts();
  return t;
}

}  // namespace kaskad
