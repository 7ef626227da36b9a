// The ray-traced reflection reference (for the reflection probes): for every pixel of a
// rendered AOV image, the radiance C_t a perfect mirror at that surface point reflects (S3 eq. 1
// and 3: I' = I + k_s p_r C_t). The mirror ray is traced with Embree (RayTracer::trace_mirror);
// a hit is shaded with the forward pass's material model (content/shaders/forward.frag; checked
// by the render test ForwardModelTest.ShadePointReproducesTheForwardPass), a miss returns the environment cube map, else the clear colour. Plus the error of
// an engine `reflection` image against it. CPU only; no GL.
//
// C_t is linear radiance BEFORE exposure (the quantity forward.frag adds to I before multiplying
// by u_ambient.w); environment cube texels are taken as they are.
//
// Differences from the rasteriser, by design or not yet done: the hit is shaded with the
// triangle's geometric normal (flat primitives agree exactly, smooth meshes differ slightly); the
// base colour texture is sampled bilinearly from its top mip level (GL filters trilinearly over
// mips); no normal maps, alpha cut-outs, occlusion, emissive or metallic-roughness textures
// (the factors alone) or texture transforms;
// the view vector at the hit points back along the mirror ray (a probe captured at a centre sees
// it from there instead); every light with cast_shadows gets a hard shadow ray (the engine
// shadows one light).
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "components/light.h"
#include "components/material.h"
#include "runtime/assets/env_lighting.h"
#include "runtime/assets/env_map.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/scene.h"
#include "runtime/result/result.h"
#include "runtime/reference/ray_tracer.h"

