// The Embree reference tracer. Procedure of a shadow reference (shadow_reference):
//   1. build: every MeshRenderer's triangles, transformed to world space on the CPU (the same
//      WorldTransform the renderer uploads), into one Embree triangle geometry per entity; casters
//      are attached to the occluder scene, every geometry to the surface scene; single-sided and
//      alpha-masked geometries get an occlusion filter (caster_face_blocks(), the cut-out);
//   2. per AOV pixel: the rasterised position P and normal N, the origin P + offset * N;
//   3. punctual lights: one shadow ray, traced 16 at a time (rtcOccluded16) along an image row;
//      area lights: sqrt(M) x sqrt(M) jittered strata over the emitter, 16 samples per packet;
//   4. rows are shared out to worker threads through one atomic counter.
#include "runtime/reference/ray_tracer.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <memory>
#include <numbers>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "components/animation.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "runtime/assets/mesh_pose.h"
#include "runtime/reference/row_workers.h"

namespace kaskad::reference {
namespace {

/// An alpha-masked (glTF MASK) geometry's cut-out: what the forward and depth passes discard,
/// alpha = base_color.a x texture alpha < cutoff. A blended (glTF BLEND) caster is cut the same
/// way: it casts where alpha >= cutoff, as the depth pass draws it (Material::alpha_mode). Hits there are rejected by Embree filter
/// functions, so the reference sees the same holes as the rasteriser. The texture is sampled
/// bilinearly at level 0 with repeat wrapping (the GPU may pick a coarser mip level: edges of
/// cut-outs can differ by a texel there).
struct AlphaCutout {
  std::vector<glm::vec2> uvs;           // per vertex
  std::vector<std::uint32_t> indices;   // 3 per kept triangle, by Embree primID
  float factor = 1.0f;                  // base_color.a
  float cutoff = 0.5f;
  int width = 0, height = 0;            // 0: no texture
  std::vector<std::uint8_t> alpha;      // width * height, rows top to bottom (uv (0,0) = row 0)

  float texture_alpha(glm::vec2 uv) const {
    if (width <= 0 || height <= 0) return 1.0f;
    const float x = uv.x * float(width) - 0.5f, y = uv.y * float(height) - 0.5f;
    if (!std::isfinite(x) || !std::isfinite(y)) return 1.0f;
    const float fx = std::floor(x), fy = std::floor(y);
    const float tx = x - fx, ty = y - fy;
    auto texel = [&](float px, float py) {
      const auto wrap = [](float v, int n) {
        const double m = std::fmod(double(v), double(n));
        return int(m < 0.0 ? m + n : m) % n;
      };
      return float(alpha[std::size_t(wrap(py, height)) * std::size_t(width) +
                         std::size_t(wrap(px, width))]) / 255.0f;
    };
    const float top = texel(fx, fy) * (1.0f - tx) + texel(fx + 1.0f, fy) * tx;
    const float bottom = texel(fx, fy + 1.0f) * (1.0f - tx) + texel(fx + 1.0f, fy + 1.0f) * tx;
    return top * (1.0f - ty) + bottom * ty;
  }

  /// Whether the hit at Embree's barycentrics (u, v) on triangle `prim` is cut away.
  bool cut(unsigned prim, float u, float v) const {
    if (std::size_t(prim) * 3 + 2 >= indices.size()) return false;
    const glm::vec2 a = uvs[indices[prim * 3]], b = uvs[indices[prim * 3 + 1]],
                    c = uvs[indices[prim * 3 + 2]];
    const glm::vec2 uv = (1.0f - u - v) * a + u * b + v * c;
    return factor * texture_alpha(uv) < cutoff;
  }
};

/// What the filter functions need to know of one geometry (its Embree user data).
struct GeometryRules {
  bool double_sided = false;  // Material::double_sided
  bool mirrored = false;      // the world transform mirrors: front faces wind clockwise
  std::optional<AlphaCutout> cutout;
};

/// The context of every occlusion query on the occluder scene: the cull of the light its rays
/// go to, for caster_face_blocks() in occlusion_filter(). Embree hands filters the pointer to
/// `embree`, the first member (standard layout, so the pointer is the context's).
struct ShadowContext {
  RTCIntersectContext embree;
  CullMode cull = CullMode::back;
};
static_assert(std::is_standard_layout_v<ShadowContext>);

/// Whether the hit of ray i of a filter call is on a front face that faces the light. Every
/// shadow ray runs from a receiver towards the light (or towards its sample of an area light),
/// so the light lies on the side of the triangle's plane the ray leaves it to: the face faces
/// the light when its normal points along the ray. The front face's normal is Embree's
/// geometric normal Ng = (v1 - v0) x (v2 - v0) of the world-space triangle (counter-clockwise),
/// reversed for mirroring transforms.
bool front_faces_light(const RTCFilterFunctionNArguments* args, unsigned i,
                       const GeometryRules& g) {
  const unsigned n = args->N;
  const glm::vec3 ng{RTCHitN_Ng_x(args->hit, n, i), RTCHitN_Ng_y(args->hit, n, i),
                     RTCHitN_Ng_z(args->hit, n, i)};
  const glm::vec3 d{RTCRayN_dir_x(args->ray, n, i), RTCRayN_dir_y(args->ray, n, i),
                    RTCRayN_dir_z(args->ray, n, i)};
  return (glm::dot(ng, d) > 0.0f) != g.mirrored;
}

/// Embree occlusion filter: rejects hits on faces that do not block the light
/// (caster_face_blocks()) and hits in the alpha cut-out.
void occlusion_filter(const RTCFilterFunctionNArguments* args) {
  const auto& g = *static_cast<const GeometryRules*>(args->geometryUserPtr);
  const auto& c = *reinterpret_cast<const ShadowContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    if (!caster_face_blocks(c.cull, g.double_sided, front_faces_light(args, i, g)) ||
        (g.cutout && g.cutout->cut(RTCHitN_primID(args->hit, args->N, i),
                                   RTCHitN_u(args->hit, args->N, i),
                                   RTCHitN_v(args->hit, args->N, i))))
      args->valid[i] = 0;
  }
}

/// Embree intersection filter (mirror rays, receiver look-ups): rejects hits in the cut-out.
void alpha_cutout_filter(const RTCFilterFunctionNArguments* args) {
  const AlphaCutout& cutout = *static_cast<const GeometryRules*>(args->geometryUserPtr)->cutout;
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    if (cutout.cut(RTCHitN_primID(args->hit, args->N, i), RTCHitN_u(args->hit, args->N, i),
                   RTCHitN_v(args->hit, args->N, i)))
      args->valid[i] = 0;
  }
}

