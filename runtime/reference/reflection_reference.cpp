// The reflection reference. Per AOV pixel:
//   1. the rasterised position P and normal N; U = P - eye;
//   2. the mirror ray R = U - 2 (N.U) N (S3 eq. 1), traced by RayTracer::trace_mirror();
//   3. hit: forward.frag's shading of the hit surface towards P (shade_point(), hard shadow rays);
//      miss: the environment cube along R, else the clear colour;
//   4. rows are shared out to worker threads through one atomic counter.
#include "runtime/reference/reflection_reference.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#include "components/brdf.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "runtime/reference/row_workers.h"

namespace kaskad::reference {
namespace {

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

Status check_sizes(const Image& image, const char* what) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.pixels.size() !=
          std::size_t(image.width) * std::size_t(image.height) * std::size_t(image.channels)) {
    std::string message = "size ";
    message += std::to_string(image.width);
    message += "x";
    message += std::to_string(image.height);
    message += "x";
    message += std::to_string(image.channels);
    message += " does not match its ";
    message += std::to_string(image.pixels.size());
    message += " values";
    return Error{"", what, message};
  }
  return {};
}

}  // namespace

glm::vec4 sample_texture(const TextureData& texture, const glm::vec2& uv) {
  const int w = texture.width, h = texture.height;
  if (w <= 0 || h <= 0 || texture.rgba8.size() < std::size_t(w) * std::size_t(h) * 4)
    return glm::vec4(1.0f);
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return glm::vec4(1.0f);
  // GL_REPEAT, GL_LINEAR: texel centres at integer + 0.5.
  const float fx = (uv.x - std::floor(uv.x)) * float(w) - 0.5f;
  const float fy = (uv.y - std::floor(uv.y)) * float(h) - 0.5f;
  const float x0f = std::floor(fx), y0f = std::floor(fy);
  const float ax = fx - x0f, ay = fy - y0f;
  auto wrap = [](int i, int n) { return ((i % n) + n) % n; };
  auto texel = [&](int x, int y) {
    const std::uint8_t* t =
        &texture.rgba8[(std::size_t(wrap(y, h)) * std::size_t(w) + std::size_t(wrap(x, w))) * 4];
    glm::vec4 c(t[0], t[1], t[2], t[3]);
    c /= 255.0f;
    if (texture.srgb) {
      for (int i = 0; i < 3; ++i)
        c[i] = c[i] <= 0.04045f ? c[i] / 12.92f : std::pow((c[i] + 0.055f) / 1.055f, 2.4f);
    }
    return c;
  };
  const int x0 = int(x0f), y0 = int(y0f);
  return glm::mix(glm::mix(texel(x0, y0), texel(x0 + 1, y0), ax),
                  glm::mix(texel(x0, y0 + 1), texel(x0 + 1, y0 + 1), ax), ay);
}

glm::vec4 hit_base_color(const ReflectionScene& scene, const Material& material,
                         const SurfaceHit& hit) {
  if (material.base_color_texture == kNoTexture || !scene.assets || !scene.world ||
      index(material.base_color_texture) >= scene.assets->textures.size())
    return material.base_color;
  const auto* mr =
      scene.world->alive(hit.entity) ? scene.world->try_get<MeshRenderer>(hit.entity) : nullptr;
  if (!mr || index(mr->mesh) >= scene.assets->meshes.size()) return material.base_color;
  const MeshData& mesh = scene.assets->meshes[index(mr->mesh)];
  const std::size_t first = 3 * std::size_t(hit.triangle);
  const TextureTransform& t = material.base_color_transform;
  const std::vector<glm::vec2>& uvs = mesh.uv_set(t.tex_coord);
  if (uvs.size() != mesh.positions.size() || first + 2 >= mesh.indices.size())
    return material.base_color;
  std::array<glm::vec2, 3> uv;
  for (std::size_t k = 0; k < 3; ++k) {
    const std::uint32_t i = mesh.indices[first + k];
    if (i >= uvs.size()) return material.base_color;
    uv[k] = uvs[i];
  }
  const glm::vec2 b = hit.barycentric;
  const glm::vec2 at = transform_uv(t, (1.0f - b.x - b.y) * uv[0] + b.x * uv[1] + b.y * uv[2]);
  return material.base_color *
         sample_texture(scene.assets->textures[index(material.base_color_texture)], at);
}