namespace kaskad::reference {

/// A light as forward.frag shades it (light_shading(), the renderer's LightItem), plus whether
/// the reference traces its shadow.
struct ShadingLight : LightShading {
  bool shadowed = false;  ///< trace a hard shadow ray (Light::cast_shadows)
  /// The faces of single-sided occluders that do not block its shadow ray: its
  /// ShadowSettings::cull, as in the shadow pass (caster_face_blocks()).
  CullMode cull = CullMode::back;
};

/// Everything the reference needs besides the geometry.
struct ReflectionScene {
  /// Materials (Material, default Material when absent) and MeshRenderer::receive_shadows of
  /// the entities mirror rays hit. Not owned; must outlive the calls. May be null: every hit
  /// then has the default Material and receives shadows.
  const ecs::World* world = nullptr;
  /// Meshes (uvs) and textures of the hit entities, for base colour textures. Not owned; may be
  /// null: the base colour factor alone is used.
  const AssetStore* assets = nullptr;
  std::vector<ShadingLight> lights;
  /// Light from the surroundings (components/ibl.h): the uniform ambient radiance, or, when
  /// `environment_light` is set, that map's SH irradiance and GGX-prefiltered radiance (by
  /// importance sampling the map itself) times `environment_intensity`.
  glm::vec3 ambient{0.05f};
  const CubeMap* environment_light = nullptr;
  Sh9 environment_sh{};
  float environment_intensity = 1.0f;
  glm::vec3 clear_color{0.0f};  ///< returned on a miss when there is no environment
  /// Misses return sample_cube(*environment, R) (world-space R). Not owned; may be null.
  const CubeMap* environment = nullptr;
};

/// The ReflectionScene of a loaded scene (run the transform phase first): every Light with a
/// WorldTransform through light_shading(), as systems/frame.cpp does for the renderer (colour *
/// intensity, direction from the matrix's -Z, cones as cosines), shadowed = cast_shadows; the
/// render settings' ambient and clear colour; world and assets point into `scene`.
ReflectionScene reflection_scene(const Scene& scene, const CubeMap* environment = nullptr);

/// A texture as a GL_LINEAR / GL_REPEAT sampler reads its top mip level at uv (glTF / GL
/// convention: (0, 0) is the first texel of the first row), decoded from sRGB to linear first
/// when texture.srgb (GL decodes sRGB texels before filtering). Empty texture: vec4(1).
glm::vec4 sample_texture(const TextureData& texture, const glm::vec2& uv);

/// The base colour a surface hit shows: Material::base_color times its base colour texture at
/// the hit's uv (interpolated from the mesh's uvs with SurfaceHit::barycentric) when the material
/// has a texture and `assets` has it and the mesh has uvs; else the factor alone.
glm::vec4 hit_base_color(const ReflectionScene& scene, const Material& material,
                         const SurfaceHit& hit);

/// forward.frag's radiance (before exposure) leaving surface point `position` with unit normal
/// `normal` (facing the viewer) towards the unit vector `to_eye`, taking material.base_color as
/// the base colour (multiply a texture sample in first): the light from the surroundings (ibl_combine) + emissive +
/// sum over lights of the glTF BRDF (components/brdf.h) * illuminance * N.L * attenuation *
/// visibility, as in forward.frag. Shadow rays (shadowed
/// lights, when `receives_shadows`) start at position + ray_offset() * normal.
glm::vec3 shade_point(const RayTracer& tracer, const ReflectionScene& scene,
                      const Material& material, const glm::vec3& position, const glm::vec3& normal,
                      const glm::vec3& to_eye, bool receives_shadows,
                      std::uint64_t* rays = nullptr);

/// What a mirror at `position` with normal `normal` (either side) reflects towards `eye`: the
/// mirror ray R = U - 2 (N.U) N (S3 eq. 1, U from the eye to the point) traced from the surface;
/// on a hit, shade_point() of the hit towards the mirror point; on a miss the environment along R
/// (or the clear colour). `hit`, when given, tells which happened.
glm::vec3 reflected_radiance(const RayTracer& tracer, const ReflectionScene& scene,
                             const glm::vec3& position, const glm::vec3& normal,
                             const glm::vec3& eye, bool* hit = nullptr,
                             std::uint64_t* rays = nullptr);

/// Channel names of C_t, in the reference image and in the engine's `reflection` AOV.
inline constexpr const char* kReflectionChannels[3] = {"reflection.R", "reflection.G",
                                                       "reflection.B"};

/// reflection_reference()'s output and what it cost.
struct ReflectionReference {
  /// Same size as the AOV; channels "reflection.R", "reflection.G", "reflection.B" (C_t; 0 where
  /// mask = 0), "reflection.hit" (1 where the mirror ray hit geometry, 0 on a miss) and "mask"
  /// (1 where the pixel was evaluated: AOV mask = 1 with a finite position and non-zero normal).
  Image image;
  std::uint64_t rays = 0;  ///< mirror rays plus shadow rays
  double seconds = 0.0;    ///< wall time of the tracing
};

/// C_t for every pixel of an AOV image (channels by name: P.X P.Y P.Z N.X N.Y N.Z mask; the
/// canonical order of Renderer::read_aovs() when unnamed) seen from `eye` (the camera position
/// the AOV was rendered from). Rows run in parallel on `threads` workers (0 = all cores).
/// Error when a channel is missing or the image's sizes are inconsistent.
Result<ReflectionReference> reflection_reference(const RayTracer& tracer, const Image& aov,
                                                 const ReflectionScene& scene, const glm::vec3& eye,
                                                 int threads = 0);

/// Error of an engine reflection image against the reference, per colour channel value.
struct ReflectionErrorStats {
  std::size_t pixels = 0;       ///< pixels compared
  std::size_t non_finite = 0;   ///< pixels skipped: the method or the reference is not finite
  double rmse = 0.0;            ///< sqrt(mean over pixels and R, G, B of (method - reference)^2)
  double mean_abs_error = 0.0;  ///< mean over pixels and R, G, B of |method - reference|
  double max_abs_error = 0.0;   ///< largest |method - reference| of any channel
};

/// Compares the "reflection.R/G/B" channels of `method` (the engine's `reflection` AOV) with a
/// reflection_reference() image, over the pixels whose reference "mask" is 1 and, when `method`
/// has a "reflector" channel, whose reflector value is >= 0.5 (pixels of reflective materials).
/// Channels are looked up by name. Errors: a channel is missing or the sizes differ.
Result<ReflectionErrorStats> compare_reflections(const Image& method, const Image& reference);

}  // namespace kaskad::reference
