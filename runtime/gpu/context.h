// The OpenGL 4.5 core context. Headless: EGL (device platform on a GPU, else Mesa's surfaceless
// platform, i.e. llvmpipe); windowed: a GLFW 3.3 window. Renderer code is the same for both, since
// it always draws into its own framebuffers; a window only adds a final blit and a swap.
#pragma once

#include <memory>
#include <string>

#include "runtime/result/result.h"

struct GLFWwindow;

namespace kaskad::gpu {

struct ContextOptions {
  bool headless = true;
  int window_width = 1280;
  int window_height = 720;
  std::string title = "Kaskad";
  bool debug = true;  ///< KHR_debug output to the log (errors are counted, see debug_error_count)
};

class Context {
 public:
  /// Creates a context and makes it current on this thread.
  static Result<std::unique_ptr<Context>> create(const ContextOptions& options);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  bool headless() const { return window_ == nullptr; }
  GLFWwindow* window() const { return window_; }
  /// "vendor | renderer | version", e.g. "Mesa | llvmpipe (LLVM 15.0.6, 256 bits) | 4.5 (Core ...".
  const std::string& description() const { return description_; }
  /// How the context was made: "egl-device", "egl-surfaceless" or "glfw".
  const std::string& platform() const { return platform_; }
  void swap_buffers();

 private:
  Context() = default;
  struct Egl;
  std::unique_ptr<Egl> egl_;
  GLFWwindow* window_ = nullptr;
  std::string description_;
  std::string platform_;
};

/// True when a display is available for a window (DISPLAY or WAYLAND_DISPLAY set).
bool display_available();

/// Number of GL debug messages of type ERROR received since start or the last reset.
/// GL errors are bugs: tests assert this stays 0.
int debug_error_count();
void reset_debug_error_count();
/// A command's exit status for the GL errors so far: 0 without any; 1 after printing
/// "<who>: error: N OpenGL errors were reported (see log above)<detail>" to stderr.
int exit_status_for_gl_errors(const char* who, const char* detail = "");

/// Installs the KHR_debug callback on the current context (done by Context::create when debug).
void install_debug_output();

}  // namespace kaskad::gpu