/// Where Embree's error callback leaves its message for check_device().
struct ErrorLog {
  std::mutex mutex;
  std::string last;
};

}  // namespace

struct RayTracer::Impl {
  RTCDevice device = nullptr;
  RTCScene occluders = nullptr;             // cast_shadows = true
  RTCScene surfaces = nullptr;              // every MeshRenderer
  std::vector<ecs::Entity> surface_entity;  // by geometry ID in `surfaces`
  std::vector<bool> surface_receives;       // MeshRenderer::receive_shadows, by geometry ID
  // By geometry ID: the mesh triangle of each Embree primitive, when triangles were dropped
  // (empty: primitive i is triangle i).
  std::vector<std::vector<std::uint32_t>> surface_triangle;
  bool all_receive = true;                  // every surface receives: no receiver look-ups
  Aabb bounds;
  float offset = RayTracer::kRayOffsetScale;
  std::size_t occluder_triangles = 0;
  std::size_t surface_triangles = 0;

  ErrorLog errors;  // filled by Embree's error callback
  std::vector<std::unique_ptr<GeometryRules>> rules;  // user data of filtered geometries
  std::size_t cutout_geometries = 0;

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl() {
    if (occluders) rtcReleaseScene(occluders);
    if (surfaces) rtcReleaseScene(surfaces);
    if (device) rtcReleaseDevice(device);
  }
};

namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();
constexpr int kPacket = 16;  // rtcOccluded16; the device reports native 16-wide support on AVX-512

const char* error_name(RTCError e) {
  switch (e) {
    case RTC_ERROR_NONE:
      return "no error";
    case RTC_ERROR_UNKNOWN:
      return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
      return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
      return "cancelled";
  }
  return "unrecognised error";
}

void on_embree_error(void* user, RTCError code, const char* message) {
  auto* log = static_cast<ErrorLog*>(user);
  std::lock_guard lock(log->mutex);
  log->last = std::string(error_name(code)) + (message ? std::string(": ") + message : "");
}

/// Status of the device after `what`: rtcGetDeviceError plus the callback's message.
Status check_device(RTCDevice device, ErrorLog& log, const std::string& what) {
  const RTCError code = rtcGetDeviceError(device);
  if (code == RTC_ERROR_NONE) return {};
  std::string message;
  {
    std::lock_guard lock(log.mutex);
    message = log.last.empty() ? error_name(code) : log.last;
  }
  return Error{"", what, "Embree: " + message};
}

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// A unit vector perpendicular to unit `axis`, as close to `hint` as possible.
glm::vec3 perpendicular(const glm::vec3& axis, const glm::vec3& hint) {
  glm::vec3 r = hint - glm::dot(hint, axis) * axis;
  if (glm::dot(r, r) < 1e-12f) {
    // hint parallel to axis: the world axis least parallel to it.
    const glm::vec3 a = glm::abs(axis);
    const glm::vec3 other = (a.x <= a.y && a.x <= a.z) ? glm::vec3(1, 0, 0)
                            : (a.y <= a.z)             ? glm::vec3(0, 1, 0)
                                                       : glm::vec3(0, 0, 1);
    r = other - glm::dot(other, axis) * axis;
  }
  return glm::normalize(r);
}

/// The light with a unit direction (straight down when it has none) and a unit `right`
/// perpendicular to it, whatever the caller filled in.
ReferenceLight prepared(const ReferenceLight& light) {
  ReferenceLight l = light;
  const float len = glm::length(l.direction);
  l.direction = len > 0.0f && std::isfinite(len) ? l.direction / len : glm::vec3(0.0f, -1.0f, 0.0f);
  l.right = perpendicular(l.direction, finite(l.right) ? l.right : glm::vec3(1.0f, 0.0f, 0.0f));
  return l;
}

