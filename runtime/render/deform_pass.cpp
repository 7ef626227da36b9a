#include "runtime/render/deform_pass.h"

#include <epoxy/gl.h>

#include <algorithm>

#include "runtime/render/draw_list.h"

namespace kaskad::render {
namespace {

constexpr GLuint kGroupSize = 64;  // deform.comp's local_size_x

/// Copies `bytes` into `buffer`, replacing it with a larger one when it does not fit.
void upload(gpu::Buffer& buffer, std::size_t& capacity, const void* data, std::size_t bytes) {
  if (bytes > capacity || !buffer) {
    capacity = std::max<std::size_t>({bytes, 2 * capacity, 256});
    buffer = gpu::make_buffer();
    glNamedBufferStorage(buffer.id(), GLsizeiptr(capacity), nullptr, GL_DYNAMIC_STORAGE_BIT);
  }
  if (bytes > 0) glNamedBufferSubData(buffer.id(), 0, GLsizeiptr(bytes), data);
}

}  // namespace

Status DeformPass::record(const FrameInput& frame, std::uint64_t assets_uid, GpuCache& cache,
                          ShaderLibrary& shaders, FrameStats& stats) {
  stats.deformed_meshes = 0;
  if (assets_uid != assets_uid_) {  // another store: its posed meshes are new to the cache
    posed_with_.clear();
    assets_uid_ = assets_uid;
  }
  if (frame.deforms.empty()) return {};
  // Every mesh in the cache first: an upload may replace the shared vertex buffer.
  for (const DeformJob& job : frame.deforms) {
    cache.mesh(job.source);
    cache.mesh(job.posed);
    cache.deform(job.source);
  }
  upload(matrices_, matrices_capacity_, frame.skin_matrices.data(),
         frame.skin_matrices.size() * sizeof(glm::mat4));
  upload(weights_, weights_capacity_, frame.morph_weights.data(),
         frame.morph_weights.size() * sizeof(float));
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kBufVertices, cache.vertex_buffer());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kBufSkinMatrices, matrices_.id());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kBufMorphWeights, weights_.id());
  GLuint bound = 0;
  for (std::size_t i = 0; i < frame.deforms.size(); ++i) {
    const DeformJob& job = frame.deforms[i];
    std::uint64_t& last = posed_with_[std::uint32_t(index(job.posed))];
    if (last == job.pose && job.pose != 0) continue;
    auto program = shaders.program(Pass::deform, deform_variant(job));
    if (!program) return program.error();
    if (program->id() != bound) glUseProgram(bound = program->id());
    const GpuMesh& source = cache.mesh(job.source);
    const GpuMesh& posed = cache.mesh(job.posed);
    const GpuDeform& inputs = cache.deform(job.source);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kBufJoints, inputs.joints.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kBufJointWeights, inputs.weights.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kBufMorphDeltas, inputs.deltas.id());
    const GLint count = GLint(job.vertex_count);
    glUniform4i(kLocDeformJob, source.base_vertex, posed.base_vertex, count, GLint(job.first_matrix));
    glUniform4i(kLocDeformMorph, GLint(job.first_weight), GLint(job.weight_count), 0, 0);
    glDispatchCompute((GLuint(count) + kGroupSize - 1) / kGroupSize, 1, 1);
    last = job.pose;
    ++stats.deformed_meshes;
  }
  // The passes after read the posed vertices as vertex attributes.
  glMemoryBarrier(GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  return {};
}

}  // namespace kaskad::render
