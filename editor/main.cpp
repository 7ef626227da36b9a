// kaskad_editor: a window onto a scene with toggles for the shadow settings and the light.
// Same runtime and frame phases as the headless player; the editor only edits components and
// settings between frames.  usage: kaskad_editor [SCENE] [--set key=value]...
#include <epoxy/gl.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include "components/light.h"
#include "components/reflector.h"
#include "components/name.h"
#include "components/shadow_settings.h"
#include "runtime/assets/image_io.h"
#include "runtime/cli/player.h"
#include "runtime/gpu/context.h"

using namespace kaskad;

namespace {

// Shadow settings of the shadowed light, as editable widgets. Returns true when something changed.
bool shadow_panel(ShadowSettings& s) {
  bool changed = false;
  static const int sizes[] = {256, 512, 1024, 2048, 4096};
  int size_index = 3;
  for (int i = 0; i < 5; ++i)
    if (sizes[i] == s.map_size) size_index = i;
  const char* size_names[] = {"256", "512", "1024", "2048", "4096"};
  if (ImGui::Combo("map size", &size_index, size_names, 5)) {
    s.map_size = sizes[size_index];
    changed = true;
  }
  int filter = int(s.filter);
  const char* filters[] = {"none (1 tap)", "bilinear (2x2 hardware)", "pcf 3x3"};
  if (ImGui::Combo("filter", &filter, filters, 3)) {
    s.filter = ShadowFilter(filter);
    changed = true;
  }
  // Soft shadows (issue 14): frame shader features, so a change compiles a program once.
  int technique = int(s.technique);
  const char* techniques[] = {"pcf (hard)", "pcss (Fernando 2005)", "backprojection (2006)"};
  if (ImGui::Combo("technique", &technique, techniques, 3)) {
    s.technique = ShadowTechnique(technique);
    changed = true;
  }
  int kernel = int(s.pcf_kernel);
  const char* kernels[] = {"3x3", "5x5", "7x7", "9x9", "poisson disc"};
  if (ImGui::Combo("pcf kernel", &kernel, kernels, 5)) {
    s.pcf_kernel = PcfKernel(kernel);
    changed = true;
  }
  changed |= ImGui::SliderInt("disc taps", &s.pcf_taps, 8, 64);
  changed |= ImGui::SliderFloat("disc radius (texels)", &s.pcf_radius, 1.0f, 16.0f);
  int cull = int(s.cull);
  const char* culls[] = {"back", "front", "none"};
  if (ImGui::Combo("shadow cull", &cull, culls, 3)) {
    s.cull = CullMode(cull);
    changed = true;
  }
  changed |= ImGui::SliderFloat("constant bias", &s.constant_bias, 0.0f, 50.0f);
  changed |= ImGui::SliderFloat("slope bias", &s.slope_bias, 0.0f, 10.0f);
  // Cascades (S0, S2). Edits keep the settings valid: fit "scene" is the one-map basic fit.
  int fit = int(s.fit_mode);
  const char* fits[] = {"crop (S0)", "stable (S2)", "scene (basic map)"};
  if (ImGui::Combo("fit", &fit, fits, 3)) {
    s.fit_mode = FitMode(fit);
    if (s.fit_mode == FitMode::scene) s.cascade_count = 1;
    changed = true;
  }
  if (ImGui::SliderInt("cascades", &s.cascade_count, 1, 8)) {
    if (s.cascade_count > 1 && s.fit_mode == FitMode::scene) s.fit_mode = FitMode::stable;
    changed = true;
  }
  int scheme = int(s.split_scheme);
  const char* schemes[] = {"uniform (S0 eq. 1)", "log (S0 eq. 2)", "mixed (S0 eq. 3)"};
  if (ImGui::Combo("splits", &scheme, schemes, 3)) {
    s.split_scheme = SplitScheme(scheme);
    changed = true;
  }
  changed |= ImGui::SliderFloat("lambda", &s.lambda, 0.0f, 1.0f);
  changed |= ImGui::SliderFloat("max distance (0 = far)", &s.max_distance, 0.0f, 500.0f);
  changed |= ImGui::SliderFloat("normal offset (texels)", &s.normal_offset_bias, 0.0f, 4.0f);
  changed |= ImGui::SliderFloat("blend band", &s.blend_band, 0.0f, 1.0f);
  int selection = int(s.selection);
  const char* selections[] = {"view depth (S0)", "map bounds"};
  if (ImGui::Combo("selection", &selection, selections, 2)) {
    s.selection = CascadeSelection(selection);
    changed = true;
  }
  int format = int(s.depth_format);
  const char* formats[] = {"16", "24", "32F"};
  if (ImGui::Combo("depth bits", &format, formats, 3)) {
    s.depth_format = DepthFormat(format);
    changed = true;
  }
  changed |= ImGui::Checkbox("debug: colour cascades", &s.debug_cascades);
  changed |= ImGui::Checkbox("debug: freeze cascades", &s.freeze_cascades);
  changed |= ImGui::Checkbox("cull casters by receivers", &s.cull_by_receivers);
  changed |= ImGui::Checkbox("draw only what receivers read", &s.scissor_to_receivers);
  changed |= ImGui::SliderInt("far cascades every N frames", &s.far_cascade_interval, 1, 16);
  int point_mode = int(s.point_mode);
  const char* point_modes[] = {"cube (6 faces)", "dual paraboloid (2)"};
  if (ImGui::Combo("point light maps", &point_mode, point_modes, 2)) {
    s.point_mode = PointShadowMode(point_mode);
    changed = true;
  }
  return changed;
}

}  // namespace

