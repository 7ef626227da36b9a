#include "runtime/render/gpu_cache.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

#include "runtime/assets/mesh_tangents.h"
#include "runtime/core/log.h"

namespace kaskad::render {
namespace {

// The vertex array's buffer bindings: 0 the shared vertices, 1 the instance records
// (InstanceRecord, divisor 1).
constexpr GLuint kVertexBinding = 0;
constexpr GLuint kInstanceBinding = 1;


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

// Stores `count` elements of `element` bytes from `data` at element `first` of a buffer the frame
// fills from its start on, replacing the buffer by a larger one (at least `min_capacity`) first
// when they do not fit: draws already recorded this frame keep reading the old one (GL holds it
// until they are done), so the new one is filled from the same index on. Returns whether the
// buffer was replaced.
bool store_in_frame_buffer(gpu::Buffer& buffer, std::size_t& capacity, std::size_t first,
                           std::size_t count, std::size_t element, std::size_t min_capacity,
                           const void* data) {
  const bool replaced = first + count > capacity;
  if (replaced) {
    capacity = std::max<std::size_t>({min_capacity, 2 * capacity, first + count});
    buffer = gpu::make_buffer();
    glNamedBufferStorage(buffer.id(), GLsizeiptr(capacity * element), nullptr,
                         GL_DYNAMIC_STORAGE_BIT);
  }
  if (count > 0)
    glNamedBufferSubData(buffer.id(), GLintptr(first * element), GLsizeiptr(count * element), data);
  return replaced;
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
  deforms_.clear();
  vertices_used_ = indices_used_ = 0;  // the buffers stay, for the next store's meshes
  textures_.clear();
  probes_->clear();
  assets_uid_ = assets.uid;
}

void GpuCache::reserve_geometry(std::size_t vertices, std::size_t indices) {
  if (!vao_) {
    vao_ = gpu::make_vertex_array();
    const GLuint vao = vao_.id();
    const GLuint attrs[5] = {kAttrPosition, kAttrNormal, kAttrUv, kAttrTangent, kAttrUv1};
    const GLuint offsets[5] = {offsetof(Vertex, position), offsetof(Vertex, normal),
                               offsetof(Vertex, uv), offsetof(Vertex, tangent),
                               offsetof(Vertex, uv1)};
    const GLint sizes[5] = {3, 3, 2, 4, 2};
    for (int i = 0; i < 5; ++i) {
      glEnableVertexArrayAttrib(vao, attrs[i]);
      glVertexArrayAttribFormat(vao, attrs[i], sizes[i], GL_FLOAT, GL_FALSE, offsets[i]);
      glVertexArrayAttribBinding(vao, attrs[i], kVertexBinding);
    }
    add_instance_attributes(vao, instances_ ? instances_.id() : 0);
  }
  // A full buffer is replaced by one twice as large holding a copy (draws recorded earlier keep
  // reading the old one, which GL holds until they are done).
  auto grow = [](gpu::Buffer& buffer, std::size_t& capacity, std::size_t used, std::size_t need,
                 std::size_t element) {
    if (need <= capacity) return false;
    const std::size_t grown = std::max<std::size_t>({kGeometryFirstCapacity, 2 * capacity, need});
    gpu::Buffer bigger = gpu::make_buffer();
    glNamedBufferStorage(bigger.id(), GLsizeiptr(grown * element), nullptr, GL_DYNAMIC_STORAGE_BIT);
    if (used > 0)
      glCopyNamedBufferSubData(buffer.id(), bigger.id(), 0, 0, GLsizeiptr(used * element));
    buffer = std::move(bigger);
    capacity = grown;
    return true;
  };
  if (grow(vertices_, vertices_capacity_, vertices_used_, vertices, sizeof(Vertex)))
    glVertexArrayVertexBuffer(vao_.id(), kVertexBinding, vertices_.id(), 0, sizeof(Vertex));
  if (grow(indices_, indices_capacity_, indices_used_, indices, sizeof(std::uint32_t)))
    glVertexArrayElementBuffer(vao_.id(), indices_.id());
}

const GpuMesh& GpuCache::mesh(MeshId id) {
  const std::size_t at = index(id);
  KASKAD_CHECK(assets_ && at < assets_->meshes.size(), "mesh id out of range");
  if (at >= meshes_.size()) meshes_.resize(at + 1);
  GpuMesh& m = meshes_[at];
  if (m.uploaded) return m;
  const MeshData& src = assets_->meshes[at];
  const std::size_t n = src.positions.size();
  // Uvs are zero when the mesh has none (uv1: uv_set(1)'s rule); tangents are the mesh's own, else generated
  // (MikkTSpace's rule), zero without uvs.
  const std::vector<glm::vec4> generated = src.tangents.size() == n ? std::vector<glm::vec4>()
                                                                      : generate_tangents(src);
  const std::vector<glm::vec4>& tangents = generated.empty() ? src.tangents : generated;
  std::vector<Vertex> vertices(n);
  for (std::size_t i = 0; i < n; ++i) {
    vertices[i].position = src.positions[i];
    if (src.normals.size() == n) vertices[i].normal = src.normals[i];
    if (src.uvs.size() == n) vertices[i].uv = src.uvs[i];
    if (src.uv_set(1).size() == n) vertices[i].uv1 = src.uv_set(1)[i];
    if (tangents.size() == n) vertices[i].tangent = tangents[i];
  }
  // The draws' base vertex is a GLint, their first index a GLuint.
  KASKAD_CHECK(vertices_used_ + n <= std::size_t(INT32_MAX) &&
                   indices_used_ + src.indices.size() <= std::size_t(UINT32_MAX),
               "the scene's meshes hold more vertices or indices than one buffer can address");
  reserve_geometry(vertices_used_ + n, indices_used_ + src.indices.size());
  if (n > 0)
    glNamedBufferSubData(vertices_.id(), GLintptr(vertices_used_ * sizeof(Vertex)),
                         GLsizeiptr(n * sizeof(Vertex)), vertices.data());
  if (!src.indices.empty())
    glNamedBufferSubData(indices_.id(), GLintptr(indices_used_ * sizeof(std::uint32_t)),
                         GLsizeiptr(src.indices.size() * sizeof(std::uint32_t)),
                         src.indices.data());
  m.index_count = GLsizei(src.indices.size());
  m.first_index = GLuint(indices_used_);
  m.base_vertex = GLint(vertices_used_);
  m.uploaded = true;
  vertices_used_ += n;
  indices_used_ += src.indices.size();
  return m;
}

std::vector<glm::vec3> GpuCache::read_positions(MeshId id) const {
  const std::size_t at = index(id);
  if (at >= meshes_.size() || !meshes_[at].uploaded) return {};
  const std::size_t n = assets_->meshes[at].positions.size();
  std::vector<Vertex> vertices(n);
  glGetNamedBufferSubData(vertices_.id(), GLintptr(std::size_t(meshes_[at].base_vertex) * sizeof(Vertex)),
                          GLsizeiptr(n * sizeof(Vertex)), vertices.data());
  std::vector<glm::vec3> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = vertices[i].position;
  return out;
}

const GpuDeform& GpuCache::deform(MeshId source) {
  const std::size_t at = index(source);
  KASKAD_CHECK(assets_ && at < assets_->meshes.size(), "mesh id out of range");
  if (at >= deforms_.size()) deforms_.resize(at + 1);
  std::unique_ptr<GpuDeform>& slot = deforms_[at];
  if (slot) return *slot;
  const MeshDeform& d = assets_->meshes[at].deform;
  const std::size_t n = assets_->meshes[at].positions.size();
  auto upload = [](gpu::Buffer& buffer, const void* data, std::size_t bytes) {
    buffer = gpu::make_buffer();
    // Storage of at least a vec4: a mesh without skin or targets still binds something.
    glNamedBufferStorage(buffer.id(), GLsizeiptr(std::max<std::size_t>(bytes, 16)),
                         bytes > 0 ? data : nullptr, GL_DYNAMIC_STORAGE_BIT);
    if (bytes == 0) {
      const float zero[4] = {0, 0, 0, 0};
      glNamedBufferSubData(buffer.id(), 0, sizeof zero, zero);
    }
  };
  slot = std::make_unique<GpuDeform>();
  upload(slot->joints, d.joints.data(), d.joints.size() * sizeof(std::uint32_t));
  upload(slot->weights, d.weights.data(), d.weights.size() * sizeof(float));
  // Target k's vertex v: position, normal and tangent displacements at (k n + v) * 9 floats.
  std::vector<float> deltas(d.targets.size() * n * kMorphDeltaFloats, 0.0f);
  for (std::size_t k = 0; k < d.targets.size(); ++k)
    for (std::size_t v = 0; v < n; ++v) {
      float* out = &deltas[(k * n + v) * kMorphDeltaFloats];
      const MeshDeform::Target& t = d.targets[k];
      for (int c = 0; c < 3; ++c) {
        out[c] = t.positions[v][c];
        out[3 + c] = t.normals[v][c];
        out[6 + c] = t.tangents.empty() ? 0.0f : t.tangents[v][c];
      }
    }
  upload(slot->deltas, deltas.data(), deltas.size() * sizeof(float));
  return *slot;
}

void GpuCache::draw_batch(std::span<const MeshDraw> draws) {
  if (draws.empty()) return;
  glBindVertexArray(vao_.id());
  if (draws.size() == 1) {
    const MeshDraw& d = draws[0];
    glDrawElementsInstancedBaseVertexBaseInstance(
        GL_TRIANGLES, d.mesh.index_count, GL_UNSIGNED_INT,
        reinterpret_cast<const void*>(std::uintptr_t(d.mesh.first_index) * sizeof(std::uint32_t)),
        GLsizei(d.count), d.mesh.base_vertex, d.first_instance);
    return;
  }
  std::vector<IndirectCommand>& commands = commands_scratch_;
  commands.clear();
  for (const MeshDraw& d : draws)
    commands.push_back({GLuint(d.mesh.index_count), d.count, d.mesh.first_index, d.mesh.base_vertex,
                        d.first_instance});
  const std::size_t first = commands_used_;
  store_in_frame_buffer(commands_, commands_capacity_, first, commands.size(),
                        sizeof(IndirectCommand), 256, commands.data());
  commands_used_ = first + commands.size();
  glBindBuffer(GL_DRAW_INDIRECT_BUFFER, commands_.id());
  glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT,
                              reinterpret_cast<const void*>(first * sizeof(IndirectCommand)),
                              GLsizei(commands.size()), 0);
  glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
}

std::uint32_t GpuCache::upload(std::span<const InstanceRecord> records) {
  const std::size_t first = instances_used_;
  if (store_in_frame_buffer(instances_, instances_capacity_, first, records.size(),
                            sizeof(InstanceRecord), 1024, records.data()) &&
      vao_)
    glVertexArrayVertexBuffer(vao_.id(), kInstanceBinding, instances_.id(), 0,
                              sizeof(InstanceRecord));
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
