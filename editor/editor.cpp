// `kaskad edit`: the app loop (events, script steps, the frame, the UI, the edits the panels
// asked for) and the entry that opens the window. The editor's parts: editor_app.h.
#include "editor/editor.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include "components/camera.h"
#include "editor/debug_views.h"
#include "editor/editor_app.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/scene_io.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/file_io.h"
#include "runtime/gpu/context.h"

namespace kaskad::editor {

Layout layout_for(int w, int h, float left, float right, bool hidden) {
  Layout l;
  if (hidden || w < kMinPanelsWindow) {
    l.view_w = w;
    l.view_h = h;
    return l;
  }
  l.panels = true;
  const float fw = float(w);
  l.left = left < 0 ? std::clamp(0.2f * fw, 160.0f, 300.0f) : left;
  l.right = right < 0 ? std::clamp(0.32f * fw, 200.0f, 460.0f) : right;
  if (left < 0 && right < 0 && l.left + l.right > 0.55f * fw) {
    const float shrink = 0.55f * fw / (l.left + l.right);
    l.left *= shrink;
    l.right *= shrink;
  }
  l.left = std::clamp(l.left, kMinPanel, max_panel(w));
  l.right = std::clamp(l.right, kMinPanel, max_panel(w));
  // Each panel is at most 45% of a window at least 2 * kMinPanel wide: the viewport keeps 10%.
  l.view_x = int(l.left);
  l.view_w = w - int(l.left) - int(l.right);
  l.view_h = h;
  return l;
}

void Editor::draw_ui(int w, int h) {
  widgets_.clear();
  const Layout l = layout_for(w, h, left_w_, right_w_, panels_hidden_);
  const ImGuiWindowFlags fixed = kPanelFlags | ImGuiWindowFlags_NoResize;
  // Panels keep the window's height; only their inner edge moves. H hides them.
  if (l.panels) entities_panel(w, h, l);

  ImGui::SetNextWindowPos(ImVec2(float(l.view_x), 0));
  ImGui::SetNextWindowSize(ImVec2(float(l.view_w), float(l.view_h)));
  ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(0, 0));
  ImGui::Begin("Viewport", nullptr, fixed | ImGuiWindowFlags_NoDecoration |
                                        ImGuiWindowFlags_NoBringToFrontOnFocus);
  if (view_texture_) {
    // Scaled to fit: the shadow map view is the map's size, its layers stacked.
    const float scale = std::min({1.0f, float(l.view_w) / float(texture_w_),
                                  float(l.view_h) / float(texture_h_)});
    ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<std::uintptr_t>(view_texture_.id())),
                 ImVec2(float(texture_w_) * scale, float(texture_h_) * scale));
  }
  if (panels_hidden_) {
    ImGui::SetCursorPos(ImVec2(6, 4));
    ImGui::TextDisabled("H: panels");
  }
  if (empty_view_ && view_ == View::colour) {
    if (const auto cam = active_camera()) {
      const Camera& c = scene_.world.get<Camera>(*cam);
      char text[256];
      std::snprintf(text, sizeof text,
                    "Nothing in view: the scene may lie outside the camera's near and far planes "
                    "(%g, %g). F frames the selection.",
                    double(c.near), double(c.far));
      // Wrapped to the viewport, on a dark band whatever the clear colour.
      const float wrap = std::max(80.0f, float(l.view_w) - 24.0f);
      const ImVec2 size = ImGui::CalcTextSize(text, nullptr, false, wrap);
      const ImVec2 at = ImVec2(ImGui::GetWindowPos().x + 8.0f, ImGui::GetWindowPos().y + 24.0f);
      ImGui::GetWindowDrawList()->AddRectFilled(ImVec2(at.x - 4.0f, at.y - 3.0f),
                                                ImVec2(at.x + size.x + 4.0f, at.y + size.y + 3.0f),
                                                IM_COL32(20, 20, 20, 210), 3.0f);
      ImGui::SetCursorScreenPos(at);
      ImGui::PushTextWrapPos(ImGui::GetCursorPos().x + wrap);
      ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.4f, 1.0f), "%s", text);
      ImGui::PopTextWrapPos();
    }
  }
  viewport_hovered_ = ImGui::IsWindowHovered();
  ImGui::End();
  ImGui::PopStyleVar();

  if (l.panels) {
    ImGui::SetNextWindowPos(ImVec2(float(w) - l.right, 0));
    ImGui::SetNextWindowSize(ImVec2(l.right, float(h)));
    ImGui::SetNextWindowSizeConstraints(ImVec2(kMinPanel, float(h)),
                                        ImVec2(max_panel(w), float(h)));
    ImGui::Begin("Inspector", nullptr, kPanelFlags);
    right_w_ = ImGui::GetWindowWidth();
    // Labels keep a fixed share of the panel, so long field names are not clipped.
    ImGui::PushItemWidth(-std::max(120.0f, 0.42f * l.right));
    inspector();
    ImGui::PopItemWidth();
    ImGui::End();
  }

  file_dialog(w, h);

  if (ask_quit_) ImGui::OpenPopup("Unsaved changes");
  if (ImGui::BeginPopupModal("Unsaved changes", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::Text("%s has unsaved changes.", opt_.scene.filename().string().c_str());
    GLFWwindow* window = player_.context->window();
    if (button("Save and quit")) {
      if (Status st = save(opt_.scene); st) glfwSetWindowShouldClose(window, true);
      else report(st.error().to_string());
      ask_quit_ = false;
      ImGui::CloseCurrentPopup();
    }
    ImGui::SameLine();
    if (button("Quit without saving")) {
      saved_ = position_;
      glfwSetWindowShouldClose(window, true);
      ask_quit_ = false;
      ImGui::CloseCurrentPopup();
    }
    ImGui::SameLine();
    if (button("Cancel")) {
      ask_quit_ = false;
      ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
  }
}

void Editor::interactive_input(float dt) {
  ImGuiIO& io = ImGui::GetIO();
  if (!ImGui::IsAnyItemActive()) last_drag_key_.clear();
  // The Dear ImGui 1.86 GLFW backend indexes keys by GLFW key code. While the file dialog is up,
  // keys are its own.
  if (!io.WantTextInput && !dialog_.visible) {
    const char* shortcut = nullptr;
    if (io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_Z, false)) shortcut = "ctrl+z";
    if (io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_Y, false)) shortcut = "ctrl+y";
    if (io.KeyCtrl && !io.KeyShift && ImGui::IsKeyPressed(GLFW_KEY_S, false)) shortcut = "ctrl+s";
    if (!io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_F, false)) shortcut = "f";
    if (!io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_H, false)) shortcut = "h";
    if (io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_O, false))
      show_file_dialog(FileDialog::Purpose::open, file_line_);
    if (io.KeyCtrl && io.KeyShift && ImGui::IsKeyPressed(GLFW_KEY_S, false))
      show_file_dialog(FileDialog::Purpose::save_as, file_line_);
    if (shortcut)
      if (Status st = press(shortcut, 0.0f); !st) report(st.error().to_string());
  }
  if (viewport_hovered_ && io.KeyAlt && ImGui::IsMouseDown(ImGuiMouseButton_Left) &&
      (io.MouseDelta.x != 0.0f || io.MouseDelta.y != 0.0f)) {
    if (Status st = orbit(-io.MouseDelta.x * 0.008f, io.MouseDelta.y * 0.008f); !st)
      report(st.error().to_string());
  }
  if (viewport_hovered_ && ImGui::IsMouseDown(ImGuiMouseButton_Right)) {
    const float radians_per_pixel = 0.004f;
    camera_.yaw += io.MouseDelta.x * radians_per_pixel;
    camera_.pitch = std::clamp(camera_.pitch - io.MouseDelta.y * radians_per_pixel, -1.55f, 1.55f);
    const float step = dt * (io.KeyShift ? 4.0f : 1.0f);
    static constexpr std::pair<int, const char*> kFly[] = {
        {GLFW_KEY_W, "w"}, {GLFW_KEY_A, "a"}, {GLFW_KEY_S, "s"},
        {GLFW_KEY_D, "d"}, {GLFW_KEY_Q, "q"}, {GLFW_KEY_E, "e"}};
    for (const auto& [glfw_key, name] : kFly)
      if (ImGui::IsKeyDown(glfw_key)) (void)press(name, step);
    if (io.MouseDelta.x != 0.0f || io.MouseDelta.y != 0.0f) write_camera();
  }
}

