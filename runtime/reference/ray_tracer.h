// The ray-traced reference (DESIGN.md "Measuring"): Intel Embree 3 BVHs built from the same
// triangles and world transforms the renderer draws. It answers, for surface points taken from a
// rendered AOV image (so it sees exactly the rasterised surface):
//   - exact hard-shadow visibility of directional, spot and point lights (one shadow ray each);
//   - Monte Carlo visibility of area lights: a square emitter for spot/point lights, a cone of
//     directions for directional lights with an angular size (stratified, deterministic);
//   - mirror-ray hits, for reflection references.
// CPU only: no GL context needed. Embree's headers stay out of this header.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include <glm/glm.hpp>

#include "components/bounds.h"
#include "components/light.h"
#include "components/shadow_settings.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/scene.h"
#include "runtime/result/result.h"
#include "runtime/ecs/entity.h"

namespace kaskad::reference {

/// A light as the reference sees it, in world space. Make one from a Light component with
/// reference_light(), or by hand in tests.
struct ReferenceLight {
  LightType type = LightType::directional;
  glm::vec3 position{0.0f};                ///< spot/point: world position, metres
  glm::vec3 direction{0.0f, -1.0f, 0.0f};  ///< the way light travels (the entity's -Z);
                                           ///< normalised by the tracer
  glm::vec3 right{1.0f, 0.0f, 0.0f};       ///< area light: the square's first edge, or the cone's
                                      ///< azimuth origin (the entity's +X); the tracer makes it
                                      ///< unit and perpendicular to `direction`
  /// Spot/point/area: side of the square emitter in metres (perpendicular to `direction`,
  /// centred at `position`, edges along `right` and direction x right; S1's 2 x 2 light has
  /// size 2). 0 = punctual.
  float size = 0.0f;
  /// Area: the rectangle's side along direction x right (its height, the light's local Y);
  /// 0 = size (a square).
  float height = 0.0f;
  /// Directional: apex angle of the cone of incoming directions around -direction, degrees
  /// (the sun: about 0.53). 0 = punctual.
  float angular_size_deg = 0.0f;
  float outer_cone_deg = 180.0f;  ///< spot: no light outside this half-angle (degrees)
  float range = 0.0f;             ///< spot/point: no light beyond this distance; 0 = infinite
  /// The faces of single-sided occluders that do not block this light, as in its shadow pass
  /// (ShadowSettings::cull; the rule is caster_face_blocks(), components/shadow_settings.h).
  CullMode cull = CullMode::back;

  /// True when visibility is a fraction (Monte Carlo over the emitter), not a single ray.
  bool is_area() const {
    return type == LightType::directional ? angular_size_deg > 0.0f : size > 0.0f;
  }
};

/// The reference light of a Light component on an entity with this world matrix: direction from
/// the matrix's -Z (light_direction(), components/light.h, as the shadow systems take it), right
/// from its +X, position from its translation; a directional light's angular_size_deg from the
/// component (an area light when > 0); a spot or point light's size = 2 Light::radius (a square
/// emitter of side 2 radius; punctual when the radius is 0); an area light's size and height
/// its Light::size, and its cone outer_cone_deg; `cull` its ShadowSettings::cull.
ReferenceLight reference_light(const Light& light, const glm::mat4& world_matrix,
                               CullMode cull = CullMode::back);
/// The reference light of light entity `light` of `world` (Light, WorldTransform, and its
/// ShadowSettings' cull, the defaults' without one): what the references compare a shadow with.
ReferenceLight reference_light(const ecs::World& world, ecs::Entity light);

/// The first surface a ray hits.
struct SurfaceHit {
  ecs::Entity entity = ecs::kNullEntity;  ///< the MeshRenderer entity hit
  glm::vec3 position{0.0f};               ///< world position of the hit, metres
  glm::vec3 normal{0.0f, 1.0f, 0.0f};  ///< unit geometric (triangle) normal, facing the ray origin
  float distance = 0.0f;               ///< along the unit ray direction, metres
  /// The hit triangle of the entity's mesh: indices[3 * triangle + 0..2] of its MeshData.
  std::uint32_t triangle = 0;
  /// Barycentric (u, v) of the hit in that triangle: position = (1 - u - v) p0 + u p1 + v p2.
  glm::vec2 barycentric{0.0f};
};

struct ReferenceOptions {
  /// Area lights: samples per pixel, a perfect square (jittered sqrt(M) x sqrt(M) strata).
  int area_samples = 256;
  /// Mixed with the pixel index into each pixel's sample seed: results are deterministic and do
  /// not depend on the thread count.
  std::uint32_t seed = 0;
  /// A pixel receives the light when N . toLight > this (unit vectors; 0.05 is about 87 degrees).
  /// Below it diffuse lighting is under 5% of its peak, so shadow errors are hardly visible, and
  /// the terminator of smooth-shaded meshes (where the interpolated AOV normal and the facet
  /// disagree) stays out of the metrics.
  float facing_threshold = 0.05f;
  /// Pixels of MeshRenderers with receive_shadows = false are not receivers (the AOV writes 1
  /// there). Costs one short ray per pixel to find the surface's entity, when any surface has
  /// receive_shadows = false.
  bool respect_receive_shadows = true;
  /// Worker threads over image rows; 0 = std::thread::hardware_concurrency().
  int threads = 0;
};

/// shadow_reference()'s output and what it cost.
struct ShadowReference {
  /// Same size as the AOV; channels "visibility" (reference visibility in [0, 1]: 1 lit, 0
  /// shadowed, fractions for area lights; 1 where mask = 0; 0 where the surface faces away from the
  /// light) and "receiver" (1 where the pixel counts for the metrics: mask = 1, finite position and
  /// normal, facing the light by facing_threshold, inside a spot's cone and the light's range,
  /// and, with respect_receive_shadows, a surface that receives shadows; else 0).
  Image image;
  std::uint64_t rays = 0;  ///< rays traced (shadow rays plus receiver look-ups)
  double seconds = 0.0;    ///< wall time of the tracing
  double rays_per_second() const { return seconds > 0.0 ? double(rays) / seconds : 0.0; }
};

/// Owns an Embree device and two scenes built from a Scene's MeshRenderers: the occluders
/// (cast_shadows = true) and every surface (for mirror rays and receiver look-ups). Occluders
/// block a light with the faces caster_face_blocks() says, for the light's cull
/// (ReferenceLight::cull): the shadow pass's rule, Material::double_sided and mirroring world
/// transforms included. Alpha-masked materials (glTF MASK) cut holes where the rasteriser
/// discards, and blended ones (glTF BLEND) where the depth pass does (alpha_masked_geometries()).
/// Triangles are transformed to world space when built; later changes to the Scene are not seen.
/// Move-only.
/// Thread safety: all const member functions may be called from any number of threads at once.
class RayTracer {
 public:
  /// Builds from every entity with MeshRenderer and WorldTransform (run the transform phase
  /// first). Triangles with non-finite vertices are dropped; degenerate ones are harmless; an
  /// empty scene gives a tracer where nothing is occluded. Errors: a MeshRenderer naming a mesh
  /// the AssetStore lacks, an index out of range, or an Embree error (rtcGetDeviceError).
  static Result<RayTracer> build(const Scene& scene);
  static Result<RayTracer> build(const ecs::World& world, const AssetStore& assets);

