#include "runtime/core/median.h"
#include "runtime/app/player.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>

#include "runtime/assets/scene_io.h"
#include "components/light.h"
#include "runtime/core/file_io.h"
#include "runtime/core/log.h"
#include "systems/animation_system.h"
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

namespace {

bool is_gltf(const std::filesystem::path& file) {
  const std::string ext = lowercase_extension(file);
  return ext == ".gltf" || ext == ".glb";
}

// The direction of the first shadowed directional light (else the first directional light,
// else straight down): the ground must catch its shadow.
glm::vec3 sun_direction(const ecs::World& world) {
  glm::vec3 any{0.0f}, shadowed{0.0f};
  world.view<Light, WorldTransform>().each(
      [&](ecs::Entity, const Light& l, const WorldTransform& wt) {
        if (l.type != LightType::directional) return;
        const glm::vec3 d = light_direction(wt.matrix);
        if (any == glm::vec3(0.0f)) any = d;
        if (l.cast_shadows && shadowed == glm::vec3(0.0f)) shadowed = d;
      });
  if (shadowed != glm::vec3(0.0f)) return shadowed;
  return any != glm::vec3(0.0f) ? any : glm::vec3(0.0f, -1.0f, 0.0f);
}

}  // namespace

namespace {

// Everything after parsing: instantiation, then the load phase (see load_scene in player.h);
// `later` are overrides of entities only instantiation makes.
Result<Scene> finish_load(Result<Scene> scene, const std::filesystem::path& file,
                          const std::vector<std::string>& later) {
  if (!scene) return scene.error();
  auto manifest = render::FeatureManifest::load(content_dir() / "shaders" / "features.json");
  if (!manifest) return manifest.error();
  KASKAD_TRY(instantiate_scene(*scene, &manifest.value()));
  // Animated models as the first frame shows them (clips at their time, not advanced), and the
  // bounds of their skinned and morphed meshes from that pose: a skinned mesh is placed by its
  // joints, not by its node's transform, which framing must not read either.
  const auto pose = [&] {
    update_animations(scene->world, scene->assets, 0.0);
    update_transforms(scene->world, scene->assets);
    update_deformers(scene->world, scene->assets);
  };
  pose();
  // The models' bounds, before a ground is added: what auto_frame cameras frame.
  const Aabb models = scene_bounds(scene->world);
  // Resolved here, not written back: the scene keeps "auto", so saving it (the editor) writes
  // what the file said.
  GroundMode ground = scene->render.ground;
  if (ground == GroundMode::automatic) ground = is_gltf(file) ? GroundMode::on : GroundMode::none;
  ecs::Entity ground_entity = ecs::kNullEntity;
  if (ground == GroundMode::on && !models.empty())
    ground_entity = add_ground(*scene, ground_extent(models, sun_direction(scene->world)));
  // Overrides of imported entities (glTF nodes by name) and of the ground.
  for (const std::string& o : later) KASKAD_TRY(apply_entity_override(*scene, o));
  if (!later.empty() || ground_entity.valid()) pose();
  // Cameras frame the models; their near/far also take in the ground.
  Aabb framed;
  scene->world.view<WorldBounds>().each([&](ecs::Entity e, const WorldBounds& b) {
    if (e != ground_entity) framed.expand(b.box);
  });
  frame_auto_cameras(scene->world, framed, scene_bounds(scene->world),
                     float(scene->render.width) / float(scene->render.height));
  // A camera with its own aspect gets an output of that aspect, never a stretched image.
  const glm::ivec2 fitted =
      fit_output_to_camera(scene->world, scene->render.width, scene->render.height);
  if (fitted != glm::ivec2(scene->render.width, scene->render.height)) {
    log::info("the camera's aspect ratio is %.4g: output %dx%d (fitted inside %dx%d)",
              double(float(fitted.x) / float(fitted.y)), fitted.x, fitted.y,
              scene->render.width, scene->render.height);
    scene->render.width = fitted.x;
    scene->render.height = fitted.y;
  }
  for (const std::string& w :
       camera_warnings(scene->world, float(scene->render.width) / float(scene->render.height),
                       scene->render.height))
    log::warn_once("%s", w.c_str());
  return scene;
}

}  // namespace

Result<Scene> load_scene(const std::filesystem::path& file,
                         const std::vector<std::string>& overrides) {
  log::set_context(file.string());  // per-frame warnings name the scene they come from
  std::vector<std::string> later;  // overrides of entities the document does not hold
  auto scene = read_scene(file, overrides, &later);
  return finish_load(std::move(scene), file, later);
}

Result<Scene> load_scene_document(const nlohmann::json& document,
                                  const std::filesystem::path& file) {
  return finish_load(parse_scene(document, file), file, {});
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
  return frame_ms.empty() ? first_frame_ms : median(frame_ms);
}

Result<RenderTimings> render_frames(Player& player, Scene& scene, const RenderRun& run) {
  RenderTimings t;
  FrameContext ctx;
  ctx.width = run.width > 0 ? run.width : scene.render.width;
  ctx.height = run.height > 0 ? run.height : scene.render.height;
  ctx.write_aovs = run.write_aovs;
  ctx.dt = run.dt;
  KASKAD_TRY(player.renderer->check_target_size(ctx.width, ctx.height, run.write_aovs,
                                                scene.render.msaa));
  if (run.prewarm) {
    const auto t0 = std::chrono::steady_clock::now();
    KASKAD_TRY(prewarm_frame(scene, *player.renderer, ctx, player.systems));
    t.prewarm_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  for (int i = 0; i < std::max(1, run.frames); ++i) {
    ctx.index = scene.frames_rendered++;  // carries on across calls (the editor: one per call)
    const auto t0 = std::chrono::steady_clock::now();
    KASKAD_TRY(run_frame(scene, *player.renderer, ctx, player.systems, t.last));
    player.renderer->finish();
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (i == 0) {
      player.renderer->shaders().first_frame_done();
      t.first_frame_ms = ms;
      t.first_probe_rounds = t.last.probes.rounds;
      t.first_probe_faces = t.last.stats.probe_faces;
    } else {
      t.frame_ms.push_back(ms);
    }
  }
  if (run.write_aovs)
    t.last.stats.cascade_receiver_pixels = player.renderer->cascade_pixel_counts();
  return t;
}

}  // namespace kaskad
