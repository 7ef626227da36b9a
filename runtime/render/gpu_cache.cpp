#include "runtime/render/gpu_cache.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>

#include <glm/glm.hpp>

#include "runtime/assets/mesh_tangents.h"
#include "runtime/core/log.h"

namespace kaskad::render {
namespace {

// The vertex array's instanced attributes (InstanceRecord, divisor 1) read from binding 3.
// Vertex buffer bindings: 0-2 positions, normals and uvs, 3 the instance records, 4 tangents.
constexpr GLuint kInstanceBinding = 3;
constexpr GLuint kTangentBinding = 4;

void add_instance_attributes(GLuint vao, GLuint buffer) {
  for (GLuint i = 0; i < 4; ++i) {
    glEnableVertexArrayAttrib(vao, kAttrModel + i);
    glVertexArrayAttribFormat(vao, kAttrModel + i, 4, GL_FLOAT, GL_FALSE,
                              GLuint(offsetof(InstanceRecord, model) + 16 * i));
    glVertexArrayAttribBinding(vao, kAttrModel + i, kInstanceBinding);
  }
  for (GLuint i = 0; i < 3; ++i) {
    glEnableVertexArrayAttrib(vao, kAttrNormalMatrix + i);
    glVertexArrayAttribFormat(vao, kAttrNormalMatrix + i, 3, GL_FLOAT, GL_FALSE,
                              GLuint(offsetof(InstanceRecord, normal_matrix) + 16 * i));
    glVertexArrayAttribBinding(vao, kAttrNormalMatrix + i, kInstanceBinding);
  }
  glEnableVertexArrayAttrib(vao, kAttrLayer);
  glVertexArrayAttribIFormat(vao, kAttrLayer, 1, GL_UNSIGNED_INT,
                             GLuint(offsetof(InstanceRecord, layer)));
  glVertexArrayAttribBinding(vao, kAttrLayer, kInstanceBinding);
  glVertexArrayBindingDivisor(vao, kInstanceBinding, 1);
  if (buffer) glVertexArrayVertexBuffer(vao, kInstanceBinding, buffer, 0, sizeof(InstanceRecord));
}

// A 1x1 texture standing in for a missing material texture.
gpu::Texture make_solid_texture(const std::array<float, 4>& rgba, GLenum internal_format) {
  gpu::Texture t = gpu::make_texture(GL_TEXTURE_2D);
  glTextureStorage2D(t.id(), 1, internal_format, 1, 1);
  glTextureSubImage2D(t.id(), 0, 0, 0, 1, 1, GL_RGBA, GL_FLOAT, rgba.data());
  return t;
}

}  // namespace

Result<std::unique_ptr<GpuCache>> GpuCache::create(const std::filesystem::path& shader_dir) {
  std::unique_ptr<GpuCache> c(new GpuCache());
  auto probes = ProbeMaps::create(shader_dir);
  if (!probes) return probes.error();
  c->probes_ = std::move(probes.value());
  c->white_ = make_solid_texture({1, 1, 1, 1}, GL_SRGB8_ALPHA8);
  // Exactly (0.5, 0.5, 1): decodes to (0, 0, 1), so the cotangent frame leaves the normal as is.
  // An 8-bit 128 would tilt every normal by 0.2 degrees, with visible derivative noise.
  c->flat_normal_ = make_solid_texture({0.5f, 0.5f, 1, 1}, GL_RGBA16F);
  return c;
}

void GpuCache::use(const AssetStore& assets) {
  assets_ = &assets;
  if (assets.uid == assets_uid_) return;
  meshes_.clear();
  textures_.clear();
  probes_->clear();
  assets_uid_ = assets.uid;
}

const GpuMesh& GpuCache::mesh(MeshId id) {
  const std::size_t at = index(id);
  KASKAD_CHECK(assets_ && at < assets_->meshes.size(), "mesh id out of range");
  if (at >= meshes_.size()) meshes_.resize(at + 1);
  GpuMesh& m = meshes_[at];
  if (m.vao) return m;
  const MeshData& src = assets_->meshes[at];
  const std::size_t n = src.positions.size();
  // One buffer, four streams: positions | normals | uvs | tangents (uvs zero when the mesh has
  // none; tangents the mesh's own, else generated (MikkTSpace's rule), zero without uvs).
  const std::size_t pos_bytes = n * sizeof(glm::vec3), uv_bytes = n * sizeof(glm::vec2),
                    tangent_bytes = n * sizeof(glm::vec4);
  std::vector<std::uint8_t> data(2 * pos_bytes + uv_bytes + tangent_bytes, 0);
  std::memcpy(data.data(), src.positions.data(), pos_bytes);
  if (src.normals.size() == n) std::memcpy(data.data() + pos_bytes, src.normals.data(), pos_bytes);
  if (src.uvs.size() == n) std::memcpy(data.data() + 2 * pos_bytes, src.uvs.data(), uv_bytes);
  const std::vector<glm::vec4> generated = src.tangents.size() == n ? std::vector<glm::vec4>()
                                                                      : generate_tangents(src);
  const std::vector<glm::vec4>& tangents = generated.empty() ? src.tangents : generated;
  if (tangents.size() == n)
    std::memcpy(data.data() + 2 * pos_bytes + uv_bytes, tangents.data(), tangent_bytes);
  m.vertices = gpu::make_buffer();
  glNamedBufferStorage(m.vertices.id(), GLsizeiptr(std::max<std::size_t>(data.size(), 1)),
                       data.data(), 0);
  m.indices = gpu::make_buffer();
  glNamedBufferStorage(m.indices.id(), GLsizeiptr(std::max<std::size_t>(src.indices.size() * 4, 4)),
                       src.indices.empty() ? nullptr : src.indices.data(), 0);
  m.index_count = GLsizei(src.indices.size());
  m.vao = gpu::make_vertex_array();
  const GLuint vao = m.vao.id();
  glVertexArrayVertexBuffer(vao, 0, m.vertices.id(), 0, sizeof(glm::vec3));
  glVertexArrayVertexBuffer(vao, 1, m.vertices.id(), GLintptr(pos_bytes), sizeof(glm::vec3));
  glVertexArrayVertexBuffer(vao, 2, m.vertices.id(), GLintptr(2 * pos_bytes), sizeof(glm::vec2));
  glVertexArrayVertexBuffer(vao, kTangentBinding, m.vertices.id(),
                            GLintptr(2 * pos_bytes + uv_bytes), sizeof(glm::vec4));
  const GLuint attrs[4] = {kAttrPosition, kAttrNormal, kAttrUv, kAttrTangent};
  const GLuint bindings[4] = {0, 1, 2, kTangentBinding};
  const GLint sizes[4] = {3, 3, 2, 4};
  for (int i = 0; i < 4; ++i) {
    glEnableVertexArrayAttrib(vao, attrs[i]);
    glVertexArrayAttribFormat(vao, attrs[i], sizes[i], GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(vao, attrs[i], bindings[i]);
  }
  glVertexArrayElementBuffer(vao, m.indices.id());
  add_instance_attributes(vao, instances_ ? instances_.id() : 0);
  return m;
}

std::uint32_t GpuCache::upload(std::span<const InstanceRecord> records) {
  const std::size_t first = instances_used_;
  if (first + records.size() > instances_capacity_) {
    // A larger buffer; draws already recorded this frame keep reading the old one (GL holds it
    // until they are done), so the new one is filled from the same index on.
    instances_capacity_ = std::max<std::size_t>({1024, 2 * instances_capacity_, first + records.size()});
    instances_ = gpu::make_buffer();
    glNamedBufferStorage(instances_.id(), GLsizeiptr(instances_capacity_ * sizeof(InstanceRecord)),
                         nullptr, GL_DYNAMIC_STORAGE_BIT);
    for (GpuMesh& m : meshes_)
      if (m.vao)
        glVertexArrayVertexBuffer(m.vao.id(), kInstanceBinding, instances_.id(), 0,
                                  sizeof(InstanceRecord));
  }
  if (!records.empty())
    glNamedBufferSubData(instances_.id(), GLintptr(first * sizeof(InstanceRecord)),
                         GLsizeiptr(records.size() * sizeof(InstanceRecord)), records.data());
  instances_used_ = first + records.size();
  return std::uint32_t(first);
}

gpu::TextureRef GpuCache::texture(TextureId id, bool is_normal_map) {
  const std::size_t at = index(id);
  if (!assets_ || id == kNoTexture || at >= assets_->textures.size())
    return is_normal_map ? flat_normal_ : white_;
  if (at >= textures_.size()) textures_.resize(at + 1);
  if (!textures_[at]) {
    const TextureData& src = assets_->textures[at];
    auto t = std::make_unique<gpu::Texture>(gpu::make_texture(GL_TEXTURE_2D));
    const GLuint tex = t->id();
    const int levels = 1 + int(std::floor(std::log2(std::max(1, std::max(src.width, src.height)))));
    // Colour data is sRGB-encoded; normal maps are linear. Normal maps reuse the same cache slot
    // as long as a texture is used in one role only (glTF practice).
    const GLenum fmt = (src.srgb && !is_normal_map) ? GL_SRGB8_ALPHA8 : GL_RGBA8;
    glTextureStorage2D(tex, levels, fmt, std::max(1, src.width), std::max(1, src.height));
    if (src.width > 0 && src.height > 0 &&
        src.rgba8.size() == std::size_t(src.width) * src.height * 4) {
      glTextureSubImage2D(tex, 0, 0, 0, src.width, src.height, GL_RGBA, GL_UNSIGNED_BYTE,
                          src.rgba8.data());
    }
    glGenerateTextureMipmap(tex);
    glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(tex, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTextureParameteri(tex, GL_TEXTURE_WRAP_T, GL_REPEAT);
    textures_[at] = std::move(t);
  }
  return *textures_[at];
}

}  // namespace kaskad::render
