#include "systems/frame.h"

#include <chrono>
#include <cmath>

#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/transform.h"
#include "systems/transform_system.h"

namespace kaskad {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace

namespace {

render::ShadowPass shadow_pass(const ShadowData& shadow, int light_index) {
  render::ShadowPass sp;
  sp.light_index = light_index;
  sp.settings = shadow.settings;
  sp.projection = shadow.projection;
  sp.cascade_count = shadow.cascade_count;
  sp.view_proj = shadow.view_proj;
  sp.splits = shadow.splits;
  sp.texel_size = shadow.texel_size;
  sp.skipped = shadow.skipped;
  return sp;
}

}  // namespace

render::FrameInput build_frame_input(const Scene& scene, const FrameContext& ctx,
                                     const CameraState& camera, const ShadowData& shadow,
                                     const ProbeData& probes,
                                     std::span<const ShadowData> extra) {
  const ecs::World& world = scene.world;
  render::FrameInput in;
  in.width = ctx.width;
  in.height = ctx.height;
  in.camera.view = camera.view;
  in.camera.proj = camera.proj;
  in.camera.position = camera.position;
  in.ambient = scene.render.ambient;
  in.clear_color = scene.render.clear_color;
  in.exposure = scene.render.exposure;
  in.write_aovs = ctx.write_aovs;
  in.aov_shadow_light = scene.render.aov_shadow_light;

  const Material default_material;
  world.view<MeshRenderer, WorldTransform>().each(
      [&](ecs::Entity e, const MeshRenderer& mr, const WorldTransform& wt) {
        if (mr.mesh == kNoMesh) return;
        const Material* mat = world.try_get<Material>(e);
        render::DrawItem d;
        d.mesh = mr.mesh;
        d.model = wt.matrix;
        d.material = mat ? *mat : default_material;
        d.cast_shadows = mr.cast_shadows;
        d.receive_shadows = mr.receive_shadows;
        d.cascade_mask = shadow.cascade_mask(e);
        d.layer = mr.layer;
        for (std::size_t k = 0; k < extra.size() && k + 1 < render::kMaxShadowedLights; ++k)
          d.extra_cascade_masks |= std::uint32_t(extra[k].cascade_mask(e)) << (8 * k);
        if (const auto* wb = world.try_get<WorldBounds>(e)) d.bounds = wb->box;
        // A reflector's own draw reflects its probe's map once one is complete (S3 eq. (3)).
        d.material.features &= ~(render::VariantKey::kReflectionCube.mask() |
                                 render::VariantKey::kReflectionSphere.mask() |
                                 render::VariantKey::kReflectionBox.mask());
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
        }
        in.draws.push_back(d);
      });
  for (const ProbeData::Entry& p : probes.probes) in.probes.push_back(p.job);

  world.view<Light, WorldTransform>().each(
      [&](ecs::Entity e, const Light& l, const WorldTransform& wt) {
        const render::LightItem item = light_shading(l, wt.matrix);
        if (e == shadow.light) in.shadow = shadow_pass(shadow, int(in.lights.size()));
        for (std::size_t k = 0; k < extra.size() && k + 1 < render::kMaxShadowedLights; ++k)
          if (e == extra[k].light) {
            if (in.extra_shadows.size() < k + 1) in.extra_shadows.resize(k + 1);
            in.extra_shadows[k] = shadow_pass(extra[k], int(in.lights.size()));
          }
        in.lights.push_back(item);
      });
  return in;
}

render::FrameInput plan_frame(Scene& scene, const FrameContext& ctx, ShadowData& shadow) {
  update_transforms(scene.world, scene.assets);
  const CameraState camera = select_camera(scene.world, float(ctx.width) / float(ctx.height));
  ShadowCascadeState state;
  std::vector<ShadowData> shadows = update_shadows(scene.world, camera, state);
  shadow = shadows.front();
  const ProbeData probes = update_environment_probes(scene.world, ctx.index, /*commit=*/false);
  return build_frame_input(scene, ctx, camera, shadow, probes,
                           std::span<const ShadowData>(shadows).subspan(1));
}

render::FrameInput plan_frame(Scene& scene, const FrameContext& ctx) {
  ShadowData shadow;
  return plan_frame(scene, ctx, shadow);
}

Status prewarm_frame(Scene& scene, render::Renderer& renderer, const FrameContext& ctx,
                     bool shadow_points) {
  return renderer.prewarm(plan_frame(scene, ctx), shadow_points);
}

Status run_frame(Scene& scene, render::Renderer& renderer, const FrameContext& ctx,
                 FrameReport& report) {
  auto t = Clock::now();
  update_transforms(scene.world, scene.assets);
  report.transforms_ms = ms_since(t);

  t = Clock::now();
  report.camera = select_camera(scene.world, float(ctx.width) / float(ctx.height));
  report.camera_ms = ms_since(t);
  if (!report.camera.entity.valid())
    return Error{scene.file.string(), "", "the scene has no camera"};

  t = Clock::now();
  std::vector<ShadowData> shadows = update_shadows(scene.world, report.camera, report.shadow_state);
  report.shadow = std::move(shadows.front());
  report.extra_shadows.assign(std::make_move_iterator(shadows.begin() + 1),
                              std::make_move_iterator(shadows.end()));
  report.shadows_ms = ms_since(t);

  t = Clock::now();
  report.probes = update_environment_probes(scene.world, ctx.index);
  report.probes_ms = ms_since(t);

  t = Clock::now();
  const render::FrameInput input = build_frame_input(scene, ctx, report.camera, report.shadow,
                                                     report.probes, report.extra_shadows);
  report.draw_list_ms = ms_since(t);

  t = Clock::now();
  Status st = renderer.render(input, scene.assets);
  report.render_ms = ms_since(t);
  report.stats = renderer.stats();
  return st;
}

}  // namespace kaskad