ReflectionScene reflection_scene(const Scene& scene, const CubeMap* environment) {
  ReflectionScene out;
  out.world = &scene.world;
  out.assets = &scene.assets;
  out.ambient = scene.render.ambient;
  if (scene.environment_map < scene.assets.env_maps.size()) {
    out.environment_light = &scene.assets.env_maps[scene.environment_map];
    out.environment_sh = scene.environment_sh;
    out.environment_intensity = scene.render.environment_intensity;
  }
  out.clear_color = scene.render.clear_color;
  out.environment = environment;
  // The same light_shading() as the renderer's lights (systems/frame.cpp).
  scene.world.view<Light, WorldTransform>().each(
      [&](ecs::Entity e, const Light& l, const WorldTransform& wt) {
        ShadingLight s;
        static_cast<LightShading&>(s) = light_shading(l, wt.matrix);
        s.shadowed = l.cast_shadows;
        s.cull = reference_light(scene.world, e).cull;
        out.lights.push_back(s);
      });
  return out;
}

glm::vec3 shade_point(const RayTracer& tracer, const ReflectionScene& scene,
                      const Material& material, const glm::vec3& position, const glm::vec3& normal,
                      const glm::vec3& to_eye, bool receives_shadows, std::uint64_t* rays) {
  // forward.frag, main(), line by line; the BRDF is components/brdf.h. The render tests
  // ForwardModelTest.ShadePointReproducesTheForwardPass and BaseColourTexturesMatchTheForwardPass
  // fail when the two part.
  const BrdfInputs brdf{glm::vec3(material.base_color), material.metallic, material.roughness};
  const glm::vec3& n = normal;
  const glm::vec3& v = to_eye;

  // Light from the surroundings (components/ibl.h).
  glm::vec3 irradiance = scene.ambient, specular = scene.ambient;
  const float roughness = std::clamp(material.roughness, kMinRoughness, 1.0f);
  if (scene.environment_light) {
    irradiance = scene.environment_intensity * sh9_irradiance_over_pi(scene.environment_sh, n);
    specular = scene.environment_intensity *
               prefiltered_radiance(*scene.environment_light, glm::reflect(-v, n), roughness, 256);
  }
  const float n_dot_v = std::clamp(glm::dot(n, v), 0.0f, 1.0f);
  glm::vec3 color = ibl_combine(brdf, n_dot_v, dfg_lookup(n_dot_v, roughness), irradiance, specular) +
                    material.emissive;
  for (const ShadingLight& light : scene.lights) {
    glm::vec3 l;
    float attenuation = 1.0f;
    const glm::vec3 dir = glm::normalize(light.direction);
    if (light.type == LightType::directional) {
      l = -dir;
    } else {
      const glm::vec3 to_light = light.position - position;
      const float d2 = std::max(glm::dot(to_light, to_light), 1e-8f);
      l = to_light / std::sqrt(d2);
      attenuation = 1.0f / d2;
      if (light.range > 0.0f) {  // KHR_lights_punctual's recommended smooth window
        const float r = d2 / (light.range * light.range);
        attenuation *= std::clamp(1.0f - r * r, 0.0f, 1.0f);
      }
      attenuation *= light_emission(light, l);  // spot cone, area cone and cosine
    }
    const float ndl = std::max(glm::dot(n, l), 0.0f);
    if (ndl <= 0.0f) continue;
    float shadow = 1.0f;
    if (light.shadowed && receives_shadows && attenuation > 0.0f) {
      ReferenceLight ref;
      ref.type = light.type;
      ref.position = light.position;
      ref.direction = dir;
      ref.cull = light.cull;
      shadow = tracer.hard_visibility(position, n, ref);
      if (rays) ++*rays;
    }
    color += brdf_evaluate(brdf, n, v, l) * light.color * ndl * attenuation * shadow;
  }
  return color;
}