/// PCG32 (O'Neill 2014, "PCG: a family of simple fast space-efficient statistically good
/// algorithms for random number generation"), XSH-RR output. Seeded per pixel, so results do not
/// depend on which thread traced which row.
class Pcg32 {
 public:
  explicit Pcg32(std::uint64_t seed, std::uint64_t stream = 0x5851f42d4c957f2dULL)
      : inc_((stream << 1u) | 1u) {
    next();
    state_ += seed;
    next();
  }
  std::uint32_t next() {
    const std::uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + inc_;
    const auto xorshifted = std::uint32_t(((old >> 18u) ^ old) >> 27u);
    const auto rot = std::uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }
  /// Uniform in [0, 1): the top 24 bits, so the value is exact in a float and never rounds to 1.
  float uniform() { return float(next() >> 8) * 0x1p-24f; }

 private:
  std::uint64_t state_ = 0;
  std::uint64_t inc_;
};

/// Seed of one pixel's samples: the pixel index and the user seed, mixed (SplitMix64's finaliser)
/// so that neighbouring pixels get unrelated streams.
std::uint64_t pixel_seed(std::size_t pixel, std::uint32_t seed) {
  std::uint64_t z = (std::uint64_t(seed) << 32) ^ std::uint64_t(pixel);
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

struct ShadowRay {
  glm::vec3 origin;
  glm::vec3 direction;  // unit
  float tmax;
};

/// The occlusion context of rays towards `light`.
ShadowContext shadow_context(const ReferenceLight& light) {
  ShadowContext c;
  rtcInitIntersectContext(&c.embree);
  c.cull = light.cull;
  return c;
}

/// occluded[i] (0 or 1) for each ray towards `light`, traced in packets of 16 (rtcOccluded16).
/// Rays must be valid (finite, tmax > 0): Embree is built without its invalid-ray filter.
void trace_occluded(RTCScene scene, const ReferenceLight& light, std::span<const ShadowRay> rays,
                    std::uint8_t* occluded) {
  ShadowContext context = shadow_context(light);
  for (std::size_t first = 0; first < rays.size(); first += kPacket) {
    const int n = int(std::min<std::size_t>(kPacket, rays.size() - first));
    alignas(64) int valid[kPacket];
    RTCRay16 packet;
    for (int i = 0; i < kPacket; ++i) {
      const ShadowRay& r = rays[first + std::size_t(std::min(i, n - 1))];
      valid[i] = i < n ? -1 : 0;
      packet.org_x[i] = r.origin.x;
      packet.org_y[i] = r.origin.y;
      packet.org_z[i] = r.origin.z;
      packet.dir_x[i] = r.direction.x;
      packet.dir_y[i] = r.direction.y;
      packet.dir_z[i] = r.direction.z;
      packet.tnear[i] = 0.0f;
      packet.tfar[i] = r.tmax;
      packet.time[i] = 0.0f;
      packet.mask[i] = 0xffffffffu;
      packet.id[i] = unsigned(i);
      packet.flags[i] = 0;
    }
    rtcOccluded16(valid, scene, &context.embree, &packet);
    // Embree sets tfar to -inf for occluded rays.
    for (int i = 0; i < n; ++i) occluded[first + std::size_t(i)] = packet.tfar[i] < 0.0f ? 1 : 0;
  }
}

/// The closest hit of a ray (unit direction, valid input) in `scene`; hit.geomID is
/// RTC_INVALID_GEOMETRY_ID on a miss.
RTCRayHit cast_ray(RTCScene scene, const glm::vec3& origin, const glm::vec3& direction,
                   float tmax) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh{};
  rh.ray.org_x = origin.x;
  rh.ray.org_y = origin.y;
  rh.ray.org_z = origin.z;
  rh.ray.dir_x = direction.x;
  rh.ray.dir_y = direction.y;
  rh.ray.dir_z = direction.z;
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = tmax;
  rh.ray.mask = 0xffffffffu;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene, &context, &rh);
  return rh;
}

/// Unit direction from a surface point towards a light and the distance to it (infinite for
/// directional lights); distance 0 when the point sits on the light.
struct ToLight {
  glm::vec3 direction{0.0f};
  float distance = 0.0f;
};
ToLight to_light(const glm::vec3& position, const ReferenceLight& light) {
  if (light.type == LightType::directional) return {-light.direction, kInfinity};
  const glm::vec3 d = light.position - position;
  const float dist = glm::length(d);
  if (!(dist > 0.0f)) return {};
  return {d / dist, dist};
}

/// The shadow ray of a punctual light from a surface point, or false when no ray is needed
/// (facing away from the light, on the light, or invalid input); `lit_without_ray` then says the
/// visibility.
bool hard_shadow_ray(const glm::vec3& position, const glm::vec3& n, const ReferenceLight& light,
                     float offset, ShadowRay& ray, bool& lit_without_ray) {
  lit_without_ray = false;
  const ToLight tl = to_light(position, light);
  if (tl.distance == 0.0f || !(glm::dot(n, tl.direction) > 0.0f)) return false;
  ray.origin = position + offset * n;
  if (light.type == LightType::directional) {
    ray.direction = tl.direction;
    ray.tmax = kInfinity;
  } else {
    // From the offset origin to the light, stopping `offset` short of it (a caster exactly at
    // the light does not shadow).
    const glm::vec3 d = light.position - ray.origin;
    const float dist = glm::length(d);
    if (!(dist > offset)) {
      lit_without_ray = true;
      return false;
    }
    ray.direction = d / dist;
    ray.tmax = dist - offset;
  }
  if (!finite(ray.origin) || !finite(ray.direction)) return false;
  return true;
}