int Editor::run() {
  GLFWwindow* window = player_.context->window();
  const std::vector<ScriptAction>& script = script_;
  std::size_t next = 0;
  int frames_left = 0;
  // `input SECONDS`: until then the window takes real input and no script action runs.
  std::optional<std::chrono::steady_clock::time_point> input_until;
  int input_phases = 0;
  int pixelless_waits = 0;  // passes in a row with a minimised window, 0.1 s each
  auto last = std::chrono::steady_clock::now();
  auto last_reload_check = last;
  for (;;) {
    glfwPollEvents();
    // Shader hot reload, twice a second: a failed compile keeps the last good program and its
    // log (mapped to file:line) stays shown until a later save fixes it.
    if (std::chrono::steady_clock::now() - last_reload_check > std::chrono::milliseconds(500)) {
      last_reload_check = std::chrono::steady_clock::now();
      const auto before = player_.renderer->shaders().stats().reloads;
      for (const auto& e : player_.renderer->shaders().reload_changed()) report(e.to_string());
      if (player_.renderer->shaders().stats().reloads > before) message_.clear();
    }
    bool quit = false;
    if (!opt_.script.empty()) {
      // Script actions run between frames; `frames N` lets N frames render, and a screenshot
      // after a change first renders the frame that shows it.
      if (input_until && std::chrono::steady_clock::now() >= *input_until) {
        input_until.reset();
        std::printf("kaskad edit: input %d ended\n", input_phases);
        std::fflush(stdout);
      }
      while (!input_until && frames_left == 0 && ui_steps_.empty() && next < script.size()) {
        const ScriptAction& a = script[next];
        if (a.kind == ActionKind::screenshot && changed_since_frame_) {
          frames_left = 1;
          break;
        }
        if (Status st = run_action(a, quit); !st) {
          Error e = st.error();
          const std::string where = "line " + std::to_string(a.line);
          std::fprintf(stderr, "kaskad edit: error: %s: %s: %s\n", opt_.script.string().c_str(),
                       where.c_str(), e.to_string().c_str());
          return 1;
        }
        ++next;
        if (a.kind == ActionKind::frames) frames_left = std::stoi(a.args[0]);
        if (a.kind == ActionKind::window_screenshot) frames_left = 1;
        if (a.kind == ActionKind::input) {
          input_until =
              std::chrono::steady_clock::now() + std::chrono::seconds(std::stoi(a.args[0]));
          // Flushed: a test driving the window with real events waits for this line.
          std::printf("kaskad edit: input %d for %s s\n", ++input_phases, a.args[0].c_str());
          std::fflush(stdout);
        }
        if (quit) break;
      }
      if (!quit && !input_until && frames_left == 0 && ui_steps_.empty() && next == script.size()) {
        std::fprintf(stderr, "kaskad edit: error: %s: the script ended without quit or quit!\n",
                     opt_.script.string().c_str());
        return 1;
      }
    } else if (glfwWindowShouldClose(window)) {
      if (!dirty()) quit = true;
      else {
        glfwSetWindowShouldClose(window, false);
        ask_quit_ = true;
      }
    }
    if (quit) break;

    int w = 0, h = 0;
    glfwGetFramebufferSize(window, &w, &h);
    if (w <= 0 || h <= 0) {
      // Minimised: nothing to draw until the window is back. A script's frames and screenshots
      // would wait for it for ever: it gives up after a few seconds instead.
      if (!opt_.script.empty() && ++pixelless_waits > 50) {
        std::fprintf(stderr, "kaskad edit: error: %s: the window has had no pixels (%dx%d, "
                     "minimised?) for 5 s; the script needs its frames\n",
                     opt_.script.string().c_str(), w, h);
        return 1;
      }
      glfwWaitEventsTimeout(0.1);
      continue;
    }
    pixelless_waits = 0;
    // The layout leaves the viewport at least 1x1 (layout_for), so every pass renders it: a
    // screenshot after a change waits for exactly this frame.
    const Layout l = layout_for(w, h, left_w_, right_w_, panels_hidden_);
    if (Status st = render_viewport(l.view_w, l.view_h); !st) {
      if (!opt_.script.empty()) {
        std::fprintf(stderr, "kaskad edit: error: %s\n", st.error().to_string().c_str());
        return 1;
      }
      // A scene that cannot be drawn (its camera deleted, say) is shown as an error until an
      // edit or an undo fixes it; the window stays.
      if (message_ != st.error().to_string()) report(st.error().to_string());
    }
    if (frames_left > 0) --frames_left;

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    // A script's clicks and typing, between the backend's input and Dear ImGui's frame.
    if (!opt_.script.empty() && !input_until) {
      if (Status st = feed_ui_step(); !st) {
        std::fprintf(stderr, "kaskad edit: error: %s\n", st.error().to_string().c_str());
        return 1;
      }
    }
    ImGui::NewFrame();
    const auto now = std::chrono::steady_clock::now();
    const float dt = std::min(std::chrono::duration<float>(now - last).count(), 0.1f);
    last = now;
    if (opt_.script.empty() || input_until) interactive_input(dt);
    draw_ui(w, h);
    // A number being typed whose field was not drawn again (a click on another entity's row
    // changed the inspector): the click ended the typing, which applies it.
    if (!typed_.first.empty() && !ImGui::IsAnyItemActive()) {
      requests_.emplace_back(typed_.second, false);
      typed_ = {};
    }
    ImGui::Render();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, w, h);
    glClearColor(0.1f, 0.1f, 0.1f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (!window_shot_.empty()) {
      if (Status st = save_image(window_shot_, read_window(w, h)); !st) {
        std::fprintf(stderr, "kaskad edit: error: %s\n", st.error().to_string().c_str());
        return 1;
      }
      std::printf("kaskad edit: wrote %s\n", window_shot_.string().c_str());
      window_shot_.clear();
    }
    player_.context->swap_buffers();

    // Edits from the panels, in the order made; a rejected one shows its error and changes nothing.
    for (const auto& [assignment, merge] : requests_) {
      // A drag the readers refuse at every step says so once.
      if (Status st = edit(assignment, merge); !st) {
        if (st.error().to_string() != message_) report(st.error().to_string());
      } else {
        message_.clear();
      }
    }
    requests_.clear();
    for (const auto& op : operations_) {
      if (Status st = op(); !st) report(st.error().to_string());
      else message_.clear();
    }
    operations_.clear();
  }
  return gpu::exit_status_for_gl_errors("kaskad edit");
}

