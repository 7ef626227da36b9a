// Tangent frames for normal mapping when a mesh has none (glTF 3.7.2.1: "When tangents are not
// specified, client implementations SHOULD calculate tangents using default MikkTSpace
// algorithms with the specified vertex positions, normals, and texture coordinates").
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "runtime/assets/asset_store.h"

namespace kaskad {

/// Per vertex: xyz the unit tangent (the direction of increasing u, in the plane of the vertex
/// normal), w the bitangent sign (the bitangent, along increasing v, is w * cross(normal,
/// tangent)), as glTF's TANGENT attribute. MikkTSpace's per-vertex rule: each triangle corner
/// adds its face's tangent and bitangent (from the uv gradients), projected onto the plane of
/// that vertex's normal, normalised and weighted by the corner's angle; the sum is projected and
/// normalised again, and w is the sign of the accumulated bitangent against cross(n, t).
/// MikkTSpace's splitting of vertices shared by triangles of opposite uv winding (mirrored
/// seams) is not done: such a vertex gets the blended frame. Triangles with degenerate uvs add
/// nothing; a vertex without any gets a tangent perpendicular to its normal and w = 1. Empty
/// when the mesh has no uvs or normals for every vertex.
std::vector<glm::vec4> generate_tangents(const MeshData& mesh);

}  // namespace kaskad