/// Whether an occluder blocks origin + t * direction, 0 < t < tmax, towards `light` (prepared()).
bool occluded_towards(RTCScene occluders, const ReferenceLight& light, const glm::vec3& origin,
                      const glm::vec3& direction, float tmax) {
  ShadowContext context = shadow_context(light);
  RTCRay ray{};
  ray.org_x = origin.x;
  ray.org_y = origin.y;
  ray.org_z = origin.z;
  ray.dir_x = direction.x;
  ray.dir_y = direction.y;
  ray.dir_z = direction.z;
  ray.tnear = 0.0f;
  ray.tfar = tmax;
  ray.mask = 0xffffffffu;
  rtcOccluded1(occluders, &context.embree, &ray);
  return ray.tfar < 0.0f;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

ReferenceLight reference_light(const Light& light, const glm::mat4& world_matrix, CullMode cull) {
  ReferenceLight r;
  r.type = light.type;
  r.cull = cull;
  r.position = glm::vec3(world_matrix[3]);
  r.direction = light_direction(world_matrix);
  r.right = perpendicular(r.direction, glm::vec3(world_matrix[0]));
  const bool cone = light.type == LightType::spot || light.type == LightType::area;
  r.outer_cone_deg = cone ? light.outer_cone_deg : 180.0f;
  r.range = light.type == LightType::directional ? 0.0f : light.range;
  r.angular_size_deg = light.type == LightType::directional ? light.angular_size_deg : 0.0f;
  // Light::radius: a square of side 2 radius (the square the shadow techniques assume).
  r.size = light.type == LightType::directional ? 0.0f : 2.0f * light.radius;
  if (light.type == LightType::area) {
    r.size = light.size.x;
    r.height = light.size.y;
  }
  return r;
}

ReferenceLight reference_light(const ecs::World& world, ecs::Entity light) {
  // No ShadowSettings: the defaults, as the shadow systems use them.
  const auto* settings = world.try_get<ShadowSettings>(light);
  return reference_light(world.get<Light>(light), world.get<WorldTransform>(light).matrix,
                         settings ? settings->cull : ShadowSettings{}.cull);
}

RayTracer::RayTracer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RayTracer::RayTracer(RayTracer&&) noexcept = default;
RayTracer& RayTracer::operator=(RayTracer&&) noexcept = default;
RayTracer::~RayTracer() = default;

Result<RayTracer> RayTracer::build(const Scene& scene) {
  return build(scene.world, scene.assets);
}

Result<RayTracer> RayTracer::build(const ecs::World& world, const AssetStore& assets) {
  auto impl = std::make_unique<Impl>();
  impl->device = rtcNewDevice(nullptr);
  if (!impl->device) {
    return Error{"", "rtcNewDevice",
                 std::string("Embree: ") + error_name(rtcGetDeviceError(nullptr))};
  }
  rtcSetDeviceErrorFunction(impl->device, on_embree_error, &impl->errors);
  impl->occluders = rtcNewScene(impl->device);
  impl->surfaces = rtcNewScene(impl->device);
  // The error of a call that returned null: the device's, else a generic one.
  auto embree_error = [&](const std::string& what) -> Error {
    Status st = check_device(impl->device, impl->errors, what);
    return st.ok() ? Error{"", what, "Embree: the call failed"} : st.error();
  };
  KASKAD_TRY(check_device(impl->device, impl->errors, "rtcNewScene"));
  for (RTCScene s : {impl->occluders, impl->surfaces}) {
    // Robust: watertight traversal, no hits lost on shared edges (what a reference needs);
    // high quality: SAH spatial splits, built once, traced millions of times.
    rtcSetSceneFlags(s, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(s, RTC_BUILD_QUALITY_HIGH);
  }

  // 1. Collect the drawn meshes (views cannot return errors from inside `each`).
  struct Item {
    ecs::Entity entity;
    MeshRenderer renderer;
    glm::mat4 matrix;
    const Material* material;  // null: opaque
    const Deformer* deformer;  // null: drawn as stored
  };
  std::vector<Item> items;
  world.view<MeshRenderer, WorldTransform>().each(
      [&](ecs::Entity e, const MeshRenderer& mr, const WorldTransform& wt) {
        if (mr.mesh != kNoMesh)
          items.push_back(
              {e, mr, wt.matrix, world.try_get<Material>(e), world.try_get<Deformer>(e)});
      });

  // 2. One world-space triangle geometry per entity.
  std::vector<glm::vec3> world_positions;
  std::vector<std::uint32_t> kept;
  std::vector<std::uint32_t> kept_triangle;  // mesh triangle of each kept triangle
  MeshData posed;  // a deformed mesh in its pose of this frame, as the deform pass draws it
  for (const Item& item : items) {
    const std::string where = "entity " + std::to_string(item.entity.index);
    if (index(item.renderer.mesh) >= assets.meshes.size()) {
      return Error{"", where,
                   "MeshRenderer names mesh " + std::to_string(index(item.renderer.mesh)) +
                       " but the asset store has " + std::to_string(assets.meshes.size())};
    }
    const MeshData* stored = &assets.meshes[index(item.renderer.mesh)];
    glm::mat4 matrix = item.matrix;
    if (item.deformer != nullptr && stored->deform.any()) {
      posed = *stored;
      pose_mesh(*stored, item.deformer->weights, item.deformer->skin_matrices, posed);
      stored = &posed;
      if (!item.deformer->skin_matrices.empty()) matrix = glm::mat4(1.0f);  // world space
    }
    const MeshData& mesh = *stored;
    world_positions.resize(mesh.positions.size());
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      const glm::vec3 p = glm::vec3(matrix * glm::vec4(mesh.positions[i], 1.0f));
      world_positions[i] = p;
    }
    kept.clear();
    kept_triangle.clear();
    for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
      bool ok = true;
      for (std::size_t k = 0; k < 3; ++k) {
        const std::uint32_t index = mesh.indices[t + k];
        if (index >= mesh.positions.size()) {
          return Error{"", where + ", mesh '" + mesh.name + "'",
                       "index " + std::to_string(index) + " at " + std::to_string(t + k) +
                           " is out of range (" + std::to_string(mesh.positions.size()) +
                           " vertices)"};
        }
        ok = ok && finite(world_positions[index]);
      }
      // Embree needs finite vertices (its invalid-ray/primitive filters are compiled out here);
      // degenerate triangles are fine, they are never hit.
      if (ok) {
        kept.insert(kept.end(), mesh.indices.begin() + std::ptrdiff_t(t),
                    mesh.indices.begin() + std::ptrdiff_t(t + 3));
        kept_triangle.push_back(std::uint32_t(t / 3));
      }
    }
    if (kept.empty()) continue;
    for (const std::uint32_t index : kept) impl->bounds.expand(world_positions[index]);

    RTCGeometry geometry = rtcNewGeometry(impl->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!geometry) return embree_error(where + ": rtcNewGeometry");
    auto* vertices = static_cast<float*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                3 * sizeof(float), world_positions.size()));
    auto* indices = static_cast<std::uint32_t*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(std::uint32_t), kept.size() / 3));
    if (!vertices || !indices) {
      rtcReleaseGeometry(geometry);
      return embree_error(where + ": rtcSetNewGeometryBuffer");
    }
    for (std::size_t i = 0; i < world_positions.size(); ++i) {
      // Unreferenced non-finite vertices are zeroed so that nothing non-finite reaches Embree.
      const glm::vec3 p = finite(world_positions[i]) ? world_positions[i] : glm::vec3(0.0f);
      vertices[3 * i + 0] = p.x;
      vertices[3 * i + 1] = p.y;
      vertices[3 * i + 2] = p.z;
    }
    std::copy(kept.begin(), kept.end(), indices);
    // Filters: caster_face_blocks() for single-sided materials (none means the default Material,
    // as the renderer draws it), the cut-out of alpha-masked ones.
    auto rules = std::make_unique<GeometryRules>();
    rules->double_sided = item.material && item.material->double_sided;
    rules->mirrored = mirrors(item.matrix);
    if (item.material && item.material->alpha_mode != AlphaMode::opaque &&
        mesh.uv_set(item.material->base_color_transform.tex_coord).size() ==
            mesh.positions.size()) {
      AlphaCutout* cutout = &rules->cutout.emplace();
      // The base colour slot's uvs, as the shadow pass's slot_uv() gives them (the transform is
      // affine: applied at the vertices, it interpolates to the same uv).
      const TextureTransform& t = item.material->base_color_transform;
      for (const glm::vec2& uv : mesh.uv_set(t.tex_coord)) cutout->uvs.push_back(transform_uv(t, uv));
      cutout->indices = kept;
      cutout->factor = item.material->base_color.a;
      cutout->cutoff = item.material->alpha_cutoff;
      const TextureId tex = item.material->base_color_texture;
      if (tex != kNoTexture && index(tex) < assets.textures.size()) {
        const TextureData& t = assets.textures[index(tex)];
        if (t.width > 0 && t.height > 0 &&
            t.rgba8.size() == std::size_t(t.width) * std::size_t(t.height) * 4) {
          cutout->width = t.width;
          cutout->height = t.height;
          cutout->alpha.resize(std::size_t(t.width) * std::size_t(t.height));
          for (std::size_t i = 0; i < cutout->alpha.size(); ++i) cutout->alpha[i] = t.rgba8[i * 4 + 3];
        }
      }
      rtcSetGeometryIntersectFilterFunction(geometry, alpha_cutout_filter);
      ++impl->cutout_geometries;
    }
    if (!rules->double_sided || rules->cutout) {
      rtcSetGeometryUserData(geometry, rules.get());
      rtcSetGeometryOccludedFilterFunction(geometry, occlusion_filter);
      impl->rules.push_back(std::move(rules));
    }
    rtcCommitGeometry(geometry);
    const unsigned id = rtcAttachGeometry(impl->surfaces, geometry);
    if (item.renderer.cast_shadows) {
      rtcAttachGeometry(impl->occluders, geometry);  // a geometry may live in several scenes
      impl->occluder_triangles += kept.size() / 3;
    }
    rtcReleaseGeometry(geometry);  // the scenes hold their own references
    KASKAD_TRY(check_device(impl->device, impl->errors, where + ": building its Embree geometry"));
    if (id >= impl->surface_entity.size()) {
      impl->surface_entity.resize(id + 1);
      impl->surface_receives.resize(id + 1, true);
      impl->surface_triangle.resize(id + 1);
    }
    impl->surface_entity[id] = item.entity;
    if (kept.size() != mesh.indices.size() / 3 * 3) impl->surface_triangle[id] = kept_triangle;
    impl->surface_receives[id] = item.renderer.receive_shadows;
    impl->all_receive = impl->all_receive && item.renderer.receive_shadows;
    impl->surface_triangles += kept.size() / 3;
  }

  // 3. The BVHs.
  rtcCommitScene(impl->occluders);
  rtcCommitScene(impl->surfaces);
  KASKAD_TRY(check_device(impl->device, impl->errors, "rtcCommitScene"));

  // 4. The origin offset, scaled to the scene (see ray_offset()).
  if (!impl->bounds.empty()) {
    const glm::vec3 a = glm::max(glm::abs(impl->bounds.min), glm::abs(impl->bounds.max));
    const float extent =
        std::max(glm::length(impl->bounds.extent()), std::max(a.x, std::max(a.y, a.z)));
    if (extent > 0.0f && std::isfinite(extent)) impl->offset = kRayOffsetScale * extent;
  }
  return RayTracer(std::move(impl));
}