int run_edit(const EditOptions& options) {
  // Whole lines: the frame lines (stdout) and errors (stderr) do not cut into each other.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  Options opt = options;
  if (opt.scene.empty()) opt.scene = content_dir() / "scenes" / "default.json";
  std::vector<ScriptAction> script;
  if (!opt.script.empty()) {
    auto parsed = parse_script(opt.script);
    if (!parsed) {
      std::fprintf(stderr, "kaskad edit: error: %s\n", parsed.error().to_string().c_str());
      return 1;
    }
    script = std::move(parsed.value());
    // Its outputs are checked before the scene loads or a frame renders, as a command line's
    // are: a screenshot or save into a folder that does not exist fails at once, naming its line.
    for (const ScriptAction& a : script) {
      Status st;
      if (a.kind == ActionKind::screenshot || a.kind == ActionKind::window_screenshot)
        st = check_image_output(a.args[0]);
      else if ((a.kind == ActionKind::save || a.kind == ActionKind::save_as) && !a.args.empty())
        st = check_output_path(a.args[0]);
      if (!st) {
        std::fprintf(stderr, "kaskad edit: error: %s: line %d: %s\n", opt.script.string().c_str(),
                     a.line, st.error().to_string().c_str());
        return 1;
      }
    }
  }
  auto scene = load_scene(opt.scene, opt.sets);
  if (!scene) {
    std::fprintf(stderr, "kaskad edit: error: %s\n", scene.error().to_string().c_str());
    return 1;
  }
  if (!gpu::display_available()) {
    std::fprintf(stderr, "kaskad edit: error: no display (DISPLAY or WAYLAND_DISPLAY): the editor "
                         "needs a window; under CI run it with xvfb-run -a\n");
    return 1;
  }
  gpu::ContextOptions copt;
  copt.headless = false;
  copt.window_width = opt.width;
  copt.window_height = opt.height;
  copt.title = "Kaskad editor - " + opt.scene.string();
  auto player = Player::create(copt);
  if (!player) {
    std::fprintf(stderr, "kaskad edit: error: %s\n", player.error().to_string().c_str());
    return 1;
  }
  GLFWwindow* window = player->context->window();
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini dropped into the working directory
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 450 core");
  int status = 0;
  {
    Editor editor(std::move(opt), std::move(scene.value()), player.value(), std::move(script));
    status = editor.run();
  }
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  return status;
}

}  // namespace kaskad::editor