glm::vec3 reflected_radiance(const RayTracer& tracer, const ReflectionScene& scene,
                             const glm::vec3& position, const glm::vec3& normal,
                             const glm::vec3& eye, bool* hit, std::uint64_t* rays) {
  if (hit) *hit = false;
  const glm::vec3 incident = position - eye;
  const float ul = glm::length(incident), nl = glm::length(normal);
  if (!(ul > 0.0f) || !(nl > 0.0f) || !finite(incident) || !finite(normal)) return glm::vec3(0.0f);
  if (rays) ++*rays;
  const std::optional<SurfaceHit> surface = tracer.trace_mirror(position, normal, incident);
  if (!surface) {
    // S3 eq. (1), as trace_mirror() computes it (N turned towards the eye first).
    const glm::vec3 u = incident / ul;
    glm::vec3 n = normal / nl;
    if (glm::dot(n, u) > 0.0f) n = -n;
    const glm::vec3 r = u - 2.0f * glm::dot(n, u) * n;
    if (scene.environment && scene.environment->size > 0)
      return glm::vec3(sample_cube(*scene.environment, r));
    return scene.clear_color;
  }
  if (hit) *hit = true;
  const Material default_material;
  const Material* material = nullptr;
  bool receives = true;
  if (scene.world && scene.world->alive(surface->entity)) {
    material = scene.world->try_get<Material>(surface->entity);
    if (const auto* mr = scene.world->try_get<MeshRenderer>(surface->entity))
      receives = mr->receive_shadows;
  }
  Material shaded = material ? *material : default_material;
  shaded.base_color = hit_base_color(scene, shaded, *surface);
  const glm::vec3 to_mirror = glm::normalize(position - surface->position);
  return shade_point(tracer, scene, shaded, surface->position, surface->normal, to_mirror, receives,
                     rays);
}

Result<ReflectionReference> reflection_reference(const RayTracer& tracer, const Image& aov,
                                                 const ReflectionScene& scene, const glm::vec3& eye,
                                                 int threads) {
  KASKAD_CHECK(threads >= 0,
               "threads must be >= 0 (0 = all cores), was " + std::to_string(threads));
  KASKAD_TRY(check_sizes(aov, "AOV image"));
  // Channels by name (EXR files may come back reordered); canonical order when unnamed.
  constexpr std::array<const char*, 7> kNames = {"P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z", "mask"};
  constexpr std::array<int, 7> kCanonical = {0, 1, 2, 3, 4, 5, 8};
  std::array<int, 7> ch{};
  if (aov.channel_names.empty()) {
    if (aov.channels != 9 && aov.channels != 10) {
      return Error{"", "AOV image",
                   "has no channel names and " + std::to_string(aov.channels) +
                       " channels, not the 9 or 10 of Renderer::read_aovs()"};
    }
    ch = kCanonical;
  } else {
    for (std::size_t i = 0; i < kNames.size(); ++i) {
      ch[i] = aov.channel(kNames[i]);
      if (ch[i] < 0)
        return Error{"", "AOV image", std::string("has no channel '") + kNames[i] + "'"};
    }
  }

  ReflectionReference out;
  Image& img = out.image;
  img.width = aov.width;
  img.height = aov.height;
  img.channel_names = {kReflectionChannels[0], kReflectionChannels[1], kReflectionChannels[2],
                       "reflection.hit", "mask"};
  img.channels = int(img.channel_names.size());
  img.pixels.assign(std::size_t(aov.width) * std::size_t(aov.height) * std::size_t(img.channels),
                    0.0f);

  std::atomic<int> next_row{0};
  std::atomic<std::uint64_t> total_rays{0};
  auto worker = [&] {
    std::uint64_t rays = 0;
    for (int y = next_row.fetch_add(1); y < aov.height; y = next_row.fetch_add(1)) {
      for (int x = 0; x < aov.width; ++x) {
        if (!(aov.at(x, y, ch[6]) >= 0.5f)) continue;  // background (or NaN mask)
        const glm::vec3 p{aov.at(x, y, ch[0]), aov.at(x, y, ch[1]), aov.at(x, y, ch[2])};
        const glm::vec3 n{aov.at(x, y, ch[3]), aov.at(x, y, ch[4]), aov.at(x, y, ch[5])};
        if (!finite(p) || !finite(n) || !(glm::length(n) > 0.0f)) continue;
        bool hit = false;
        const glm::vec3 c = reflected_radiance(tracer, scene, p, n, eye, &hit, &rays);
        for (int i = 0; i < 3; ++i) img.at(x, y, i) = c[i];
        img.at(x, y, 3) = hit ? 1.0f : 0.0f;
        img.at(x, y, 4) = 1.0f;
      }
    }
    total_rays.fetch_add(rays);
  };
  out.seconds = run_row_workers(aov.height, threads, worker);
  out.rays = total_rays.load();
  return out;
}

