#include "runtime/app/envmap_command.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string_view>

#include "runtime/assets/env_map.h"
#include "runtime/assets/image_io.h"
#include "runtime/core/output_paths.h"
#include "runtime/core/output_paths.h"
#include "components/light.h"
#include "components/transform.h"
#include "runtime/reference/ray_tracer.h"
#include "runtime/reference/reflection_reference.h"
#include "runtime/reference/shadow_metrics.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

int fail(const Error& e) {
  std::fprintf(stderr, "kaskad: error: %s\n", e.to_string().c_str());
  return 1;
}

}  // namespace

int run_envmap(const EnvmapOptions& o) {
  // Outputs are checked before any work (docs/guide/bad_input.md, "Outputs"); no folder is made
  // but one named by --faces DIR.
  if (!o.faces_out.empty())
    if (auto st = check_cube_faces_output(o.faces_out); !st) return fail(st.error());
  if (!o.sphere_out.empty())
    if (auto st = check_image_output(o.sphere_out); !st) return fail(st.error());
  // No output may replace another, or the input (a face of it, for a pattern).
  std::vector<NamedPath> outputs, inputs = {{"IN", o.input}};
  if (!o.faces_out.empty())
    for (const std::string& file : cube_face_files(o.faces_out)) outputs.push_back({"--faces", file});
  if (!o.sphere_out.empty()) outputs.push_back({"--sphere", o.sphere_out});
  if (o.input.find('*') != std::string::npos)
    for (const std::string& file : cube_face_files(o.input)) inputs.push_back({"IN", file});
  if (auto st = check_distinct_outputs(outputs, inputs); !st) {
    std::fprintf(stderr, "kaskad envmap: %s\n", st.error().to_string().c_str());
    return 2;
  }
  const auto t0 = std::chrono::steady_clock::now();
  EnvLayout layout = o.load.layout;
  auto cube = load_cube_map(o.input, o.load, &layout);
  if (!cube) return fail(cube.error());
  std::printf("envmap    %s: %s, %d^2 x 6 faces%s (load %.1f ms)\n", o.input.c_str(),
              env_layout_name(layout), cube->size,
              o.load.z_up_3dsmax ? ", converted from 3ds Max Z-up" : "", ms_since(t0));
  if (!o.faces_out.empty()) {
    if (auto st = save_cube_faces(*cube, o.faces_out); !st) return fail(st.error());
    std::printf("wrote     %s (px nx py ny pz nz)\n", o.faces_out.c_str());
  }
  if (!o.sphere_out.empty()) {
    const int size = o.sphere_size > 0 ? o.sphere_size : 2 * cube->size;
    const auto t1 = std::chrono::steady_clock::now();
    const SphereMap map = sphere_map_from_cube(*cube, size);
    const double ms = ms_since(t1);
    if (auto st = save_sphere_map(map, o.sphere_out); !st) return fail(st.error());
    std::printf("wrote     %s (sphere map %d^2, S3 eq. 2, %.1f ms)\n", o.sphere_out.c_str(), size,
                ms);
  }
  return 0;
}

Status write_reflection_reference(const Scene& scene, const Image& aov, const glm::vec3& eye,
                                  const std::string& environment, const std::string& out) {
  CubeMap env;
  if (!environment.empty()) {
    auto cube = load_cube_map(environment);
    if (!cube) return cube.error();
    env = std::move(*cube);
  }
  auto tracer = reference::RayTracer::build(scene);
  if (!tracer) return tracer.error();
  const reference::ReflectionScene rs =
      reference::reflection_scene(scene, environment.empty() ? nullptr : &env);
  auto ref = reference::reflection_reference(*tracer, aov, rs, eye);
  if (!ref) return ref.error();
  KASKAD_TRY(save_image(out, ref->image));
  std::printf(
      "wrote     %s (reflection reference: reflection.R/G/B reflection.hit mask; %llu rays, "
      "%.1f ms, %.2f Mrays/s)\n",
      fs::absolute(out).string().c_str(), static_cast<unsigned long long>(ref->rays),
      ref->seconds * 1e3, ref->seconds > 0.0 ? double(ref->rays) / ref->seconds * 1e-6 : 0.0);
  return {};
}

Status write_shadow_reference(const Scene& scene, const Image& aov, ecs::Entity light,
                              const std::string& out) {
  auto tracer = reference::RayTracer::build(scene);
  if (!tracer) return tracer.error();
  const auto rlight = reference::reference_light(scene.world, light);
  auto ref = tracer->shadow_reference(aov, rlight, {});
  if (!ref) return ref.error();
  auto metrics = reference::compare_shadows(aov, ref->image);
  if (!metrics) return metrics.error();
  const int method_ch = aov.channel("visibility");
  const int ref_ch = ref->image.channel("visibility");
  const int receiver_ch = ref->image.channel("receiver");
  Image img;
  img.width = aov.width;
  img.height = aov.height;
  img.channels = 4;
  img.channel_names = {"reference", "visibility", "error", "receiver"};
  const std::size_t n = std::size_t(aov.width) * std::size_t(aov.height);
  img.pixels.resize(n * 4);
  for (std::size_t i = 0; i < n; ++i) {
    const float v = aov.pixels[i * std::size_t(aov.channels) + std::size_t(method_ch)];
    const float r = ref->image.pixels[i * std::size_t(ref->image.channels) + std::size_t(ref_ch)];
    const float rec =
        ref->image.pixels[i * std::size_t(ref->image.channels) + std::size_t(receiver_ch)];
    img.pixels[i * 4 + 0] = r;
    img.pixels[i * 4 + 1] = v;
    img.pixels[i * 4 + 2] = rec > 0.0f ? v - r : 0.0f;
    img.pixels[i * 4 + 3] = rec;
  }
  KASKAD_TRY(save_image(out, img));
  std::printf("wrote     %s (shadow reference: reference visibility error receiver; %zu receiver "
              "pixels, RMSE %.4f, MAE %.4f; %.1f ms)\n",
              fs::absolute(out).string().c_str(), metrics->all.pixels, metrics->all.rmse,
              metrics->all.mean_abs_error, ref->seconds * 1e3);
  return {};
}

}  // namespace kaskad