  RayTracer(RayTracer&&) noexcept;
  RayTracer& operator=(RayTracer&&) noexcept;
  RayTracer(const RayTracer&) = delete;
  RayTracer& operator=(const RayTracer&) = delete;
  ~RayTracer();

  /// Whether an occluder lies on the ray origin + t * direction, 0 < t < tmax (t in units of
  /// direction's length), the ray a shadow ray towards a light farther along it whose cull is
  /// `cull` (caster_face_blocks()). The origin is used as given: offset it off its surface
  /// first. Rays with non-finite or zero direction, or tmax <= 0, are never occluded.
  bool occluded(const glm::vec3& origin, const glm::vec3& direction, float tmax,
                CullMode cull = CullMode::back) const;

  /// First surface (any MeshRenderer, caster or not) hit by origin + t * direction,
  /// 0 < t < tmax; direction need not be unit (distance is still in metres).
  std::optional<SurfaceHit> intersect(const glm::vec3& origin, const glm::vec3& direction,
                                      float tmax = 1e30f) const;

  /// Exact hard-shadow visibility (0 or 1) of a punctual light at a surface point with unit
  /// normal n (the light's size is ignored). One ray from position + ray_offset() * n: towards
  /// -direction for directional lights, to the light's position (length distance - ray_offset())
  /// for spot and point lights. 0 when the point faces away from the light (n . toLight <= 0).
  float hard_visibility(const glm::vec3& position, const glm::vec3& n,
                        const ReferenceLight& light) const;

  /// Fraction in [0, 1] of the emitter visible from a surface point: `samples` (a perfect square)
  /// stratified jittered samples, uniform over the square's area (spot/point) or over the cone's
  /// solid angle (directional). Samples below the surface's tangent plane count as blocked.
  /// Deterministic for a given seed. A punctual light gives hard_visibility().
  float area_light_visibility(const glm::vec3& position, const glm::vec3& n,
                              const ReferenceLight& light, int samples, std::uint32_t seed) const;

  /// The mirror reflection of `incident` (direction from the eye to the point, any length) about
  /// the unit normal n: R = U - 2 (N . U) N, traced from position + ray_offset() * n (n flipped
  /// to face against U first). nullopt on a miss.
  std::optional<SurfaceHit> trace_mirror(const glm::vec3& position, const glm::vec3& n,
                                         const glm::vec3& incident) const;

  /// Reference visibility of one light for every pixel of an AOV image (channels looked up by
  /// name: P.X P.Y P.Z N.X N.Y N.Z mask; the canonical order of Renderer::read_aovs() when the
  /// image has no names). Rows run in parallel. Punctual lights: hard_visibility(); area lights:
  /// area_light_visibility() with options.area_samples. Error when a channel is missing.
  Result<ShadowReference> shadow_reference(const Image& aov, const ReferenceLight& light,
                                           const ReferenceOptions& options = {}) const;

  /// Offset of ray origins along the surface normal, metres: kRayOffsetScale times the scene
  /// extent (the larger of the bounds' diagonal and its largest absolute coordinate), so that
  /// float rounding of rasterised positions (relative error ~1e-6) never self-shadows.
  float ray_offset() const;
  static constexpr float kRayOffsetScale = 1e-5f;

  Aabb bounds() const;                     ///< of every surface triangle kept
  std::size_t occluder_triangles() const;  ///< triangles in the occluder BVH
  std::size_t surface_triangles() const;   ///< triangles in the all-surfaces BVH
  /// Geometries with an alpha cut-out (Material::alpha_mode mask or blend, and uvs): rays pass
  /// through where base_color.a x texture alpha < alpha_cutoff, as the rasteriser discards
  /// there (and as the depth pass draws blended casters).
  std::size_t alpha_masked_geometries() const;

 private:
  struct Impl;
  explicit RayTracer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace kaskad::reference
