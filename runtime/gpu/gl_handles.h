// RAII owners for OpenGL objects. Public APIs pass these typed handles, never a raw GLuint
// (STYLE.md 11): the type says what the object is, and ownership is explicit (move-only).
#pragma once

#include <epoxy/gl.h>

#include <atomic>
#include <utility>

namespace kaskad::gpu {

/// Move-only owner of one GL object name; Deleter::destroy(GLuint) frees it.
template <class Deleter>
class GlObject {
 public:
  GlObject() = default;
  explicit GlObject(GLuint id) : id_(id) {
    if (id_ != 0) ++live_;
  }
  ~GlObject() { reset(); }
  GlObject(GlObject&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  GlObject& operator=(GlObject&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, 0);
    }
    return *this;
  }
  GlObject(const GlObject&) = delete;
  GlObject& operator=(const GlObject&) = delete;

  /// The GL name, for GL calls inside the gpu/render modules only.
  GLuint id() const { return id_; }
  explicit operator bool() const { return id_ != 0; }
  void reset() {
    if (id_ != 0) {
      Deleter::destroy(id_);
      --live_;
    }
    id_ = 0;
  }
  /// Objects of this kind alive now (leak checks: the count stays flat while frames repeat).
  static long live() { return live_; }

 private:
  GLuint id_ = 0;
  static inline std::atomic<long> live_{0};
};

namespace detail {
struct BufferDeleter { static void destroy(GLuint id) { glDeleteBuffers(1, &id); } };
struct TextureDeleter { static void destroy(GLuint id) { glDeleteTextures(1, &id); } };
struct FramebufferDeleter { static void destroy(GLuint id) { glDeleteFramebuffers(1, &id); } };
struct RenderbufferDeleter { static void destroy(GLuint id) { glDeleteRenderbuffers(1, &id); } };
struct VertexArrayDeleter { static void destroy(GLuint id) { glDeleteVertexArrays(1, &id); } };
struct ProgramDeleter { static void destroy(GLuint id) { glDeleteProgram(id); } };
struct ShaderDeleter { static void destroy(GLuint id) { glDeleteShader(id); } };
struct QueryDeleter { static void destroy(GLuint id) { glDeleteQueries(1, &id); } };
struct SamplerDeleter { static void destroy(GLuint id) { glDeleteSamplers(1, &id); } };
}  // namespace detail

/// A typed, non-owning name of a GL object that a GlObject of the same kind owns elsewhere: what
/// public APIs hand out when they keep ownership (a program from the shader library, a probe's
/// map). Valid while that owner lives and is not reset or replaced; default: none (GL name 0).
template <class Deleter>
class GlRef {
 public:
  GlRef() = default;
  /// Refers to what `owner` holds now (none when it holds nothing).
  GlRef(const GlObject<Deleter>& owner) : id_(owner.id()) {}  // NOLINT: implicit on purpose
  /// The GL name, for GL calls inside the gpu/render modules only.
  GLuint id() const { return id_; }
  explicit operator bool() const { return id_ != 0; }
  bool operator==(const GlRef&) const = default;

 private:
  GLuint id_ = 0;
};

using Buffer = GlObject<detail::BufferDeleter>;
using Texture = GlObject<detail::TextureDeleter>;
using Framebuffer = GlObject<detail::FramebufferDeleter>;
using Renderbuffer = GlObject<detail::RenderbufferDeleter>;
using VertexArray = GlObject<detail::VertexArrayDeleter>;
using Program = GlObject<detail::ProgramDeleter>;
using Shader = GlObject<detail::ShaderDeleter>;
using Query = GlObject<detail::QueryDeleter>;
using Sampler = GlObject<detail::SamplerDeleter>;
using TextureRef = GlRef<detail::TextureDeleter>;
using ProgramRef = GlRef<detail::ProgramDeleter>;
using FramebufferRef = GlRef<detail::FramebufferDeleter>;

/// GL objects alive through these owners, all kinds together.
inline long live_gl_objects() {
  return Buffer::live() + Texture::live() + Framebuffer::live() + Renderbuffer::live() +
         VertexArray::live() + Program::live() + Shader::live() + Query::live() + Sampler::live();
}

// DSA creation helpers (OpenGL 4.5).
inline Buffer make_buffer() { GLuint id = 0; glCreateBuffers(1, &id); return Buffer(id); }
inline Texture make_texture(GLenum target) { GLuint id = 0; glCreateTextures(target, 1, &id); return Texture(id); }
inline Framebuffer make_framebuffer() { GLuint id = 0; glCreateFramebuffers(1, &id); return Framebuffer(id); }
inline VertexArray make_vertex_array() { GLuint id = 0; glCreateVertexArrays(1, &id); return VertexArray(id); }
inline Query make_query(GLenum target) { GLuint id = 0; glCreateQueries(target, 1, &id); return Query(id); }
inline Sampler make_sampler() { GLuint id = 0; glCreateSamplers(1, &id); return Sampler(id); }

}  // namespace kaskad::gpu
