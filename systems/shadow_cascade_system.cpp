#include "systems/shadow_cascade_system.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "components/light.h"
#include "components/mesh_renderer.h"
#include "components/name.h"
#include "components/shadow_technique.h"
#include "components/transform.h"
#include "runtime/core/log.h"
#include "runtime/math/local_light_math.h"

namespace kaskad {
namespace {

bool finite_box(const Aabb& b) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(b.min[a]) || !std::isfinite(b.max[a])) return false;
  return true;
}

// The 8 corners of a box in clip space (homogeneous, not divided: points behind a perspective
// camera keep their sign).
std::array<glm::vec4, 8> clip_corners(const glm::mat4& m, const Aabb& b) {
  std::array<glm::vec4, 8> out;
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 c{(i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y,
                      (i & 4) ? b.max.z : b.min.z};
    out[std::size_t(i)] = m * glm::vec4(c, 1.0f);
  }
  return out;
}

// False when all corners lie outside one of the 6 clip planes (-w <= x, y, z <= w): the box is
// certainly outside. True may be a false positive near frustum corners (conservative).
bool maybe_inside(const std::array<glm::vec4, 8>& c) {
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f}) {
      bool all_out = true;
      for (const glm::vec4& p : c)
        if (sign * p[axis] <= p.w) {
          all_out = false;
          break;
        }
      if (all_out) return false;
    }
  return true;
}

bool entity_less(ecs::Entity a, ecs::Entity b) {
  return a.index != b.index ? a.index < b.index : a.generation < b.generation;
}

void set_error(ShadowData& out, const std::string& message) {
  if (out.error.empty()) out.error = message;
}

// Whether any part of the box lies in the half space z <= margin of `view` (a paraboloid
// hemisphere drawn slightly past its rim).
bool in_hemisphere(const glm::mat4& view, const Aabb& box, float margin) {
  const Aabb v = box.transformed(view);
  const float reach = std::max(glm::length(v.min), glm::length(v.max));
  return v.min.z <= margin * reach;
}

// Spot and point lights: the maps' depth range from every box in range, then per layer the
// projection, the skip test (no receiver in the layer) and the casters drawn into it.
void fit_local_light(const Light& light, const LightFrame& frame, ShadowData& out,
                     std::span<const Aabb> caster_boxes,
                     std::span<const ecs::Entity> caster_entities,
                     std::span<const Aabb> receiver_boxes) {
  const ShadowSettings& s = out.settings;
  std::vector<Aabb> boxes(caster_boxes.begin(), caster_boxes.end());
  boxes.insert(boxes.end(), receiver_boxes.begin(), receiver_boxes.end());
  const NearFar range = local_light_near_far(frame.origin, boxes, light.range);
  if (range.empty) {
    out.light = ecs::kNullEntity;  // nothing within range
    return;
  }
  // Texels kept free at the map edges: the lookup's reach (1.5 for the 3x3 PCF), the normal
  // offset, 1 spare.
  const float border = filter_reach_texels(s) + 1.0f + s.normal_offset_bias;
  float tan_half = 0.0f;  // paraboloid maps clip by distance
  if (light.type == LightType::spot || light.type == LightType::area)
    tan_half = spot_tan_half_fov(light.outer_cone_deg, s.map_size, border);
  else if (s.point_mode == PointShadowMode::cube)
    tan_half = cube_tan_half_fov(s.map_size, border);
  const float near = local_light_near(range, tan_half);
  const float far = std::max(range.far * 1.001f, near * 1.01f);  // margin: corners on the far plane
  out.splits[0] = near;
  out.splits[1] = far;
  auto finish_layer = [&](int i, auto&& overlaps) {
    const auto c = std::size_t(i);
    bool any_receiver = false;
    for (const Aabb& b : receiver_boxes) any_receiver = any_receiver || overlaps(b);
    out.skipped[c] = !any_receiver;
    if (out.skipped[c]) return;
    for (std::size_t k = 0; k < caster_boxes.size(); ++k)
      if (overlaps(caster_boxes[k])) out.casters[c].push_back(caster_entities[k]);
    std::sort(out.casters[c].begin(), out.casters[c].end(), entity_less);
  };
  auto frustum_overlaps = [&](int i) {
    return [&, i](const Aabb& b) {
      return !b.empty() && maybe_inside(clip_corners(out.view_proj[std::size_t(i)], b));
    };
  };
  if (light.type == LightType::spot || light.type == LightType::area) {
    out.projection = ShadowProjection::perspective;
    out.cascade_count = 1;
    // An area light's map has the rectangle's axes (its width along the map's x), which its
    // soft shadows take the light's extent along.
    const PerspectiveShadow map =
        fit_spot_shadow(frame.origin, frame.direction, tan_half, near, far, s.map_size,
                        light.type == LightType::area ? frame.up : glm::vec3(0.0f));
    out.view_proj[0] = map.view_proj();
    out.texel_size[0] = map.texel_at_unit_distance;
    finish_layer(0, frustum_overlaps(0));
  } else if (s.point_mode == PointShadowMode::cube) {
    out.projection = ShadowProjection::cube;
    out.cascade_count = kCubeFaces;
    for (int f = 0; f < kCubeFaces; ++f) {
      const PerspectiveShadow map =
          cube_face_shadow(frame.origin, f, tan_half, near, far, s.map_size);
      out.view_proj[std::size_t(f)] = map.view_proj();
      out.texel_size[std::size_t(f)] = map.texel_at_unit_distance;
      finish_layer(f, frustum_overlaps(f));
    }
  } else {
    out.projection = ShadowProjection::dual_paraboloid;
    out.cascade_count = 2;
    const float margin = paraboloid_margin(s.map_size, border);
    out.paraboloid_margin = margin;
    const auto views = paraboloid_views(frame.origin, frame.direction);
    for (int h = 0; h < 2; ++h) {
      out.view_proj[std::size_t(h)] = views[std::size_t(h)];
      out.texel_size[std::size_t(h)] = paraboloid_texel_at_unit_distance(s.map_size, margin);
      finish_layer(h, [&, h](const Aabb& b) {
        return !b.empty() && in_hemisphere(views[std::size_t(h)], b, margin);
      });
    }
  }
}

}  // namespace

