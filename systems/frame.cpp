#include "systems/frame.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "components/animation.h"
#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/shadow_technique.h"
#include "components/transform.h"
#include "runtime/core/log.h"
#include "systems/animation_system.h"
#include "systems/transform_system.h"

namespace kaskad {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace

namespace {

// A shadow view as the renderer draws it; `light_index` is its light's place in
// FrameInput::lights.
render::ShadowView shadow_view(const ShadowData& d, int light_index) {
  render::ShadowView v;
  const ShadowSettings& s = d.settings;
  v.light_index = light_index;
  v.projection = d.projection;
  v.first_layer = d.first_layer;
  v.layer_count = d.cascade_count;
  v.view_proj = d.view_proj;
  v.splits = d.splits;
  v.texel_size = d.texel_size;
  v.skipped = d.skipped;
  v.read_rect = d.read_rect;
  v.held = d.held;
  // The basic map (fit scene) is biased by polygon offset alone, as before the cascades.
  v.normal_offset = d.projection == ShadowProjection::ortho && s.fit_mode == FitMode::scene
                        ? 0.0f
                        : s.normal_offset_bias;
  v.blend_band = s.blend_band;
  v.paraboloid_margin = d.paraboloid_margin;
  // Only the techniques that read the light's size get it: for the others a light that grows
  // changes neither the frame block nor what the visibility cache compares.
  v.light_size = traits(s.technique).needs_light_size ? d.light_size : glm::vec2(0.0f);
  v.pcf_taps = s.pcf_taps;
  v.pcf_radius = s.pcf_radius;
  v.filter_reach = filter_reach_texels(s);
  v.slope_bias = s.slope_bias;
  v.constant_bias = s.constant_bias;
  v.cull = s.cull;
  return v;
}

}  // namespace

const ShadowData& FrameReport::shadow(std::size_t k) const {
  static const ShadowData none;
  return k < shadows.size() ? shadows[k] : none;
}

int aov_shadow_index(const Scene& scene, std::size_t views) {
  const int aov = scene.render.aov_shadow_light;
  return aov >= 0 && aov < int(views) ? aov : 0;
}

render::FrameInput build_frame_input(const Scene& scene, const FrameContext& ctx,
                                     const CameraState& camera,
                                     std::span<const ShadowData> shadows,
                                     const ProbeData& probes) {
  const ecs::World& world = scene.world;
  render::FrameInput in;
  in.width = ctx.width;
  in.height = ctx.height;
  in.camera.view = camera.view;
  in.camera.proj = camera.proj;
  in.camera.position = camera.position;
  in.ambient = scene.render.ambient;
  if (scene.environment_map < scene.assets.env_maps.size()) {
    in.environment = &scene.assets.env_maps[scene.environment_map];
    in.environment_key = scene.environment_serial;
    in.environment_sh = scene.environment_sh;
    in.environment_intensity = scene.render.environment_intensity;
  }
  in.clear_color = scene.render.clear_color;
  in.exposure = scene.render.exposure;
  in.tone_mapping = scene.render.tone_mapping;
  in.write_aovs = ctx.write_aovs;
  in.msaa = scene.render.msaa;
  in.shadow_cache = scene.render.shadow_cache;
  in.shadow_scroll = scene.render.shadow_scroll;
  in.multi_draw = scene.render.multi_draw;
  in.visibility_cache = scene.render.visibility_cache;
  in.visibility_reproject = scene.render.visibility_reproject;
  if (!shadows.empty()) {
    in.shadow_settings = shadows.front().settings;  // its shared fields are every view's
    in.aov_shadow_view = aov_shadow_index(scene, shadows.size());
  }

  // Each entity's shadow layers, by entity index (with its generation): one pass over every
  // layer's casters, instead of a search of every list per draw.
  struct Layers {
    std::uint32_t generation = 0, mask = 0;
  };
  std::vector<Layers> layers_of;
  for (const ShadowData& v : shadows)
    for (int c = 0; c < v.cascade_count; ++c)
      for (ecs::Entity e : v.casters[std::size_t(c)]) {
        if (!world.alive(e)) continue;
        if (e.index >= layers_of.size()) layers_of.resize(std::size_t(e.index) + 1);
        layers_of[e.index].generation = e.generation;
        layers_of[e.index].mask |= 1u << (v.first_layer + c);
      }
  const Material default_material;
  std::vector<ProbeHandle> pbr_probes;  // probes a draw of the pbr reflection model reflects
  const auto renderers = world.view<MeshRenderer, WorldTransform>();
  in.draws.reserve(renderers.size_hint());
  renderers.each(
      [&](ecs::Entity e, const MeshRenderer& mr, const WorldTransform& wt) {
        if (mr.mesh == kNoMesh) return;
        const Material* mat = world.try_get<Material>(e);
        render::DrawItem d;
        d.mesh = mr.mesh;
        d.model = wt.matrix;
        d.material = mat ? *mat : default_material;
        d.cast_shadows = mr.cast_shadows;
        d.receive_shadows = mr.receive_shadows;
        d.shadow_layers = e.index < layers_of.size() && layers_of[e.index].generation == e.generation
                              ? layers_of[e.index].mask
                              : 0u;
        d.layer = mr.layer;
        if (const auto* wb = world.try_get<WorldBounds>(e)) d.bounds = wb->box;
        if (const auto* def = world.try_get<Deformer>(e); def && def->posed != kNoMesh) {
          // Drawn with its posed copy; a skinned pose is in world space already.
          const MeshData& source = scene.assets.meshes[index(mr.mesh)];
          const render::DeformJob job{
              .source = mr.mesh,
              .posed = def->posed,
              .influences = def->skin_matrices.empty() ? 0 : source.deform.influences,
              .vertex_count = std::uint32_t(source.positions.size()),
              .pose = def->pose,
              .first_matrix = std::uint32_t(in.skin_matrices.size()),
              .matrix_count = std::uint32_t(def->skin_matrices.size()),
              .first_weight = std::uint32_t(in.morph_weights.size()),
              .weight_count = std::uint32_t(def->weights.size())};
          in.skin_matrices.insert(in.skin_matrices.end(), def->skin_matrices.begin(),
                                  def->skin_matrices.end());
          in.morph_weights.insert(in.morph_weights.end(), def->weights.begin(), def->weights.end());
          in.deforms.push_back(job);
          d.mesh = def->posed;
          d.pose = def->pose;
          if (!def->skin_matrices.empty()) d.model = glm::mat4(1.0f);
        }
        // A reflector's own draw reflects its probe's map once one is complete (S3 eq. (3)).
        d.material.features &= ~(render::VariantKey::kReflectionCube.mask() |
                                 render::VariantKey::kReflectionSphere.mask() |
                                 render::VariantKey::kReflectionBox.mask() |
                                 render::VariantKey::kReflectionPbr.mask());
        // A mesh imported under a model reflects the model's probe (and stays out of it).
        const ProbeData::Entry* p = probes.find(e);
        if (!p)
          if (const auto* imp = world.try_get<Imported>(e)) p = probes.find(imp->source);
        if (p) {
          d.probe = p->job.handle;
          if (p->has_map) {
            d.material.features |= (p->sphere ? render::VariantKey::kReflectionSphere
                                              : render::VariantKey::kReflectionCube).mask();
            if (p->job.box) d.material.features |= render::VariantKey::kReflectionBox.mask();
            d.reflection_scale = d.material.k_s * p->amount;
          }
          // The pbr model reads the probe's prefiltered cube: sphere maps keep S3's model.
          if (d.material.reflection_model == ReflectionModel::pbr && p->sphere)
            log::warn_once("reflection_model pbr needs a cube-map probe; sphere-map probes keep "
                           "S3's model");
          if (d.material.reflection_model == ReflectionModel::pbr && !p->sphere) {
            pbr_probes.push_back(p->job.handle);
            if (p->has_map) {
              d.material.features |= render::VariantKey::kReflectionPbr.mask();
              d.reflection_scale = p->amount;
            }
          }
        }
        in.draws.push_back(std::move(d));
      });
  for (const ProbeData::Entry& p : probes.probes) {
    in.probes.push_back(p.job);
    in.probes.back().prefilter =
        std::find(pbr_probes.begin(), pbr_probes.end(), p.job.handle) != pbr_probes.end();
  }

  // Lights in entity order; each shadow view learns its light's index.
  in.shadow_views.resize(shadows.size());
  world.view<Light, WorldTransform>().each(
      [&](ecs::Entity e, const Light& l, const WorldTransform& wt) {
        for (std::size_t k = 0; k < shadows.size(); ++k)
          if (e == shadows[k].light) in.shadow_views[k] = shadow_view(shadows[k], int(in.lights.size()));
        in.lights.push_back(light_shading(l, wt.matrix));
      });
  return in;
}

namespace {

// Phases 1-5, timed into `report`. `commit`: advance the probe states (a frame that is rendered)
// or only plan them. False when the scene has no camera (nothing after phase 2 ran).
bool run_systems(Scene& scene, const FrameContext& ctx, SystemState& state, bool commit,
                 FrameReport& report, render::FrameInput& input) {
  if (state.scene != scene.assets.uid) state = SystemState{scene.assets.uid, {}};
  auto t = Clock::now();
  update_animations(scene.world, scene.assets, commit ? ctx.dt : 0.0);
  report.animation_ms = ms_since(t);

  t = Clock::now();
  update_transforms(scene.world, scene.assets);
  update_deformers(scene.world, scene.assets);
  report.transforms_ms = ms_since(t);

  t = Clock::now();
  report.camera = select_camera(scene.world, float(ctx.width) / float(ctx.height));
  report.camera_ms = ms_since(t);
  if (!report.camera.entity.valid()) return false;

  t = Clock::now();
  report.shadows = update_shadows(scene.world, report.camera, state.shadows);
  report.shadows_ms = ms_since(t);

  t = Clock::now();
  report.probes = update_environment_probes(scene.world, ctx.index, commit,
                                            scene.render.probe_bounces);
  report.probes_ms = ms_since(t);

  t = Clock::now();
  input = build_frame_input(scene, ctx, report.camera, report.shadows, report.probes);
  report.draw_list_ms = ms_since(t);
  return true;
}

}  // namespace

render::FrameInput plan_frame(Scene& scene, const FrameContext& ctx, const SystemState& state,
                              FrameReport* report) {
  SystemState planned = state;  // the caller's state stays as it is
  FrameReport local;
  render::FrameInput input;
  run_systems(scene, ctx, planned, /*commit=*/false, report ? *report : local, input);
  return input;
}

Status prewarm_frame(Scene& scene, render::Renderer& renderer, const FrameContext& ctx,
                     const SystemState& state, bool shadow_points) {
  return renderer.prewarm(plan_frame(scene, ctx, state), shadow_points);
}

Status run_frame(Scene& scene, render::Renderer& renderer, const FrameContext& ctx,
                 SystemState& state, FrameReport& report) {
  render::FrameInput input;
  if (!run_systems(scene, ctx, state, /*commit=*/true, report, input))
    return Error{scene.file.string(), "", "the scene has no camera"};
  const auto t = Clock::now();
  Status st = renderer.render(input, scene.assets);
  report.render_ms = ms_since(t);
  report.stats = renderer.stats();
  return st;
}

}  // namespace kaskad
