#include "runtime/gpu/context.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "runtime/core/log.h"

namespace kaskad::gpu {
namespace {

std::atomic<int> g_debug_errors{0};

const char* debug_source(GLenum source) {
  switch (source) {
    case GL_DEBUG_SOURCE_API: return "api";
    case GL_DEBUG_SOURCE_WINDOW_SYSTEM: return "window";
    case GL_DEBUG_SOURCE_SHADER_COMPILER: return "shader-compiler";
    case GL_DEBUG_SOURCE_THIRD_PARTY: return "third-party";
    case GL_DEBUG_SOURCE_APPLICATION: return "application";
    default: return "other";
  }
}

void GLAPIENTRY on_debug_message(GLenum source, GLenum type, GLuint id, GLenum severity,
                                 GLsizei /*length*/, const GLchar* message, const void* /*user*/) {
  // Shader compile and link failures reach the caller as content errors (with the log mapped to
  // file:line); Mesa also reports them here as type ERROR, so they are not counted twice.
  if (type == GL_DEBUG_TYPE_ERROR && source != GL_DEBUG_SOURCE_SHADER_COMPILER) {
    ++g_debug_errors;
    log::error("GL error (%s, id %u): %s", debug_source(source), id, message);
  } else if (source == GL_DEBUG_SOURCE_SHADER_COMPILER) {
    log::debug("GL (%s, id %u): %s", debug_source(source), id, message);
  } else if (severity == GL_DEBUG_SEVERITY_HIGH || severity == GL_DEBUG_SEVERITY_MEDIUM) {
    log::warn("GL (%s, id %u): %s", debug_source(source), id, message);
  } else {
    log::debug("GL (%s, id %u): %s", debug_source(source), id, message);
  }
}

std::string describe_current_context() {
  auto str = [](GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return str(GL_VENDOR) + " | " + str(GL_RENDERER) + " | " + str(GL_VERSION);
}

bool has_extension(const char* list, const char* name) {
  if (!list) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = std::strstr(list, name); p; p = std::strstr(p + 1, name)) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

}  // namespace

struct Context::Egl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
};

bool display_available() {
  const char* x = std::getenv("DISPLAY");
  const char* w = std::getenv("WAYLAND_DISPLAY");
  return (x && *x) || (w && *w);
}

int debug_error_count() { return g_debug_errors; }

int exit_status_for_gl_errors(const char* who, const char* detail) {
  if (g_debug_errors == 0) return 0;
  std::fprintf(stderr, "%s: error: %d OpenGL errors were reported (see log above)%s\n", who,
               g_debug_errors.load(), detail);
  return 1;
}
void reset_debug_error_count() { g_debug_errors = 0; }

void install_debug_output() {
  if (!epoxy_has_gl_extension("GL_KHR_debug") && epoxy_gl_version() < 43) {
    log::warn("KHR_debug is not available: GL errors will not be reported");
    return;
  }
  glEnable(GL_DEBUG_OUTPUT);
  glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);  // report on the offending call's thread and stack
  glDebugMessageCallback(on_debug_message, nullptr);
  glDebugMessageControl(GL_DONT_CARE, GL_DONT_CARE, GL_DONT_CARE, 0, nullptr, GL_TRUE);
}

namespace {

// Picks an EGL display: a hardware device when one exists (EGL_EXT_platform_device), else Mesa's
// surfaceless platform (llvmpipe). Returns EGL_NO_DISPLAY when neither initialises.
EGLDisplay open_egl_display(std::string& platform) {
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (has_extension(client_ext, "EGL_EXT_device_enumeration") &&
      has_extension(client_ext, "EGL_EXT_platform_device")) {
    EGLint count = 0;
    eglQueryDevicesEXT(0, nullptr, &count);
    std::vector<EGLDeviceEXT> devices(std::size_t(std::max(count, 0)));
    if (count > 0 && eglQueryDevicesEXT(count, devices.data(), &count)) {
      for (EGLDeviceEXT dev : devices) {
        const char* dev_ext = eglQueryDeviceStringEXT(dev, EGL_EXTENSIONS);
        if (has_extension(dev_ext, "EGL_MESA_device_software")) continue;  // llvmpipe's device
        EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, dev, nullptr);
        EGLint major = 0, minor = 0;
        if (d != EGL_NO_DISPLAY && eglInitialize(d, &major, &minor)) {
          platform = "egl-device";
          return d;
        }
      }
    }
  }
  if (has_extension(client_ext, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY,
                                            nullptr);
    EGLint major = 0, minor = 0;
    if (d != EGL_NO_DISPLAY && eglInitialize(d, &major, &minor)) {
      platform = "egl-surfaceless";
      return d;
    }
  }
  return EGL_NO_DISPLAY;
}

}  // namespace

Result<std::unique_ptr<Context>> Context::create(const ContextOptions& options) {
  std::unique_ptr<Context> ctx(new Context());
  if (options.headless) {
    ctx->egl_ = std::make_unique<Egl>();
    ctx->egl_->display = open_egl_display(ctx->platform_);
    if (ctx->egl_->display == EGL_NO_DISPLAY)
      return Error{"", "EGL", "no usable EGL display (tried device and Mesa surfaceless platforms)"};
    if (!eglBindAPI(EGL_OPENGL_API)) return Error{"", "EGL", "eglBindAPI(EGL_OPENGL_API) failed"};
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4,
                              EGL_CONTEXT_MINOR_VERSION, 5,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                              EGL_CONTEXT_OPENGL_DEBUG, options.debug ? EGL_TRUE : EGL_FALSE,
                              EGL_NONE};
    // Configless + surfaceless: we always render into our own framebuffer objects.
    ctx->egl_->context =
        eglCreateContext(ctx->egl_->display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attribs);
    if (ctx->egl_->context == EGL_NO_CONTEXT) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "eglCreateContext for OpenGL 4.5 core failed (0x%x)",
                    eglGetError());
      return Error{"", "EGL", buf};
    }
    if (!eglMakeCurrent(ctx->egl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx->egl_->context))
      return Error{"", "EGL", "eglMakeCurrent failed"};
  } else {
    if (!glfwInit()) return Error{"", "GLFW", "glfwInit failed (is a display available?)"};
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, options.debug ? GLFW_TRUE : GLFW_FALSE);
    ctx->window_ = glfwCreateWindow(options.window_width, options.window_height,
                                    options.title.c_str(), nullptr, nullptr);
    if (!ctx->window_) {
      glfwTerminate();
      return Error{"", "GLFW", "could not create an OpenGL 4.5 core window"};
    }
    glfwMakeContextCurrent(ctx->window_);
    glfwSwapInterval(1);
    ctx->platform_ = "glfw";
  }
  if (epoxy_gl_version() < 45)
    return Error{"", "OpenGL", "OpenGL 4.5 core is required, got " + describe_current_context()};
  ctx->description_ = describe_current_context();
  if (options.debug) install_debug_output();
  return ctx;
}

Context::~Context() {
  if (window_) {
    glfwDestroyWindow(window_);
    glfwTerminate();
  }
  if (egl_ && egl_->display != EGL_NO_DISPLAY) {
    eglMakeCurrent(egl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (egl_->context != EGL_NO_CONTEXT) eglDestroyContext(egl_->display, egl_->context);
    eglTerminate(egl_->display);
  }
}

void Context::swap_buffers() {
  if (window_) glfwSwapBuffers(window_);
}

}  // namespace kaskad::gpu