std::uint8_t ShadowData::cascade_mask(ecs::Entity e) const {
  std::uint8_t mask = 0;
  for (int i = 0; i < cascade_count; ++i) {
    const auto& list = casters[std::size_t(i)];
    if (std::binary_search(list.begin(), list.end(), e, entity_less)) mask |= std::uint8_t(1u << i);
  }
  return mask;
}

DepthRange visible_receiver_depths(const glm::mat4& view, const glm::mat4& view_proj,
                                   std::span<const Aabb> receivers) {
  // The frustum's 6 planes (a point p is inside when dot(plane, (p, 1)) >= 0 for all) and its
  // 8 corners, in double precision: far/near ratios of 1e5 occur.
  const glm::dmat4 m(view_proj);
  const glm::dvec4 row[4] = {glm::dvec4(m[0][0], m[1][0], m[2][0], m[3][0]),
                             glm::dvec4(m[0][1], m[1][1], m[2][1], m[3][1]),
                             glm::dvec4(m[0][2], m[1][2], m[2][2], m[3][2]),
                             glm::dvec4(m[0][3], m[1][3], m[2][3], m[3][3])};
  std::array<glm::dvec4, 6> planes;
  for (int a = 0; a < 3; ++a) {
    planes[std::size_t(2 * a)] = row[3] + row[a];
    planes[std::size_t(2 * a + 1)] = row[3] - row[a];
  }
  const glm::dmat4 inv = glm::inverse(m);
  std::array<glm::dvec3, 8> frustum_corners;
  for (int i = 0; i < 8; ++i) {
    const glm::dvec4 c = inv * glm::dvec4((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1, 1);
    frustum_corners[std::size_t(i)] = glm::dvec3(c) / c.w;
  }
  const glm::dmat4 v(view);
  DepthRange out{std::numeric_limits<float>::max(), 0.0f};
  auto add = [&](const glm::dvec3& p) {
    const float depth = float(-(v * glm::dvec4(p, 1.0)).z);
    out.near = std::min(out.near, depth);
    out.far = std::max(out.far, depth);
  };
  std::vector<glm::dvec3> poly, next;
  for (const Aabb& b : receivers) {
    if (b.empty()) continue;
    const auto clip = clip_corners(view_proj, b);
    if (!maybe_inside(clip)) continue;
    const glm::dvec3 lo(b.min), hi(b.max);
    // A box whose corners' depths lie within the range found so far cannot widen it (what the
    // frustum leaves of it lies between them): most boxes of a large scene, unclipped.
    float box_near = std::numeric_limits<float>::max(), box_far = -box_near;
    for (int i = 0; i < 8; ++i) {
      const glm::dvec3 p{(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z};
      const float depth = float(-(v * glm::dvec4(p, 1.0)).z);
      box_near = std::min(box_near, depth);
      box_far = std::max(box_far, depth);
    }
    if (box_near >= out.near && box_far <= out.far) continue;
    // Wholly inside (the common case): its corners are the vertices.
    bool inside = true;
    for (const glm::vec4& c : clip)
      inside = inside && std::abs(c.x) <= c.w && std::abs(c.y) <= c.w && std::abs(c.z) <= c.w;
    if (inside) {
      for (int i = 0; i < 8; ++i)
        add({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
      continue;
    }
    // Each face of the box as a quad, clipped by the 6 planes (Sutherland-Hodgman).
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        const int u = (axis + 1) % 3, w = (axis + 2) % 3;
        poly.clear();
        for (int k = 0; k < 4; ++k) {
          glm::dvec3 p;
          p[axis] = side ? hi[axis] : lo[axis];
          p[u] = (k == 1 || k == 2) ? hi[u] : lo[u];
          p[w] = (k >= 2) ? hi[w] : lo[w];
          poly.push_back(p);
        }
        for (const glm::dvec4& pl : planes) {
          next.clear();
          for (std::size_t k = 0; k < poly.size(); ++k) {
            const glm::dvec3& p = poly[k];
            const glm::dvec3& q = poly[(k + 1) % poly.size()];
            const double dp = glm::dot(pl, glm::dvec4(p, 1.0)), dq = glm::dot(pl, glm::dvec4(q, 1.0));
            if (dp >= 0.0) next.push_back(p);
            if ((dp >= 0.0) != (dq >= 0.0)) next.push_back(p + (q - p) * (dp / (dp - dq)));
          }
          poly.swap(next);
          if (poly.empty()) break;
        }
        for (const glm::dvec3& p : poly) add(p);
      }
    // Frustum corners inside the box are vertices of the intersection too.
    const glm::dvec3 slack = 1e-9 * (glm::abs(lo) + glm::abs(hi)) + 1e-12;
    for (const glm::dvec3& c : frustum_corners)
      if (glm::all(glm::greaterThanEqual(c, lo - slack)) && glm::all(glm::lessThanEqual(c, hi + slack)))
        add(c);
  }
  if (out.far == 0.0f) return {};
  return out;
}

DepthRange quantize_depth_range(DepthRange r) {
  KASKAD_CHECK(r.near > 0.0f && r.near <= r.far, "need 0 < near <= far");
  constexpr double kSteps = 4.0;  // per octave: each step is 2^(1/4) = 1.19x
  DepthRange q;
  q.near = float(std::exp2(std::floor(std::log2(double(r.near)) * kSteps) / kSteps));
  q.far = float(std::exp2(std::ceil(std::log2(double(r.far)) * kSteps) / kSteps));
  q.near = std::min(q.near, r.near);  // float rounding must not move an end inwards
  q.far = std::max(q.far, r.far);
  return q;
}

namespace {

// NDC bounds of `box` through the affine map `m` (an orthographic projection): the centre
// mapped, the half-extent through |m| (Arvo's box transform).
Aabb ndc_bounds(const glm::mat4& m, const Aabb& box) {
  // Halves first: min + max overflows for boxes beyond half of float's range.
  const glm::vec3 centre = 0.5f * box.min + 0.5f * box.max, half = 0.5f * box.max - 0.5f * box.min;
  const glm::vec3 c = glm::vec3(m * glm::vec4(centre, 1.0f));
  glm::vec3 e(0.0f);
  for (int col = 0; col < 3; ++col)
    for (int row = 0; row < 3; ++row) e[row] += std::abs(m[col][row]) * half[col];
  return Aabb{c - e, c + e};
}

// Whether `box` certainly lies outside the clip volume of the affine map `m` (an orthographic
// projection: w = 1 everywhere), from its NDC box: the margin covers the rounding by which the
// box's transformed corners could differ from it, so a box this rejects is one maybe_inside()
// rejects too, and it costs one transform instead of eight.
bool clearly_outside_ortho(const glm::mat4& m, const Aabb& box) {
  const Aabb b = ndc_bounds(m, box);
  for (int row = 0; row < 3; ++row) {
    float size = 1.0f + std::abs(m[3][row]);  // a bound on the terms each coordinate sums
    for (int col = 0; col < 3; ++col)
      size += std::abs(m[col][row]) * std::max(std::abs(box.min[col]), std::abs(box.max[col]));
    const float slack = 1e-5f * size;
    if (b.min[row] - slack > 1.0f || b.max[row] + slack < -1.0f) return true;
  }
  return false;
}

bool affine(const glm::mat4& m) {
  return m[0][3] == 0.0f && m[1][3] == 0.0f && m[2][3] == 0.0f && m[3][3] == 1.0f;
}

}  // namespace

std::vector<std::uint32_t> cull_casters(const glm::mat4& light_view_proj,
                                        std::span<const Aabb> casters) {
  const bool ortho = affine(light_view_proj);
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < casters.size(); ++i) {
    if (casters[i].empty() || (ortho && clearly_outside_ortho(light_view_proj, casters[i])))
      continue;
    if (maybe_inside(clip_corners(light_view_proj, casters[i]))) out.push_back(std::uint32_t(i));
  }
  return out;
}

namespace {

// The convex slice with corners `c` (near 0-3, far 4-7, in slice_corners_world()'s order) as its
// six face planes, normals pointing out; a degenerate face bounds nothing and is left out.
struct SlicePlanes {
  std::array<glm::vec3, 6> normal, point;
  int count = 0;

  explicit SlicePlanes(const std::array<glm::vec3, 8>& c) {
    static constexpr int kFaces[6][3] = {{0, 1, 2}, {4, 5, 6}, {0, 1, 5},
                                         {3, 2, 6}, {0, 3, 7}, {1, 2, 6}};
    glm::vec3 centre(0.0f);
    for (const glm::vec3& p : c) centre += p * 0.125f;
    for (const auto& f : kFaces) {
      glm::vec3 n = glm::cross(c[f[1]] - c[f[0]], c[f[2]] - c[f[0]]);
      if (!(glm::dot(n, n) > 0.0f)) continue;
      if (glm::dot(n, centre - c[f[0]]) > 0.0f) n = -n;
      normal[std::size_t(count)] = n;
      point[std::size_t(count)] = c[f[0]];
      ++count;
    }
  }

  // Whether `box` lies wholly outside the slice: outside one of its planes.
  bool outside(const Aabb& box) const {
    for (int i = 0; i < count; ++i) {
      const glm::vec3& n = normal[std::size_t(i)];
      // The box corner farthest against n: outside when even it is in front of the plane.
      const glm::vec3 v = glm::mix(box.max, box.min, glm::vec3(glm::greaterThan(n, glm::vec3(0.0f))));
      if (glm::dot(n, v - point[std::size_t(i)]) > 0.0f) return true;
    }
    return false;
  }
};

}  // namespace

glm::vec4 receiver_rect(const glm::mat4& light_view_proj,
                        const std::array<glm::vec3, 8>& slice_corners,
                        std::span<const Aabb> receivers, float margin_ndc, Aabb* touched) {
  Aabb slice;
  for (const glm::vec3& p : slice_corners) slice.expand(glm::vec3(light_view_proj * glm::vec4(p, 1.0f)));
  const SlicePlanes planes(slice_corners);
  glm::vec2 lo(std::numeric_limits<float>::infinity()), hi(-lo);
  for (const Aabb& box : receivers) {
    if (box.empty()) continue;
    const Aabb b = ndc_bounds(light_view_proj, box);
    if (b.max.x < slice.min.x || b.min.x > slice.max.x || b.max.y < slice.min.y ||
        b.min.y > slice.max.y || b.max.z < slice.min.z || b.min.z > slice.max.z ||
        planes.outside(box))
      continue;
    if (touched) touched->expand(box);
    lo = glm::min(lo, glm::max(glm::vec2(b.min), glm::vec2(slice.min)));
    hi = glm::max(hi, glm::min(glm::vec2(b.max), glm::vec2(slice.max)));
  }
  if (!(lo.x <= hi.x && lo.y <= hi.y)) return glm::vec4(1.0f, 1.0f, -1.0f, -1.0f);
  lo = glm::max(lo - margin_ndc, glm::vec2(-1.0f));
  hi = glm::min(hi + margin_ndc, glm::vec2(1.0f));
  return glm::vec4(lo, hi);
}

bool may_shadow(const Aabb& caster, const Aabb& receivers, const glm::vec3& light_dir) {
  if (receivers.empty()) return false;  // nothing to shadow
  if (caster.empty()) return true;
  for (int a = 0; a < 3; ++a) {
    const float towards_light = -light_dir[a];
    if (towards_light > 0.0f && receivers.min[a] >= caster.max[a]) return false;
    if (towards_light < 0.0f && receivers.max[a] <= caster.min[a]) return false;
    if (towards_light == 0.0f && (receivers.min[a] > caster.max[a] || receivers.max[a] < caster.min[a]))
      return false;
  }
  return true;
}

glm::vec2 light_size_for_shadows(const Light& light) {
  if (light.type == LightType::directional)
    return glm::vec2(2.0f * std::tan(0.5f * glm::radians(light.angular_size_deg)));
  if (light.type == LightType::area) return light.size;
  return glm::vec2(2.0f * light.radius);
}

namespace {

// The maps of one shadowed light (entity `e`, null for none). Errors are logged when they differ
// from `last_error`, which is updated. `previous` is this slot's last result (freeze_cascades).
/// `shared`: for lights after the first, the first light's settings whose shared fields
/// (for_each_shared_field()) apply to every light (one shared
/// texture array, one set of shader features). They are applied before fitting, so texel sizes
/// and the stable fit's snapping use the real map size.
ShadowData fit_shadowed_light(const ecs::World& world, const CameraState& camera, ecs::Entity e,
                              const Light& light_component, const glm::mat4& light_matrix,
                              const ShadowData& previous, std::string& last_error,
                              std::uint64_t frame, const ShadowSettings* shared = nullptr) {
  ShadowData out;
  // 1. The light: its settings and a finite transform.
  out.light = e;
  auto finish = [&]() -> ShadowData {
    if (out.error != last_error) {
      if (!out.error.empty()) log::error("shadows: %s", out.error.c_str());
      last_error = out.error;
    }
    return std::move(out);
  };
  if (!out.light.valid()) return finish();
  if (const auto* s = world.try_get<ShadowSettings>(out.light)) out.settings = *s;
  if (shared)
    for_each_shared_field(out.settings, *shared,
                          [](const char*, auto& mine, const auto& first) { mine = first; });
  const ShadowSettings& s = out.settings;
  if (std::string bad = validate_shadow_settings(s); !bad.empty()) {
    set_error(out, "light " + std::to_string(out.light.index) + ": " + bad);
    out.light = ecs::kNullEntity;
    return finish();
  }
  if (std::string bad = validate_transform(light_matrix); !bad.empty()) {
    set_error(out, "light " + std::to_string(out.light.index) + " transform: " + bad);
    out.light = ecs::kNullEntity;
    return finish();
  }
  LightFrame light;
  light.direction = light_direction(light_matrix);
  light.origin = glm::vec3(light_matrix[3]);
  light.up = glm::vec3(light_matrix[1]);

  // 2. Casters, receivers and the scene box; entities with non-finite bounds are left out.
  Aabb scene;
  std::vector<Aabb> caster_boxes, receiver_boxes;
  std::vector<ecs::Entity> caster_entities;
  world.view<MeshRenderer, WorldBounds>().each(
      [&](ecs::Entity e, const MeshRenderer& mr, const WorldBounds& b) {
        if (b.box.empty()) return;
        if (!finite_box(b.box)) {
          set_error(out, "entity " + std::to_string(e.index) +
                             " has non-finite bounds (NaN or inf transform); left out");
          return;
        }
        scene.expand(b.box);
        if (mr.cast_shadows) {
          caster_boxes.push_back(b.box);
          caster_entities.push_back(e);
        }
        if (mr.receive_shadows) receiver_boxes.push_back(b.box);
      });
  if (scene.empty()) {
    out.light = ecs::kNullEntity;  // nothing to shadow
    return finish();
  }
  out.light_size = light_size_for_shadows(light_component);
  if (light_component.type != LightType::directional) {
    fit_local_light(light_component, light, out, caster_boxes, caster_entities, receiver_boxes);
    return finish();
  }

  // 3. FitMode::scene: the basic map, one cascade around the whole scene at every depth.
  if (s.fit_mode == FitMode::scene) {
    out.cascade_count = 1;
    const LightProjection basic = fit_ortho_light_to_bounds(light.direction, scene);
    out.view_proj[0] = basic.view_proj();
    out.splits[0] = 0.0f;
    out.splits[1] = std::numeric_limits<float>::max();
    const Aabb ls = scene.transformed(basic.view);
    out.texel_size[0] = std::max(ls.max.x - ls.min.x, ls.max.y - ls.min.y) / float(s.map_size);
    out.casters[0] = caster_entities;
    std::sort(out.casters[0].begin(), out.casters[0].end(), entity_less);
    return finish();
  }

  // 4. The camera slice shape; a non-finite or degenerate camera gives no shadow.
  if (!camera.entity.valid()) {
    out.light = ecs::kNullEntity;
    return finish();
  }
  CameraSlice slice;
  slice.camera_world = glm::inverse(camera.view);
  slice.projection = camera.camera.projection;
  slice.fov_y_rad = glm::radians(camera.camera.fov_y_deg);
  slice.ortho_height = camera.camera.ortho_height;
  slice.aspect = camera.aspect;
  slice.near = camera.camera.near;
  slice.far = camera.camera.far;
  if (std::string bad = validate_transform(camera.view); !bad.empty()) {
    set_error(out, "camera transform: " + bad);
    out.light = ecs::kNullEntity;
    return finish();
  }
  if (std::string bad = validate_camera_slice(slice); !bad.empty() || !(slice.near > 0.0f)) {
    set_error(out, "camera: " + (bad.empty() ? std::string("near must be > 0") : bad));
    out.light = ecs::kNullEntity;
    return finish();
  }

  // 5. The depth range (S0 step 3 and S2's tight near/far, taken to the receivers; SDSM's
  // min/max): what the visible receivers occupy, rounded outwards so small camera moves keep
  // it, within [camera near, min(camera far, max_distance)].
  float near = slice.near;
  float far = slice.far;
  if (s.max_distance > 0.0f) far = std::min(far, s.max_distance);
  out.near_requested = near;
  out.far_requested = far;
  const DepthRange seen =
      visible_receiver_depths(camera.view, camera.proj * camera.view, receiver_boxes);
  if (!seen.empty()) {
    const float cap = far;
    const DepthRange need{std::clamp(seen.near, slice.near, cap),
                          std::clamp(seen.far, slice.near, cap)};
    const DepthRange q = quantize_depth_range(need);
    near = std::clamp(q.near, slice.near, cap);
    far = std::clamp(q.far, near, cap);
    // Hysteresis: last frame's range stays while it still holds what is seen, lies within the
    // camera's range and is at most two grid steps looser at either end, so a camera moving
    // through the scene keeps its splits (and stable-fit sizes) instead of stepping whenever a
    // receiver's edge crosses a grid point.
    constexpr float kLooser = 1.4142135f;  // 2^(2/4): two steps of quantize_depth_range
    const bool same_layout = previous.light == out.light &&
                             previous.projection == ShadowProjection::ortho &&
                             previous.cascade_count == s.cascade_count && previous.near_used > 0.0f;
    if (same_layout && previous.near_used <= need.near && previous.far_used >= need.far &&
        previous.near_used >= slice.near && previous.far_used <= cap &&
        previous.near_used * kLooser >= near && previous.far_used <= far * kLooser) {
      near = previous.near_used;
      far = previous.far_used;
    }
  }
  // N distinct splits need some room (split_distances' precondition).
  far = std::max(far, near * (1.0f + 1e-3f * float(s.cascade_count)) + 1e-6f);
  out.near_used = near;
  out.far_used = far;
  const std::vector<float> D =
      split_distances(s.split_scheme, s.cascade_count, near, far, s.lambda);

  // 6. Per cascade (S0 steps 1-5, or S2's stable fit): fit, skip when no receiver, cull casters.
  out.cascade_count = s.cascade_count;
  CascadeFitOptions options;
  options.mode = s.fit_mode;
  options.map_size = s.map_size;
  options.beam_radius = s.beam_radius;
  options.depth = DepthFit::enclose_slice;
  const ShadowGeometry geometry{scene, caster_boxes, receiver_boxes};
  for (int i = 0; i <= s.cascade_count; ++i) out.splits[std::size_t(i)] = D[std::size_t(i)];
  // Debug freeze (MJP's "freeze cascades"): last frame's splits and matrices stay while the
  // camera moves on, so the cascades can be inspected from elsewhere; casters are still culled
  // against the frozen volumes. Only when the previous result has the same light and layout.
  const bool frozen =
      s.freeze_cascades && previous.light == out.light &&
      previous.projection == ShadowProjection::ortho && previous.cascade_count == s.cascade_count &&
      previous.settings.fit_mode == s.fit_mode && previous.settings.map_size == s.map_size;
  if (frozen) {
    out.splits = previous.splits;
    out.near_requested = previous.near_requested;
    out.far_requested = previous.far_requested;
    out.near_used = previous.near_used;
    out.far_used = previous.far_used;
  }
  const bool by_depth = s.selection == CascadeSelection::depth;
  const float margin_ndc =
      2.0f * (filter_reach_texels(s) + s.normal_offset_bias + 1.0f) / float(s.map_size);
  // Far-cascade cadence: last frame's fit of cascade c still serves when its map holds the
  // corners of every point that reads it now and the receivers' rectangle it was drawn over
  // holds theirs (a drawn layer is valid only there).
  const bool same_fit = previous.light == out.light &&
                        previous.projection == ShadowProjection::ortho &&
                        previous.cascade_count == s.cascade_count &&
                        previous.settings.map_size == s.map_size &&
                        previous.settings.fit_mode == s.fit_mode;
  const int k = s.far_cascade_interval;
  auto still_serves = [&](std::size_t c, const std::array<glm::vec3, 8>& reads) {
    if (!same_fit || previous.skipped[c]) return false;
    for (const glm::vec3& p : reads) {
      const glm::vec3 ndc = glm::vec3(previous.view_proj[c] * glm::vec4(p, 1.0f));
      if (!(std::abs(ndc.x) <= 1.0f - margin_ndc && std::abs(ndc.y) <= 1.0f - margin_ndc &&
            std::abs(ndc.z) <= 1.0f))
        return false;
    }
    const glm::vec4 need = receiver_rect(previous.view_proj[c], reads, receiver_boxes, margin_ndc);
    const glm::vec4 have = previous.read_rect[c];
    return need.x > need.z || (need.x >= have.x && need.y >= have.y && need.z <= have.z &&
                               need.w <= have.w);
  };
  for (int i = 0; i < s.cascade_count; ++i) {
    const auto c = std::size_t(i);
    // Points of view depth D[c] - band (D[c] - D[c-1]) on blend into this cascade; the first
    // cascade also serves anything nearer than D[0], so it starts at the camera's near.
    CameraSlice reads = slice;
    reads.near = i == 0 ? camera.camera.near
                        : out.splits[c] - s.blend_band * (out.splits[c] - out.splits[c - 1]);
    reads.far = out.splits[c + 1];
    const std::array<glm::vec3, 8> read_corners = slice_corners_world(reads);
    if (!frozen && k > 1 && i >= 1 && (frame + std::uint64_t(i)) % std::uint64_t(k) != 0 &&
        still_serves(c, read_corners)) {
      out.view_proj[c] = previous.view_proj[c];
      out.texel_size[c] = previous.texel_size[c];
      out.read_rect[c] = previous.read_rect[c];
      out.casters[c] = previous.casters[c];
      out.held |= 1u << i;
      continue;
    }
    if (frozen) {
      out.view_proj[c] = previous.view_proj[c];
      out.texel_size[c] = previous.texel_size[c];
      out.skipped[c] = previous.skipped[c];
    } else {
      slice.near = D[c];
      slice.far = D[c + 1];
      const CascadeFit fit = fit_cascade(slice, light, options, geometry);
      out.view_proj[c] = fit.view_proj();
      out.texel_size[c] = fit.world_units_per_texel;
      out.skipped[c] = fit.empty || receiver_boxes.empty();
    }
    if (out.skipped[c]) continue;
    Aabb served;  // the receivers this cascade serves (depth selection)
    if (by_depth && (s.scissor_to_receivers || s.cull_by_receivers)) {
      glm::vec4 rect =
          receiver_rect(out.view_proj[c], read_corners, receiver_boxes, margin_ndc, &served);
      if (k > 1 && i >= 1 && rect.x <= rect.z) {
        // Kept for up to k - 1 frames while the camera moves on: drawn a quarter wider on every
        // side, so that the receivers of the next frames still fall inside what was drawn.
        const glm::vec2 grow = 0.25f * glm::vec2(rect.z - rect.x, rect.w - rect.y);
        rect = glm::vec4(glm::max(glm::vec2(rect) - grow, glm::vec2(-1.0f)),
                         glm::min(glm::vec2(rect.z, rect.w) + grow, glm::vec2(1.0f)));
      }
      if (s.scissor_to_receivers) out.read_rect[c] = rect;
    }
    for (std::uint32_t k : cull_casters(out.view_proj[c], caster_boxes))
      if (!(by_depth && s.cull_by_receivers) || may_shadow(caster_boxes[k], served, light.direction))
        out.casters[c].push_back(caster_entities[k]);
    std::sort(out.casters[c].begin(), out.casters[c].end(), entity_less);
  }
  return finish();
}

}  // namespace

namespace {

// Every shadowed light's view, in entity order, including the ones that failed (light null,
// `error` set): update_shadows() publishes the others, update_shadow_cascades() the first.
std::vector<ShadowData> fit_shadowed_lights(const ecs::World& world, const CameraState& camera,
                                            ShadowCascadeState& state) {
  struct Shadowed {
    ecs::Entity entity;
    Light light;
    glm::mat4 matrix;
  };
  std::vector<Shadowed> lights;
  int shaded = 0;  // the renderer shades the first kMaxLights lights (FrameInput::lights)
  world.view<Light, WorldTransform>().each(
      [&](ecs::Entity e, const Light& l, const WorldTransform& wt) {
        if (l.cast_shadows && shaded < kMaxLights) lights.push_back({e, l, wt.matrix});
        ++shaded;
      });
  std::vector<ShadowData> out;
  out.reserve(std::size_t(kMaxShadowedLights));  // `shared` points into it
  const ShadowSettings* shared = nullptr;  // the first view's settings
  int layers = 0;
  std::string notice;  // every notice of this frame, logged once while it stays the same
  auto add_notice = [&](const std::string& n) { notice += (notice.empty() ? "" : "; ") + n; };
  if (shaded > kMaxLights)
    add_notice(std::to_string(shaded) + " lights; only the first " + std::to_string(kMaxLights) +
               " are shaded, so only they can cast shadows");
  std::size_t slot = 0;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const Shadowed& l = lights[i];
    const auto* named = world.try_get<Name>(l.entity);
    const std::string name = "light " + (named ? "'" + named->value + "' (" : std::string("(")) +
                             "entity " + std::to_string(l.entity.index) + ")";
    // The first view's projection is a shader feature; the views after it are cascades.
    if (i > 0 && l.light.type != LightType::directional) {
      add_notice(name +
                 ": only the first shadowed light may be a spot or point light; it is lit "
                 "without shadows");
      continue;
    }
    if (slot == std::size_t(kMaxShadowedLights)) {
      add_notice(std::to_string(lights.size()) + " shadowed lights; only the first " +
                 std::to_string(kMaxShadowedLights) + " get shadow maps, " + name +
                 " and the ones after it are lit without shadows");
      break;
    }
    ShadowData d = fit_shadowed_light(world, camera, l.entity, l.light, l.matrix,
                                      state.previous[slot], state.last_errors[slot], state.frame,
                                      shared);
    state.previous[slot] = d;
    ++slot;
    if (d.light.valid()) {
      d.first_layer = layers;
      layers += d.cascade_count;
    }
    out.push_back(std::move(d));
    if (!out.back().light.valid()) continue;  // its error is logged
    if (!shared) {
      shared = &out.back().settings;
      continue;
    }
    // Say which of the shared fields the light's own component asks otherwise.
    if (const auto* own = world.try_get<ShadowSettings>(l.entity)) {
      std::string differ;
      for_each_shared_field(*own, *shared, [&](const char* field, const auto& mine, const auto& first) {
        if (!(mine == first)) differ += std::string(differ.empty() ? "" : ", ") + field;
      });
      if (!differ.empty())
        add_notice(name + ": its " + differ +
                   " differ from the first shadowed light's, whose values apply (one shared "
                   "texture array, one set of shader features)");
    }
  }
  if (notice != state.last_notice) {
    if (!notice.empty()) log::warn_once("shadows: %s", notice.c_str());
    state.last_notice = notice;
  }
  ++state.frame;
  return out;
}

}  // namespace

std::vector<ShadowData> update_shadows(const ecs::World& world, const CameraState& camera,
                                       ShadowCascadeState& state) {
  std::vector<ShadowData> views = fit_shadowed_lights(world, camera, state);
  std::erase_if(views, [](const ShadowData& d) { return !d.light.valid(); });
  return views;
}

ShadowData update_shadow_cascades(const ecs::World& world, const CameraState& camera,
                                  ShadowCascadeState& state) {
  std::vector<ShadowData> views = fit_shadowed_lights(world, camera, state);
  return views.empty() ? ShadowData{} : std::move(views.front());
}

}  // namespace kaskad