Result<ReflectionErrorStats> compare_reflections(const Image& method, const Image& reference) {
  KASKAD_TRY(check_sizes(method, "reflection image"));
  KASKAD_TRY(check_sizes(reference, "reflection reference"));
  if (method.width != reference.width || method.height != reference.height) {
    std::string message = "is ";
    message += std::to_string(method.width);
    message += "x";
    message += std::to_string(method.height);
    message += ", the reference ";
    message += std::to_string(reference.width);
    message += "x";
    message += std::to_string(reference.height);
    return Error{"", "reflection image", message};
  }
  std::array<int, 3> m{}, r{};
  for (int i = 0; i < 3; ++i) {
    m[std::size_t(i)] = method.channel(kReflectionChannels[i]);
    r[std::size_t(i)] = reference.channel(kReflectionChannels[i]);
    if (m[std::size_t(i)] < 0)
      return Error{"", "reflection image",
                   std::string("has no channel '") + kReflectionChannels[i] + "'"};
    if (r[std::size_t(i)] < 0)
      return Error{"", "reflection reference",
                   std::string("has no channel '") + kReflectionChannels[i] + "'"};
  }
  const int mask = reference.channel("mask");
  if (mask < 0) return Error{"", "reflection reference", "has no channel 'mask'"};
  const int reflector = method.channel("reflector");  // optional

  ReflectionErrorStats stats;
  double sum_sq = 0.0, sum_abs = 0.0;
  for (int y = 0; y < method.height; ++y) {
    for (int x = 0; x < method.width; ++x) {
      if (!(reference.at(x, y, mask) >= 0.5f)) continue;
      if (reflector >= 0 && !(method.at(x, y, reflector) >= 0.5f)) continue;
      std::array<double, 3> d{};
      bool ok = true;
      for (std::size_t i = 0; i < 3; ++i) {
        const float a = method.at(x, y, m[i]), b = reference.at(x, y, r[i]);
        ok = ok && std::isfinite(a) && std::isfinite(b);
        d[i] = double(a) - double(b);
      }
      if (!ok) {
        ++stats.non_finite;
        continue;
      }
      ++stats.pixels;
      for (double e : d) {
        sum_sq += e * e;
        sum_abs += std::abs(e);
        stats.max_abs_error = std::max(stats.max_abs_error, std::abs(e));
      }
    }
  }
  if (stats.pixels > 0) {
    const double values = 3.0 * double(stats.pixels);
    stats.rmse = std::sqrt(sum_sq / values);
    stats.mean_abs_error = sum_abs / values;
  }
  return stats;
}

}  // namespace kaskad::reference