int run_editor(int argc, char** argv) {
  std::string scene_path = (content_dir() / "scenes" / "default.json").string();
  std::vector<std::string> sets;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--set" && i + 1 < argc) {
      sets.push_back(argv[++i]);
    } else if (a == "-h" || a == "--help") {
      std::puts("usage: kaskad_editor [SCENE] [--set key=value]...");
      return 0;
    } else {
      scene_path = a;
    }
  }
  auto scene = load_scene(scene_path, sets);
  if (!scene) {
    std::fprintf(stderr, "kaskad_editor: error: %s\n", scene.error().to_string().c_str());
    return 1;
  }
  gpu::ContextOptions opt;
  opt.headless = false;
  opt.window_width = scene->render.width;
  opt.window_height = scene->render.height;
  opt.title = "Kaskad editor - " + scene_path;
  auto player = Player::create(opt);
  if (!player) {
    std::fprintf(stderr, "kaskad_editor: error: %s\n", player.error().to_string().c_str());
    return 1;
  }
  GLFWwindow* window = player->context->window();
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini dropped into the working directory
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 450 core");

  std::uint64_t frame = 0;
  auto last_reload_check = std::chrono::steady_clock::now();
  std::string shader_error;  // last hot-reload failure, shown in the panel until fixed
  int max_frames = -1;  // KASKAD_EDITOR_FRAMES limits the run (for automated screenshots)
  if (const char* f = std::getenv("KASKAD_EDITOR_FRAMES")) max_frames = std::atoi(f);
  while (!glfwWindowShouldClose(window) && (max_frames < 0 || int(frame) < max_frames)) {
    glfwPollEvents();
    int w = 0, h = 0;
    glfwGetFramebufferSize(window, &w, &h);
    if (w <= 0 || h <= 0) continue;
    // Hot reload: poll the shader files twice a second. A failed compile keeps the last good
    // program; its log (mapped to file:line) is shown until a later save fixes it.
    if (std::chrono::steady_clock::now() - last_reload_check > std::chrono::milliseconds(500)) {
      last_reload_check = std::chrono::steady_clock::now();
      const auto before = player->renderer->shaders().stats().reloads;
      for (const auto& e : player->renderer->shaders().reload_changed()) {
        shader_error = e.to_string();
        std::fprintf(stderr, "kaskad_editor: shader reload failed: %s\n", shader_error.c_str());
      }
      if (player->renderer->shaders().stats().reloads > before) shader_error.clear();
    }
    RenderRun run;
    run.prewarm = frame == 0;
    run.width = w;
    run.height = h;
    run.write_aovs = false;
    auto t = render_frames(*player, *scene, run);
    if (!t) {
      std::fprintf(stderr, "kaskad_editor: error: %s\n", t.error().to_string().c_str());
      break;
    }
    player->renderer->present(w, h);

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(330, 0), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowBgAlpha(0.8f);
    ImGui::Begin("Kaskad");
    ImGui::Text("frame %.2f ms (shadow GPU %.2f, forward GPU %.2f)", t->first_frame_ms,
                t->last.stats.shadow_gpu_ms, t->last.stats.forward_gpu_ms);
    ImGui::Text("%d draws, %zu shadow triangles", t->last.stats.draw_calls,
                t->last.stats.shadow_triangles);
    ImGui::Text("%d programs, %d reloads", int(player->renderer->shaders().program_count()),
                player->renderer->shaders().stats().reloads);
    if (!shader_error.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", shader_error.c_str());
    scene->world.view<Light, ShadowSettings>().each(
        [&](ecs::Entity e, Light& light, ShadowSettings& s) {
          const Name* n = scene->world.try_get<Name>(e);
          ImGui::PushID(int(e.index));
          if (ImGui::CollapsingHeader(n ? n->value.c_str() : "light", ImGuiTreeNodeFlags_DefaultOpen)) {
            ImGui::Checkbox("cast shadows", &light.cast_shadows);
            ImGui::SliderFloat("intensity", &light.intensity, 0.0f, 10.0f);
            ImGui::ColorEdit3("colour", &light.color[0]);
            // The light's size (soft shadows and the area-light reference).
            if (light.type == LightType::directional)
              ImGui::SliderFloat("angular size (deg)", &light.angular_size_deg, 0.0f, 45.0f);
            else
              ImGui::SliderFloat("radius (m)", &light.radius, 0.0f, 2.0f);
            shadow_panel(s);
          }
          ImGui::PopID();
        });
    // Reflection probes (S3): the map type switches at runtime (takes effect next frame); amount,
    // cadence and time slicing are live too.
    scene->world.view<Reflector>().each([&](ecs::Entity e, Reflector& r) {
      const Name* n = scene->world.try_get<Name>(e);
      ImGui::PushID(int(e.index) + 0x10000);
      const std::string title = std::string("reflector ") + (n ? n->value : "");
      if (ImGui::CollapsingHeader(title.c_str())) {
        int map = int(r.map);
        const char* maps[] = {"cube map", "sphere map"};
        if (ImGui::Combo("map", &map, maps, 2)) r.map = ReflectionMap(map);
        ImGui::SliderFloat("amount p_r", &r.amount, 0.0f, 1.0f);
        if (r.update == ProbeUpdate::every_n) ImGui::SliderInt("every n frames", &r.every_n, 1, 120);
        ImGui::SliderInt("faces per frame", &r.faces_per_frame, 1, 6);
        if (r.map == ReflectionMap::cube && r.box_max != r.box_min)  // an authored box only
          ImGui::Checkbox("box projection", &r.box_projection);
      }
      ImGui::PopID();
    });
    ImGui::End();
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    ++frame;
    const char* shot = std::getenv("KASKAD_EDITOR_SCREENSHOT");
    if (shot && max_frames >= 0 && int(frame) == max_frames) {
      // The window as the user sees it (scene + UI), for automated checks.
      Image img;
      img.width = w;
      img.height = h;
      img.channels = 3;
      std::vector<unsigned char> bytes(std::size_t(w) * h * 3);
      glPixelStorei(GL_PACK_ALIGNMENT, 1);
      glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, bytes.data());
      img.pixels.resize(bytes.size());
      for (int y = 0; y < h; ++y)
        for (int i = 0; i < w * 3; ++i)
          img.pixels[std::size_t(y) * w * 3 + i] = bytes[std::size_t(h - 1 - y) * w * 3 + i] / 255.0f;
      if (auto st = save_image(shot, img); !st) {
        std::fprintf(stderr, "kaskad_editor: error: %s\n", st.error().to_string().c_str());
        return 1;
      }
      std::printf("wrote %s\n", shot);
    }
    player->context->swap_buffers();
  }
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  return 0;
}

int main(int argc, char** argv) {
  // As in the CLI (runtime/cli/main.cpp): a file-size limit fails a write instead of killing the
  // editor, and anything that escapes the readers is an error exit with a message, not an abort.
  std::signal(SIGXFSZ, SIG_IGN);
  try {
    return run_editor(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kaskad_editor: error: unexpected failure: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "kaskad_editor: error: unexpected failure (unknown exception)\n");
  }
  return 1;
}
