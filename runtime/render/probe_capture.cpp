#include "runtime/render/probe_capture.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "components/ibl.h"
#include "runtime/gpu/shader.h"

namespace kaskad::render {
namespace {

gpu::Texture make_cube(int size) {
  gpu::Texture t = gpu::make_texture(GL_TEXTURE_CUBE_MAP);
  glTextureStorage2D(t.id(), cube_mip_levels(size), GL_RGBA16F, size, size);
  set_cube_sampling(t);
  // A new map is black until its first capture or upload (never uninitialised memory).
  const float black[4] = {0, 0, 0, 1};
  for (int level = 0; level < cube_mip_levels(size); ++level)
    glClearTexImage(t.id(), level, GL_RGBA, GL_FLOAT, black);
  return t;
}

}  // namespace

Result<std::unique_ptr<ProbeMaps>> ProbeMaps::create(const std::filesystem::path& shader_dir) {
  std::unique_ptr<ProbeMaps> m(new ProbeMaps());
  auto prog = fullscreen_program(shader_dir, "probe_sphere.frag");
  if (!prog) return prog.error();
  m->sphere_program_ = std::move(prog.value());
  m->empty_vao_ = gpu::make_vertex_array();
  m->fbo_ = gpu::make_framebuffer();
  auto ibl = IblMaps::create(shader_dir);
  if (!ibl) return ibl.error();
  m->ibl_ = std::move(ibl.value());
  return m;
}

gpu::TextureRef ProbeMaps::cube(ProbeHandle handle, int buffer, int resolution) {
  Probe& p = probes_[handle];
  if (p.resolution != resolution || !p.cubes[0]) {
    p.resolution = resolution;
    p.cubes[0] = make_cube(resolution);
    p.cubes[1] = make_cube(resolution);
    p.sphere = gpu::Texture();
    p.specular[0] = gpu::Texture();  // made again at the new size by prefilter()
    p.specular[1] = gpu::Texture();
    p.shown = -1;
    p.pending = {-1, 0};
  }
  return p.cubes[buffer & 1];
}

gpu::TextureRef ProbeMaps::existing_cube(ProbeHandle handle, int buffer) const {
  auto it = probes_.find(handle);
  return it == probes_.end() ? gpu::TextureRef() : gpu::TextureRef(it->second.cubes[buffer & 1]);
}

void ProbeMaps::begin_face(ProbeHandle handle, int buffer, int face, const glm::vec3& clear) {
  const Probe& p = probes_.at(handle);
  if (!depth_ || depth_size_ != p.resolution) {
    GLuint id = 0;
    glCreateRenderbuffers(1, &id);
    depth_ = gpu::Renderbuffer(id);
    glNamedRenderbufferStorage(depth_.id(), GL_DEPTH_COMPONENT32F, p.resolution, p.resolution);
    depth_size_ = p.resolution;
  }
  glNamedFramebufferRenderbuffer(fbo_.id(), GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_.id());
  // A cube map's layer f is face f (GL 4.5 section 9.2.8).
  glNamedFramebufferTextureLayer(fbo_.id(), GL_COLOR_ATTACHMENT0, p.cubes[buffer & 1].id(), 0, face);
  glNamedFramebufferDrawBuffer(fbo_.id(), GL_COLOR_ATTACHMENT0);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
  glViewport(0, 0, p.resolution, p.resolution);
  const float c[4] = {clear.r, clear.g, clear.b, 1.0f};
  const float one = 1.0f;
  glClearBufferfv(GL_COLOR, 0, c);
  glClearBufferfv(GL_DEPTH, 0, &one);
  ++faces_rendered;
}

void ProbeMaps::drop(Probe& p) {
  for (int& row : p.sh_rows) {
    ibl_->release_row(row);
    row = -1;
  }
}

void ProbeMaps::clear() {
  for (auto& [handle, p] : probes_) drop(p);
  probes_.clear();
}

void ProbeMaps::retain(const std::vector<ProbeHandle>& live) {
  for (auto it = probes_.begin(); it != probes_.end();) {
    if (std::binary_search(live.begin(), live.end(), it->first)) {
      ++it;
      continue;
    }
    drop(it->second);
    it = probes_.erase(it);
  }
}

void ProbeMaps::finish_cube(ProbeHandle handle, int buffer) {
  Probe& p = probes_.at(handle);
  glGenerateTextureMipmap(p.cubes[buffer & 1].id());
  ++p.changes[buffer & 1];
}

bool ProbeMaps::prefilter(ProbeHandle handle, int buffer, int faces) {
  auto it = probes_.find(handle);
  const int b = buffer & 1;
  if (it == probes_.end() || !it->second.cubes[b]) return false;
  Probe& p = it->second;
  const std::pair<int, std::uint64_t> source{b, p.changes[b]};
  if (p.shown >= 0 && p.shown_source == source) return false;  // up to date
  if (p.pending != source) {  // a new cube: start over
    p.pending = source;
    p.pending_faces = 0;
  }
  const int count = std::clamp(faces, 1, 6 - p.pending_faces);
  ibl_->prefilter_faces(p.cubes[b], p.resolution, p.specular[b], p.pending_faces, count);
  p.pending_faces += count;
  prefilter_faces += count;
  if (p.pending_faces < 6) return false;
  if (p.sh_rows[b] < 0) p.sh_rows[b] = ibl_->acquire_row();
  ibl_->project_sh(p.cubes[b], p.resolution, p.sh_rows[b]);
  p.shown = b;
  p.shown_source = source;
  p.pending = {-1, 0};
  return true;
}

bool ProbeMaps::has_specular(ProbeHandle handle) const {
  auto it = probes_.find(handle);
  return it != probes_.end() && it->second.shown >= 0;
}

gpu::TextureRef ProbeMaps::existing_specular(ProbeHandle handle) const {
  auto it = probes_.find(handle);
  if (it == probes_.end() || it->second.shown < 0) return gpu::TextureRef();
  return gpu::TextureRef(it->second.specular[it->second.shown]);
}

int ProbeMaps::sh_row(ProbeHandle handle) const {
  auto it = probes_.find(handle);
  return it == probes_.end() || it->second.shown < 0 ? -1 : it->second.sh_rows[it->second.shown];
}

int ProbeMaps::specular_last_level(ProbeHandle handle) const {
  auto it = probes_.find(handle);
  return it == probes_.end() ? 0 : ibl_specular_levels(it->second.resolution) - 1;
}

void ProbeMaps::upload(ProbeHandle handle, int buffer, const CubeMap& cube_map) {
  const GLuint tex = cube(handle, buffer, cube_map.size).id();
  for (int f = 0; f < 6; ++f)
    glTextureSubImage3D(tex, 0, 0, 0, f, cube_map.size, cube_map.size, 1, GL_RGBA, GL_FLOAT,
                        cube_map.faces[std::size_t(f)].data());
  glGenerateTextureMipmap(tex);
  ++probes_.at(handle).changes[buffer & 1];
}

gpu::TextureRef ProbeMaps::update_sphere(ProbeHandle handle, int buffer,
                                         const glm::mat3& view_rotation) {
  Probe& p = probes_.at(handle);
  if (!p.sphere) {
    p.sphere = gpu::make_texture(GL_TEXTURE_2D);
    glTextureStorage2D(p.sphere.id(), 1, GL_RGBA16F, p.resolution, p.resolution);
    glTextureParameteri(p.sphere.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(p.sphere.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(p.sphere.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(p.sphere.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  }
  glNamedFramebufferTexture(fbo_.id(), GL_COLOR_ATTACHMENT0, p.sphere.id(), 0);
  glNamedFramebufferRenderbuffer(fbo_.id(), GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, 0);  // no depth
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
  glViewport(0, 0, p.resolution, p.resolution);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glUseProgram(sphere_program_.id());
  const glm::mat3 view_to_world = glm::transpose(view_rotation);
  glProgramUniformMatrix3fv(sphere_program_.id(), 0, 1, GL_FALSE, &view_to_world[0][0]);
  glBindTextureUnit(0, p.cubes[buffer & 1].id());
  glBindVertexArray(empty_vao_.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  glEnable(GL_DEPTH_TEST);
  return p.sphere;
}

gpu::TextureRef ProbeMaps::existing_sphere(ProbeHandle handle) const {
  auto it = probes_.find(handle);
  return it == probes_.end() ? gpu::TextureRef() : gpu::TextureRef(it->second.sphere);
}

CubeMap ProbeMaps::read_cube(ProbeHandle handle, int buffer) const {
  CubeMap out;
  auto it = probes_.find(handle);
  if (it == probes_.end() || !it->second.cubes[buffer & 1]) return out;
  return read_cube_level(it->second.cubes[buffer & 1], 0);
}

SphereMap ProbeMaps::read_sphere(ProbeHandle handle) const {
  SphereMap out;
  auto it = probes_.find(handle);
  if (it == probes_.end() || !it->second.sphere) return out;
  const int n = it->second.resolution;
  std::vector<glm::vec4> gl(std::size_t(n) * n);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(it->second.sphere.id(), 0, GL_RGBA, GL_FLOAT,
                    GLsizei(gl.size() * sizeof(glm::vec4)), gl.data());
  out.size = n;
  out.texels.resize(gl.size());
  for (int y = 0; y < n; ++y)  // GL rows bottom up -> image rows top down
    std::memcpy(&out.texels[std::size_t(y) * n], &gl[std::size_t(n - 1 - y) * n],
                std::size_t(n) * sizeof(glm::vec4));
  return out;
}

}  // namespace kaskad::render
