// Posing a deformed mesh on the CPU: morph targets, then skinning (glTF 2.0, 3.7.2.2 and 3.7.3).
// The deform pass (content/shaders/deform.comp) computes the same per vertex on the GPU; the
// CPU form serves the ray-traced references, conservative bounds and the tests that compare the
// two. The one definition of a pose, shared by both:
//   morph:  p = p0 + sum_k w_k dp_k, n = n0 + sum_k w_k dn_k, t = t0 + sum_k w_k dt_k;
//   skin:   M = sum_i weight_i S[joint_i], S[j] = world(joint j) * inverse_bind[j];
//           p' = M p, n' = normalize(cofactor(M) n), t' = normalize(M t) (t.w kept);
//   without a skin: p' = p, n' and t' normalised (a zero vector stays zero).
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/assets/asset_store.h"

namespace kaskad {

/// The skin matrices S[j] of a pose: each joint's world matrix times its inverse bind matrix.
std::vector<glm::mat4> skin_matrices(std::span<const glm::mat4> joint_world,
                                     const SkinData& skin);

/// `base` posed: positions, normals and tangents of `out` replaced (resized to base's); its
/// other streams are left as they are (a posed copy of base already holds base's indices and
/// uvs). `weights`: morph weights, one per target (missing
/// ones are 0); `skin`: S[] of skin_matrices(), empty when the mesh is not skinned.
void pose_mesh(const MeshData& base, std::span<const float> weights,
               std::span<const glm::mat4> skin, MeshData& out);

/// Per joint, the box of the vertices it moves (weight > 0), in the joint's bind space
/// (inverse_bind[j] * p); empty for a joint that moves none.
std::vector<Aabb> joint_boxes(const MeshData& mesh, const SkinData& skin);

/// A box that holds every posed vertex (conservative, never cut): skinned, the union of each
/// joint's box, grown by the largest morph displacement, through world(joint) (world space);
/// morph-only, the mesh's bounds grown by each weighted target's displacement box (mesh space).
Aabb pose_bounds(const MeshData& base, std::span<const float> weights,
                 std::span<const glm::mat4> joint_world, const SkinData* skin,
                 std::span<const Aabb> boxes);

}  // namespace kaskad
