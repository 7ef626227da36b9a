// The GPU copies of a scene's assets: meshes and material textures uploaded on first use and
// kept by id, and the reflection probes' maps by probe handle. One AssetStore's ids at a time:
// a frame of another store (another scene) starts the cache afresh.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <vector>

#include "components/mesh_renderer.h"
#include "runtime/assets/asset_store.h"
#include "runtime/result/result.h"
#include "runtime/gpu/gl_handles.h"
#include "runtime/render/probe_capture.h"
#include "runtime/features/shader_interface.h"

namespace kaskad::render {

/// Where one mesh lies in the cache's shared geometry. Every mesh's vertices (position, normal,
/// uv, tangent: one Vertex each) share one buffer and its 32-bit indices another, read through one
/// vertex array, so that draws of different meshes with the same program and material can be one
/// multi-draw (draw_batch()).
struct GpuMesh {
  GLsizei index_count = 0;
  GLuint first_index = 0;  ///< in the shared index buffer
  GLint base_vertex = 0;   ///< added to each of its indices
  bool uploaded = false;
};

/// A deformed mesh's inputs on the GPU (MeshDeform), read by the deform pass: joints and weights
/// (MeshDeform::influences a vertex) and morph displacements (kMorphDeltaFloats a vertex and
/// target, targets one after another).
struct GpuDeform {
  gpu::Buffer joints, weights, deltas;
};

/// Vertices (and indices) the shared geometry's buffers first hold; each growth doubles them.
inline constexpr std::size_t kGeometryFirstCapacity = 4096;

/// One draw of a batch: `count` instances of `mesh` (a copy: mesh() may move the cache's
/// records) from instance record `first_instance` on (upload()'s index plus the draw's first).
struct MeshDraw {
  GpuMesh mesh;
  std::uint32_t first_instance, count;
};

class GpuCache {
 public:
  /// Needs a current GL 4.5 context; `shader_dir` holds the probe maps' sphere-map shader.
  static Result<std::unique_ptr<GpuCache>> create(const std::filesystem::path& shader_dir);

  /// The frame's assets: another store than last frame's clears every mesh, texture and probe map
  /// (their ids and handles named that store's assets and entities).
  void use(const AssetStore& assets);

  /// Mesh `id` of the store given to use(), uploaded on first use. Precondition: a valid id.
  const GpuMesh& mesh(MeshId id);
  /// Draws `draws` (triangles, instanced) with the bound program and state: one
  /// glDrawElementsInstancedBaseVertexBaseInstance for one draw, else one
  /// glMultiDrawElementsIndirect whose commands go to the frame's indirect buffer.
  void draw_batch(std::span<const MeshDraw> draws);
  /// Material texture `id` (sRGB colour, or linear for a normal map), uploaded with mips on
  /// first use; a 1x1 white (or flat normal) texture for kNoTexture or an unknown id.
  gpu::TextureRef texture(TextureId id, bool is_normal_map);
  ProbeMaps& probes() { return *probes_; }
  /// The deform inputs of mesh `source`, uploaded on first use. Precondition: a valid id.
  const GpuDeform& deform(MeshId source);
  /// The positions of mesh `id` as its vertices in the shared buffer hold them now (empty when
  /// it was not uploaded); waits for the GPU.
  std::vector<glm::vec3> read_positions(MeshId id) const;
  /// The shared vertex buffer (every mesh's Vertex records; mesh() may replace it when it grows).
  GLuint vertex_buffer() const { return vertices_.id(); }

  /// Instance records for this frame's draws: begin_frame() starts the frame; upload() stores
  /// `records` after the ones stored earlier in the frame and returns the index of the first,
  /// the base instance of the draws that read them (the shared vertex array reads instanced
  /// attributes from this buffer).
  void begin_frame() { instances_used_ = commands_used_ = 0; }
  std::uint32_t upload(std::span<const InstanceRecord> records);

 private:
  GpuCache() = default;
  const AssetStore* assets_ = nullptr;
  std::uint64_t assets_uid_ = 0;
  void reserve_geometry(std::size_t vertices, std::size_t indices);

  std::vector<GpuMesh> meshes_;                        // indexed by MeshId
  std::vector<std::unique_ptr<GpuDeform>> deforms_;     // indexed by MeshId; null: not yet
  gpu::VertexArray vao_;  // every mesh's vertices and indices, and the instance records
  gpu::Buffer vertices_, indices_;
  std::size_t vertices_used_ = 0, vertices_capacity_ = 0;  // in Vertex
  std::size_t indices_used_ = 0, indices_capacity_ = 0;    // in indices
  // glMultiDrawElementsIndirect's command layout (GL 4.6 core, 10.4).
  struct IndirectCommand {
    GLuint count, instance_count, first_index;
    GLint base_vertex;
    GLuint base_instance;
  };
  gpu::Buffer commands_;  // the frame's multi-draw commands, from commands_used_ on free
  std::vector<IndirectCommand> commands_scratch_;  // draw_batch()'s, kept for its capacity
  std::size_t commands_used_ = 0, commands_capacity_ = 0;
  std::vector<std::unique_ptr<gpu::Texture>> textures_;  // indexed by TextureId
  gpu::Texture white_, flat_normal_;
  gpu::Buffer instances_;
  std::size_t instances_capacity_ = 0, instances_used_ = 0;  // in records
  std::unique_ptr<ProbeMaps> probes_;
};

}  // namespace kaskad::render