bool RayTracer::occluded(const glm::vec3& origin, const glm::vec3& direction, float tmax,
                         CullMode cull) const {
  KASKAD_CHECK(impl_, "RayTracer used after being moved from");
  if (!finite(origin) || !finite(direction) || glm::dot(direction, direction) == 0.0f ||
      !(tmax > 0.0f)) {
    return false;
  }
  ReferenceLight light;
  light.cull = cull;
  return occluded_towards(impl_->occluders, light, origin, direction, tmax);
}

std::optional<SurfaceHit> RayTracer::intersect(const glm::vec3& origin, const glm::vec3& direction,
                                               float tmax) const {
  KASKAD_CHECK(impl_, "RayTracer used after being moved from");
  const float len = glm::length(direction);
  if (!finite(origin) || !(len > 0.0f) || !std::isfinite(len) || !(tmax > 0.0f)) {
    return std::nullopt;
  }
  const glm::vec3 dir = direction / len;
  // tmax is in units of the given direction's length.
  const RTCRayHit rh = cast_ray(impl_->surfaces, origin, dir, tmax * len);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;

  SurfaceHit hit;
  hit.entity = rh.hit.geomID < impl_->surface_entity.size() ? impl_->surface_entity[rh.hit.geomID]
                                                            : ecs::kNullEntity;
  hit.distance = rh.ray.tfar;
  hit.position = origin + hit.distance * dir;
  hit.triangle = rh.hit.primID;
  if (rh.hit.geomID < impl_->surface_triangle.size()) {
    const auto& map = impl_->surface_triangle[rh.hit.geomID];
    if (rh.hit.primID < map.size()) hit.triangle = map[rh.hit.primID];
  }
  hit.barycentric = {rh.hit.u, rh.hit.v};
  glm::vec3 n{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
  const float nl = glm::length(n);
  n = nl > 0.0f ? n / nl : -dir;
  hit.normal = glm::dot(n, dir) > 0.0f ? -n : n;
  return hit;
}

float RayTracer::hard_visibility(const glm::vec3& position, const glm::vec3& n,
                                 const ReferenceLight& light) const {
  KASKAD_CHECK(impl_, "RayTracer used after being moved from");
  ShadowRay ray;
  bool lit = false;
  const ReferenceLight l = prepared(light);
  if (!hard_shadow_ray(position, n, l, impl_->offset, ray, lit)) return lit ? 1.0f : 0.0f;
  return occluded_towards(impl_->occluders, l, ray.origin, ray.direction, ray.tmax) ? 0.0f : 1.0f;
}

namespace {

/// The area-light estimator shared by area_light_visibility() and shadow_reference(); returns the
/// visible fraction and adds the rays traced to `rays`.
float area_visibility(RTCScene occluders, float offset, const glm::vec3& position,
                      const glm::vec3& n, const ReferenceLight& light, int strata,
                      std::uint64_t seed, std::uint64_t& rays) {
  const glm::vec3 origin = position + offset * n;
  if (!finite(origin) || !finite(n)) return 0.0f;
  const glm::vec3 axis = light.direction;  // prepared(): unit, and right is perpendicular
  const glm::vec3 t1 = light.right;
  const glm::vec3 t2 = glm::cross(axis, t1);
  // Directional: uniform over the cone's solid angle, cos(theta) uniform in [cos(half), 1].
  const float half_angle = 0.5f * glm::radians(light.angular_size_deg);
  const float one_minus_cos_max = 1.0f - std::cos(half_angle);

  Pcg32 rng(seed);
  const int total = strata * strata;
  std::array<ShadowRay, kPacket> batch;
  std::array<std::uint8_t, kPacket> hit{};
  int pending = 0;
  int visible = 0;
  auto flush = [&] {
    trace_occluded(occluders, light, std::span(batch.data(), std::size_t(pending)), hit.data());
    for (int i = 0; i < pending; ++i) visible += hit[std::size_t(i)] ? 0 : 1;
    rays += std::uint64_t(pending);
    pending = 0;
  };
  for (int j = 0; j < strata; ++j) {
    for (int i = 0; i < strata; ++i) {
      // Jittered stratum (i, j) of the unit square.
      const float su = (float(i) + rng.uniform()) / float(strata);
      const float sv = (float(j) + rng.uniform()) / float(strata);
      ShadowRay ray;
      ray.origin = origin;
      if (light.type == LightType::directional) {
        const float cos_t = 1.0f - su * one_minus_cos_max;
        const float sin_t = std::sqrt(std::max(0.0f, 1.0f - cos_t * cos_t));
        const float phi = 2.0f * std::numbers::pi_v<float> * sv;
        ray.direction =
            glm::normalize(cos_t * -axis + sin_t * (std::cos(phi) * t1 + std::sin(phi) * t2));
        ray.tmax = kInfinity;
      } else {
        // Point on the rectangular emitter (S1's square), edges along t1 and t2, centred at the
        // light.
        const float height = light.height > 0.0f ? light.height : light.size;
        const glm::vec3 s =
            light.position + light.size * (su - 0.5f) * t1 + height * (sv - 0.5f) * t2;
        const glm::vec3 d = s - origin;
        const float dist = glm::length(d);
        if (!(dist > offset)) {  // the sample is at the surface point: nothing in between
          ++visible;
          continue;
        }
        ray.direction = d / dist;
        ray.tmax = dist - offset;
      }
      // Below the tangent plane: the surface itself blocks this part of the emitter.
      if (!(glm::dot(n, ray.direction) > 0.0f) || !finite(ray.direction)) continue;
      batch[std::size_t(pending++)] = ray;
      if (pending == kPacket) flush();
    }
  }
  if (pending > 0) flush();
  return float(visible) / float(total);
}

int strata_of(int samples, const char* function) {
  const int strata = int(std::lround(std::sqrt(double(std::max(samples, 0)))));
  if (samples < 1 || strata * strata != samples) {
    const std::string value = std::to_string(samples);
    precondition_failed(function, "samples must be a perfect square >= 1, was " + value);
  }
  return strata;
}

}  // namespace

float RayTracer::area_light_visibility(const glm::vec3& position, const glm::vec3& n,
                                       const ReferenceLight& light, int samples,
                                       std::uint32_t seed) const {
  KASKAD_CHECK(impl_, "RayTracer used after being moved from");
  const int strata = strata_of(samples, __func__);
  if (!light.is_area()) return hard_visibility(position, n, light);
  std::uint64_t rays = 0;
  return area_visibility(impl_->occluders, impl_->offset, position, n, prepared(light), strata,
                         pixel_seed(0, seed), rays);
}

std::optional<SurfaceHit> RayTracer::trace_mirror(const glm::vec3& position, const glm::vec3& n,
                                                  const glm::vec3& incident) const {
  KASKAD_CHECK(impl_, "RayTracer used after being moved from");
  const float ul = glm::length(incident), nl = glm::length(n);
  if (!(ul > 0.0f) || !(nl > 0.0f) || !std::isfinite(nl)) return std::nullopt;
  const glm::vec3 u = incident / ul;
  const glm::vec3 nu = n / nl;
  const glm::vec3 nf = glm::dot(nu, u) > 0.0f ? -nu : nu;  // the side the eye is on
  const glm::vec3 r = u - 2.0f * glm::dot(nf, u) * nf;
  return intersect(position + impl_->offset * nf, r);
}

Result<ShadowReference> RayTracer::shadow_reference(const Image& aov,
                                                    const ReferenceLight& authored_light,
                                                    const ReferenceOptions& options) const {
  KASKAD_CHECK(impl_, "RayTracer used after being moved from");
  const ReferenceLight light = prepared(authored_light);
  const int strata = strata_of(options.area_samples, __func__);
  KASKAD_CHECK(options.threads >= 0,
               "threads must be >= 0 (0 = all cores), was " + std::to_string(options.threads));

  // Channels by name (EXR files may come back reordered); canonical order when unnamed.
  constexpr std::array<const char*, 7> kNames = {"P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z", "mask"};
  constexpr std::array<int, 7> kCanonical = {0, 1, 2, 3, 4, 5, 8};
  std::array<int, 7> ch{};
  if (aov.width <= 0 || aov.height <= 0 || aov.channels <= 0 ||
      aov.pixels.size() !=
          std::size_t(aov.width) * std::size_t(aov.height) * std::size_t(aov.channels)) {
    return Error{"", "AOV image",
                 "size " + std::to_string(aov.width) + "x" + std::to_string(aov.height) + "x" +
                     std::to_string(aov.channels) + " does not match its " +
                     std::to_string(aov.pixels.size()) + " values"};
  }
  if (aov.channel_names.empty()) {
    if (aov.channels != 9 && aov.channels != 10) {  // 10 with the cascade channel
      return Error{"", "AOV image",
                   "has no channel names and " + std::to_string(aov.channels) +
                       " channels, not the 9 or 10 of Renderer::read_aovs()"};
    }
    ch = kCanonical;
  } else {
    for (std::size_t i = 0; i < kNames.size(); ++i) {
      const auto it = std::find(aov.channel_names.begin(), aov.channel_names.end(), kNames[i]);
      if (it == aov.channel_names.end() || it - aov.channel_names.begin() >= aov.channels) {
        return Error{"", "AOV image", std::string("has no channel '") + kNames[i] + "'"};
      }
      ch[i] = int(it - aov.channel_names.begin());
    }
  }

  ShadowReference out;
  out.image.width = aov.width;
  out.image.height = aov.height;
  out.image.channels = 2;
  out.image.channel_names = {"visibility", "receiver"};
  out.image.pixels.assign(std::size_t(aov.width) * std::size_t(aov.height) * 2, 0.0f);

  const Impl& im = *impl_;
  const bool area = light.is_area();
  const float cos_outer = std::cos(glm::radians(std::min(light.outer_cone_deg, 180.0f)));
  const bool spot = light.type == LightType::spot || light.type == LightType::area;  // a cone
  std::atomic<int> next_row{0};
  std::atomic<std::uint64_t> total_rays{0};

  // One image row: steps 2 and 3 of the file comment.
  auto trace_row = [&](int y, std::vector<ShadowRay>& rays, std::vector<int>& ray_x,
                       std::vector<std::uint8_t>& occluded) -> std::uint64_t {
    std::uint64_t count = 0;
    rays.clear();
    ray_x.clear();
    for (int x = 0; x < aov.width; ++x) {
      float& vis = out.image.at(x, y, 0);
      float& receiver = out.image.at(x, y, 1);
      vis = 1.0f;
      receiver = 0.0f;
      if (!(aov.at(x, y, ch[6]) >= 0.5f)) continue;  // background (or NaN mask): skipped
      const glm::vec3 p{aov.at(x, y, ch[0]), aov.at(x, y, ch[1]), aov.at(x, y, ch[2])};
      glm::vec3 n{aov.at(x, y, ch[3]), aov.at(x, y, ch[4]), aov.at(x, y, ch[5])};
      const float nl = glm::length(n);
      if (!finite(p) || !(nl > 0.0f) || !std::isfinite(nl)) continue;
      n /= nl;

      // Does the pixel count for the metrics (ReferenceOptions::facing_threshold)?
      const ToLight tl = to_light(p, light);
      bool receives = tl.distance > 0.0f && glm::dot(n, tl.direction) > options.facing_threshold;
      if (receives && spot) receives = glm::dot(light.direction, -tl.direction) >= cos_outer;
      if (receives && light.range > 0.0f && light.type != LightType::directional)
        receives = tl.distance <= light.range;
      if (receives && options.respect_receive_shadows && !im.all_receive) {
        // The entity under the pixel: a short ray down the normal onto the surface.
        // A miss (should not happen) keeps the pixel.
        const unsigned g =
            cast_ray(im.surfaces, p + 2.0f * im.offset * n, -n, 4.0f * im.offset).hit.geomID;
        ++count;
        if (g < im.surface_receives.size()) receives = im.surface_receives[g];
      }
      receiver = receives ? 1.0f : 0.0f;

      if (area) {
        const std::size_t pixel = std::size_t(y) * std::size_t(aov.width) + std::size_t(x);
        vis = area_visibility(im.occluders, im.offset, p, n, light, strata,
                              pixel_seed(pixel, options.seed), count);
      } else {
        ShadowRay ray;
        bool lit = false;
        if (hard_shadow_ray(p, n, light, im.offset, ray, lit)) {
          rays.push_back(ray);
          ray_x.push_back(x);
        } else {
          vis = lit ? 1.0f : 0.0f;
        }
      }
    }
    if (!rays.empty()) {
      occluded.resize(rays.size());
      trace_occluded(im.occluders, light, rays, occluded.data());
      for (std::size_t i = 0; i < rays.size(); ++i)
        out.image.at(ray_x[i], y, 0) = occluded[i] ? 0.0f : 1.0f;
      count += rays.size();
    }
    return count;
  };

  auto worker = [&] {
    std::vector<ShadowRay> rays;
    std::vector<int> ray_x;
    std::vector<std::uint8_t> occluded;
    std::uint64_t count = 0;
    for (int y = next_row.fetch_add(1); y < aov.height; y = next_row.fetch_add(1))
      count += trace_row(y, rays, ray_x, occluded);
    total_rays.fetch_add(count);
  };

  out.seconds = run_row_workers(aov.height, options.threads, worker);
  out.rays = total_rays.load();
  return out;
}

float RayTracer::ray_offset() const {
  KASKAD_CHECK(impl_, "RayTracer used after being moved from");
  return impl_->offset;
}
Aabb RayTracer::bounds() const {
  KASKAD_CHECK(impl_, "RayTracer used after being moved from");
  return impl_->bounds;
}
std::size_t RayTracer::occluder_triangles() const {
  KASKAD_CHECK(impl_, "RayTracer used after being moved from");
  return impl_->occluder_triangles;
}
std::size_t RayTracer::alpha_masked_geometries() const { return impl_->cutout_geometries; }

std::size_t RayTracer::surface_triangles() const {
  KASKAD_CHECK(impl_, "RayTracer used after being moved from");
  return impl_->surface_triangles;
}

}  // namespace kaskad::reference
