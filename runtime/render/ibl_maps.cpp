#include "runtime/render/ibl_maps.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <bit>
#include <cstring>

#include "components/ibl.h"
#include "runtime/gpu/shader.h"
#include "runtime/render/gpu_timers.h"
#include "runtime/features/shader_interface.h"

namespace kaskad::render {

int cube_mip_levels(int size) { return std::bit_width(unsigned(std::max(1, size))); }

void set_cube_sampling(const gpu::Texture& cube) {
  const GLuint t = cube.id();
  glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTextureParameteri(t, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
}

CubeMap read_cube_level(const gpu::Texture& cube, int level) {
  CubeMap out;
  GLint n = 0;
  glGetTextureLevelParameteriv(cube.id(), level, GL_TEXTURE_WIDTH, &n);
  out.size = n;
  const std::size_t face = std::size_t(n) * std::size_t(n);
  std::vector<glm::vec4> all(face * 6);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(cube.id(), level, GL_RGBA, GL_FLOAT, GLsizei(all.size() * sizeof(glm::vec4)),
                    all.data());
  for (std::size_t f = 0; f < 6; ++f)
    out.faces[f].assign(all.begin() + std::ptrdiff_t(f * face),
                        all.begin() + std::ptrdiff_t((f + 1) * face));
  return out;
}

Result<gpu::Program> fullscreen_program(const std::filesystem::path& shader_dir,
                                        const char* fragment) {
  auto vs = gpu::preprocess_shader(shader_dir, "fullscreen.vert", {});
  if (!vs) return vs.error();
  auto fs = gpu::preprocess_shader(shader_dir, fragment, {});
  if (!fs) return fs.error();
  return gpu::build_program(*vs, *fs);
}

Result<std::unique_ptr<IblMaps>> IblMaps::create(const std::filesystem::path& shader_dir) {
  std::unique_ptr<IblMaps> m(new IblMaps());
  auto prefilter = fullscreen_program(shader_dir, "ibl_prefilter.frag");
  if (!prefilter) return prefilter.error();
  m->prefilter_program_ = std::move(prefilter.value());
  auto sh = fullscreen_program(shader_dir, "sh_project.frag");
  if (!sh) return sh.error();
  m->sh_program_ = std::move(sh.value());
  m->empty_vao_ = gpu::make_vertex_array();
  m->fbo_ = gpu::make_framebuffer();
  // The split-sum table, computed once per process (components/ibl.h).
  m->dfg_ = gpu::make_texture(GL_TEXTURE_2D);
  glTextureStorage2D(m->dfg_.id(), 1, GL_RG32F, kDfgTableSize, kDfgTableSize);
  glTextureSubImage2D(m->dfg_.id(), 0, 0, 0, kDfgTableSize, kDfgTableSize, GL_RG, GL_FLOAT,
                      dfg_table().data());
  glTextureParameteri(m->dfg_.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(m->dfg_.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(m->dfg_.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(m->dfg_.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  m->black_cube_ = gpu::make_texture(GL_TEXTURE_CUBE_MAP);
  glTextureStorage2D(m->black_cube_.id(), 1, GL_RGBA16F, 1, 1);
  const float black[4] = {0, 0, 0, 1};
  glClearTexImage(m->black_cube_.id(), 0, GL_RGBA, GL_FLOAT, black);
  m->row_used_ = {true};  // row 0: the environment
  m->ensure_rows(4);
  return m;
}

void IblMaps::ensure_rows(int rows) {
  if (rows <= sh_rows_) return;
  const int grown = std::max(rows, 2 * sh_rows_);
  gpu::Texture t = gpu::make_texture(GL_TEXTURE_2D);
  glTextureStorage2D(t.id(), 1, GL_RGBA32F, 9, grown);
  const float zero[4] = {0, 0, 0, 0};
  glClearTexImage(t.id(), 0, GL_RGBA, GL_FLOAT, zero);
  glTextureParameteri(t.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(t.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  if (sh_) glCopyImageSubData(sh_.id(), GL_TEXTURE_2D, 0, 0, 0, 0, t.id(), GL_TEXTURE_2D, 0, 0, 0, 0, 9, sh_rows_, 1);
  sh_ = std::move(t);
  sh_rows_ = grown;
}

int IblMaps::acquire_row() {
  for (std::size_t r = 1; r < row_used_.size(); ++r)
    if (!row_used_[r]) {
      row_used_[r] = true;
      return int(r);
    }
  row_used_.push_back(true);
  ensure_rows(int(row_used_.size()));
  return int(row_used_.size()) - 1;
}

void IblMaps::release_row(int row) {
  if (row > 0 && std::size_t(row) < row_used_.size()) row_used_[std::size_t(row)] = false;
}

void IblMaps::begin_fullscreen(const gpu::Texture& source) {
  if (timers_) timers_->begin(TimedPart::probe_prefilter);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glDisable(GL_FRAMEBUFFER_SRGB);
  glBindVertexArray(empty_vao_.id());
  glBindTextureUnit(0, source.id());
  glNamedFramebufferRenderbuffer(fbo_.id(), GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, 0);
  glNamedFramebufferDrawBuffer(fbo_.id(), GL_COLOR_ATTACHMENT0);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
}

void IblMaps::end_fullscreen() {
  glNamedFramebufferTexture(fbo_.id(), GL_COLOR_ATTACHMENT0, 0, 0);
  glBindVertexArray(0);
  glEnable(GL_DEPTH_TEST);
  if (timers_) timers_->end(TimedPart::probe_prefilter);
}

void IblMaps::prefilter(const gpu::Texture& source, int size, gpu::Texture& target, int row) {
  prefilter_faces(source, size, target, 0, 6);
  project_sh(source, size, row);
}

void IblMaps::prefilter_faces(const gpu::Texture& source, int size, gpu::Texture& target,
                              int first, int count) {
  const int levels = ibl_specular_levels(size);
  GLint have = 0, levels_have = 0;
  if (target) {
    glGetTextureLevelParameteriv(target.id(), 0, GL_TEXTURE_WIDTH, &have);
    glGetTextureParameteriv(target.id(), GL_TEXTURE_IMMUTABLE_LEVELS, &levels_have);
  }
  if (!target || have != size || levels_have != levels) {
    target = gpu::make_texture(GL_TEXTURE_CUBE_MAP);
    glTextureStorage2D(target.id(), levels, GL_RGBA16F, size, size);
    set_cube_sampling(target);
  }
  first = std::clamp(first, 0, 6);
  count = std::clamp(count, 0, 6 - first);
  if (count == 0) return;
  // Level 0 is roughness 0: the mirror, the source as it is.
  glCopyImageSubData(source.id(), GL_TEXTURE_CUBE_MAP, 0, 0, 0, first, target.id(),
                     GL_TEXTURE_CUBE_MAP, 0, 0, 0, first, size, size, count);
  begin_fullscreen(source);
  glUseProgram(prefilter_program_.id());
  for (int level = 1; level < levels; ++level) {
    const int s = std::max(1, size >> level);
    glViewport(0, 0, s, s);
    glProgramUniform4f(prefilter_program_.id(), 1, float(level) / float(levels - 1), float(size),
                       float(prefilter_samples(level)), 0.0f);
    for (int face = first; face < first + count; ++face) {
      glNamedFramebufferTextureLayer(fbo_.id(), GL_COLOR_ATTACHMENT0, target.id(), level, face);
      glProgramUniform4i(prefilter_program_.id(), 0, face, 0, 0, 0);
      glDrawArrays(GL_TRIANGLES, 0, 3);
    }
  }
  end_fullscreen();
}

void IblMaps::project_sh(const gpu::Texture& source, int size, int row) {
  // SH from a level of at most 16 x 16 texels a face (a box-filtered mip: SH are smooth).
  ensure_rows(row + 1);
  begin_fullscreen(source);
  const int sh_level = std::max(0, cube_mip_levels(size) - 5);
  glNamedFramebufferTexture(fbo_.id(), GL_COLOR_ATTACHMENT0, sh_.id(), 0);
  glViewport(0, row, 9, 1);
  glUseProgram(sh_program_.id());
  glProgramUniform4f(sh_program_.id(), 1, float(sh_level), float(std::max(1, size >> sh_level)), 0, 0);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  end_fullscreen();
}

void IblMaps::set_environment(const CubeMap* cube, std::uint64_t key) {
  if (!cube || cube->size <= 0) {
    environment_specular_ = gpu::Texture();
    environment_levels_ = 0;
    environment_key_ = 0;
    return;
  }
  if (key == environment_key_ && environment_specular_) return;
  environment_key_ = key;
  const int n = cube->size;
  // The map itself is needed only to prefilter it (level 0 of the result is a copy of it).
  const gpu::Texture source = gpu::make_texture(GL_TEXTURE_CUBE_MAP);
  glTextureStorage2D(source.id(), cube_mip_levels(n), GL_RGBA16F, n, n);
  set_cube_sampling(source);
  for (int f = 0; f < 6; ++f)
    glTextureSubImage3D(source.id(), 0, 0, 0, f, n, n, 1, GL_RGBA, GL_FLOAT,
                        cube->faces[std::size_t(f)].data());
  glGenerateTextureMipmap(source.id());
  prefilter(source, n, environment_specular_, 0);
  environment_levels_ = ibl_specular_levels(n);
}

void IblMaps::bind() const {
  glBindTextureUnit(kTexDfg, dfg_.id());
  glBindTextureUnit(kTexSh, sh_.id());
  glBindTextureUnit(kTexEnvironment,
                    environment_specular_ ? environment_specular_.id() : black_cube_.id());
}

std::vector<glm::vec3> IblMaps::read_sh_row(int row) const {
  std::vector<glm::vec3> out;
  if (row < 0 || row >= sh_rows_) return out;
  std::vector<glm::vec4> texels(9);
  glGetTextureSubImage(sh_.id(), 0, 0, row, 0, 9, 1, 1, GL_RGBA, GL_FLOAT,
                       GLsizei(texels.size() * sizeof(glm::vec4)), texels.data());
  for (const glm::vec4& t : texels) out.emplace_back(t);
  return out;
}

CubeMap IblMaps::read_environment_level(int level) const {
  if (!environment_specular_ || level < 0 || level >= environment_levels_) return {};
  return read_cube_level(environment_specular_, level);
}

}  // namespace kaskad::render
