#include "systems/environment_probe_system.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/transform.h"
#include "runtime/core/hash.h"
#include "runtime/core/log.h"
#include "runtime/result/result.h"

namespace kaskad {
namespace {

// A pivot farther than this fraction of the bounds' diagonal from their centre is "off-centre"
// (S3 assumes the pivot is the geometric centre). Engine choice: 5%.
constexpr float kOffCentreFraction = 0.05f;

bool sphere_intersects_box(const glm::vec3& c, float r, const Aabb& b) {
  if (b.empty()) return false;
  const glm::vec3 nearest = glm::clamp(c, b.min, b.max);
  const glm::vec3 d = nearest - c;
  return glm::dot(d, d) <= r * r;
}

void hash_material(Hash& h, const Material& m) {
  h.add(m.base_color);
  h.add(m.base_color_texture);
  h.add(m.metallic);
  h.add(m.roughness);
  h.add(m.normal_texture);
  h.add(m.normal_scale);
  h.add(m.emissive);
  h.add(m.double_sided);
  h.add(m.alpha_mode);
  h.add(m.alpha_cutoff);
  h.add(m.k_s);
  h.add(m.features);
}

}  // namespace

const ProbeData::Entry* ProbeData::find(ecs::Entity e) const {
  for (const Entry& p : probes)
    if (p.entity == e) return &p;
  return nullptr;
}

ProbeWork schedule_probe(const Reflector& r, ProbeState& s, std::uint64_t frame,
                         std::uint64_t signature) {
  ProbeWork work;
  // 1. Static files: one load, shown at once.
  if (r.update == ProbeUpdate::static_file) {
    if (!s.has_map) {
      work.load = true;
      s.has_map = true;
      s.last_capture_frame = frame;
      ++s.captures;
    }
    return work;
  }
  // 2. Is a capture due? (It waits while one is in progress.)
  const bool never = s.captures == 0 && !s.capturing;
  switch (r.update) {
    case ProbeUpdate::first_frame: s.requested = s.requested || never; break;
    case ProbeUpdate::every_n:
      s.requested = s.requested || frame % std::uint64_t(std::max(1, r.every_n)) == 0 || never;
      break;
    case ProbeUpdate::on_change: s.requested = s.requested || never || signature != s.signature; break;
    case ProbeUpdate::static_file: break;
  }
  if (!s.capturing && s.requested) {
    s.capturing = true;
    s.requested = false;
    s.faces_done = 0;
    s.signature = signature;
  }
  if (!s.capturing) return work;
  // 3. The next faces in GL order into the back buffer; swap when all six are there. The first
  // capture renders all six at once: until a map exists the reflector shows none, and slicing it
  // would only delay the first reflection (time slicing spreads the cost of re-captures).
  const int per_frame = s.has_map ? std::clamp(r.faces_per_frame, 1, 6) : 6;
  for (int f = 0, n = 0; f < 6 && n < per_frame; ++f) {
    const std::uint8_t bit = std::uint8_t(1u << f);
    if (s.faces_done & bit) continue;
    work.faces |= bit;
    ++n;
  }
  s.faces_done |= work.faces;
  s.faces_rendered += std::uint64_t(std::popcount(unsigned(work.faces)));
  if (s.faces_done == kAllFaces) {
    work.swap = true;
    s.front = 1 - s.front;
    s.has_map = true;
    s.capturing = false;
    s.last_capture_frame = frame;
    ++s.captures;
  }
  return work;
}

glm::mat4 cube_face_view(int face, const glm::vec3& center) {
  // GL's cube-map table: the face's major axis is the view direction, and "up" is chosen so that
  // NDC +x/+y run along the face's s/t axes (e.g. +X: s = -z, t = -y).
  static const std::array<glm::vec3, 6> forward = {glm::vec3(1, 0, 0),  glm::vec3(-1, 0, 0),
                                                   glm::vec3(0, 1, 0),  glm::vec3(0, -1, 0),
                                                   glm::vec3(0, 0, 1),  glm::vec3(0, 0, -1)};
  static const std::array<glm::vec3, 6> up = {glm::vec3(0, -1, 0), glm::vec3(0, -1, 0),
                                              glm::vec3(0, 0, 1),  glm::vec3(0, 0, -1),
                                              glm::vec3(0, -1, 0), glm::vec3(0, -1, 0)};
  const std::size_t f = std::size_t(std::clamp(face, 0, 5));
  return glm::lookAt(center, center + forward[f], up[f]);
}

glm::mat4 cube_face_projection(float near, float far) {
  return glm::perspective(glm::half_pi<float>(), 1.0f, near, far);
}

std::uint64_t scene_signature(const ecs::World& world, ecs::Entity self, const glm::vec3& center,
                              float far, std::uint32_t exclude_layers) {
  Hash h;
  h.add(center);
  world.view<Light, WorldTransform>().each(
      [&](ecs::Entity e, const Light& l, const WorldTransform& wt) {
        // Field by field: a struct's padding bytes are not part of its value.
        h.add(e.index);
        h.add(l.type);
        h.add(l.color);
        h.add(l.intensity);
        h.add(l.range);
        h.add(l.inner_cone_deg);
        h.add(l.outer_cone_deg);
        h.add(l.cast_shadows);
        h.add(l.angular_size_deg);
        h.add(wt.matrix);
      });
  const Material none;
  world.view<MeshRenderer, WorldTransform, WorldBounds>().each(
      [&](ecs::Entity e, const MeshRenderer& mr, const WorldTransform& wt, const WorldBounds& b) {
        if (e == self || (exclude_layers & (1u << (mr.layer & 31)))) return;
        if (const Imported* imp = world.try_get<Imported>(e); imp && imp->source == self) return;
        if (!sphere_intersects_box(center, far, b.box)) return;
        h.add(e.index);
        h.add(mr.mesh);
        h.add(wt.matrix);
        const Material* m = world.try_get<Material>(e);
        hash_material(h, m ? *m : none);
      });
  return h.value();
}

Aabb reflector_bounds(const ecs::World& world, ecs::Entity e) {
  if (const WorldBounds* wb = world.try_get<WorldBounds>(e); wb && !wb->box.empty()) return wb->box;
  Aabb box;  // a model: the meshes imported under it
  world.view<Imported, WorldBounds>().each([&](ecs::Entity, const Imported& imp, const WorldBounds& b) {
    if (imp.source == e) box.expand(b.box);
  });
  return box;
}

int probe_capture_rounds(int full_captures, bool any_first, int bounces) {
  KASKAD_CHECK(bounces >= kMinProbeBounces && bounces <= kMaxProbeBounces,
               "probe_capture_rounds: bounces must be in [1, 4], was " + std::to_string(bounces));
  // One probe alone gains nothing from a second round: it never sees itself, and nothing else
  // it sees changes between rounds.
  return any_first && full_captures >= 2 ? bounces : 1;
}

ProbeData update_environment_probes(ecs::World& world, std::uint64_t frame, bool commit,
                                    int bounces) {
  ProbeData out;
  struct Planned {
    ecs::Entity entity;
    ProbeState state;
    ProbeWork work;
    bool first = false;  // this frame's capture is the probe's first
  };
  std::vector<Planned> planned;
  world.view<Reflector>().each([&](ecs::Entity e, const Reflector&) {
    const ProbeState* s = world.try_get<ProbeState>(e);
    ProbeState st = s ? *s : ProbeState{};
    // Index and generation: a reflector in a reused entity slot must not get the old maps.
    st.handle = ProbeHandle::of(e.index, e.generation);
    planned.push_back({e, st, {}, false});
  });
  for (Planned& p : planned) {
    const ecs::Entity e = p.entity;
    ProbeState& s = p.state;
    const Reflector& r = world.get<Reflector>(e);
    // 1. Capture centre: explicit, else the world-bounds centre (S3 wants the pivot there).
    const WorldTransform* wt = world.try_get<WorldTransform>(e);
    const glm::vec3 pivot = wt ? glm::vec3(wt->matrix[3]) : glm::vec3(0.0f);
    const Aabb bounds = reflector_bounds(world, e);
    if (r.has_center) {
      s.center = r.center;
    } else if (!bounds.empty()) {
      s.center = bounds.center();
      const float diagonal = glm::length(bounds.extent());
      if (!s.warned_off_centre && glm::length(pivot - s.center) > kOffCentreFraction * diagonal) {
        if (commit)
          log::warn("reflector entity %u: pivot (%g, %g, %g) is off the bounds centre (%g, %g, "
                    "%g); capturing from the bounds centre (S3 assumes the pivot is the centre)",
                    e.index, double(pivot.x), double(pivot.y), double(pivot.z),
                    double(s.center.x), double(s.center.y), double(s.center.z));
        s.warned_off_centre = true;
      }
    } else {
      s.center = pivot;
    }
    // 2. Schedule (the signature only matters for on_change).
    const std::uint64_t signature =
        r.update == ProbeUpdate::on_change
            ? scene_signature(world, e, s.center, r.far, r.exclude_layers)
            : 0;
    const bool had_map = s.has_map;
    p.work = schedule_probe(r, s, frame, signature);
    p.first = p.work.swap && !had_map;
  }
  // 3. Bounce rounds: the probes that capture all six faces this frame take part, when one of
  // them makes its first capture (probe_capture_rounds()).
  int full = 0;
  bool any_first = false;
  for (const Planned& p : planned) {
    full += p.work.faces == kAllFaces && p.work.swap;
    any_first = any_first || p.first;
  }
  const int rounds = probe_capture_rounds(full, any_first, bounces);
  for (Planned& p : planned) {
    const ecs::Entity e = p.entity;
    ProbeState& s = p.state;
    const Reflector& r = world.get<Reflector>(e);
    const ProbeWork& work = p.work;
    const int job_rounds = work.faces == kAllFaces && work.swap ? rounds : 1;
    // Round k writes the buffer round k + 1 reads from, and the last one the new front
    // (capture_buffer()); round 1 writes the back buffer, so with an even number of rounds the
    // front ends where it was.
    if (job_rounds % 2 == 0) s.front = 1 - s.front;
    s.faces_rendered += std::uint64_t(std::popcount(unsigned(work.faces))) * std::uint64_t(job_rounds - 1);
    // 4. Publish.
    ProbeData::Entry entry;
    entry.entity = e;
    entry.has_map = s.has_map;
    entry.sphere = r.map == ReflectionMap::sphere;
    entry.amount = r.amount;
    render::ProbeJob& job = entry.job;
    job.handle = s.handle;
    job.center = s.center;
    job.near = r.near;
    job.far = r.far;
    job.resolution = r.resolution;
    job.exclude_layers = r.exclude_layers;
    job.faces = work.faces;
    job.faces_per_frame = r.faces_per_frame;
    job.rounds = job_rounds;
    // After a swap s.front is already the buffer just completed; else the back buffer is 1 - front.
    job.target = work.swap ? s.front : 1 - s.front;
    job.visible = s.front;
    job.sphere = entry.sphere;
    job.box = r.box_projection && !entry.sphere;
    job.box_min = r.box_min;
    job.box_max = r.box_max;
    const glm::mat4 proj = cube_face_projection(r.near, r.far);
    for (int f = 0; f < 6; ++f) job.view_proj[std::size_t(f)] = proj * cube_face_view(f, s.center);
    if (work.load)
      if (const StaticEnvMap* env = world.try_get<StaticEnvMap>(e)) job.env_map = env->index;
    out.faces_this_frame += std::popcount(unsigned(work.faces)) * job_rounds;
    out.captures_this_frame += (work.swap || work.load) ? 1 : 0;
    out.captures_total += s.captures;
    out.faces_total += s.faces_rendered;
    out.rounds = std::max(out.rounds, job_rounds);
    out.probes.push_back(entry);
  }
  if (commit)
    for (const Planned& p : planned) world.emplace<ProbeState>(p.entity, p.state);
  return out;
}

}  // namespace kaskad
