#include "runtime/assets/mesh_pose.h"

#include <cmath>

namespace kaskad {
namespace {

glm::vec3 normalized_or_zero(const glm::vec3& v) {
  const float len2 = glm::dot(v, v);
  return len2 > 0.0f ? v * (1.0f / std::sqrt(len2)) : v;
}

/// cofactor(m): transforms normals as the inverse transpose does, up to a positive scale (and
/// defined for singular m).
glm::mat3 cofactor(const glm::mat3& m) {
  return glm::mat3(glm::cross(m[1], m[2]), glm::cross(m[2], m[0]), glm::cross(m[0], m[1]));
}

float weight_of(std::span<const float> weights, std::size_t k) {
  return k < weights.size() ? weights[k] : 0.0f;
}

}  // namespace

std::vector<glm::mat4> skin_matrices(std::span<const glm::mat4> joint_world,
                                     const SkinData& skin) {
  std::vector<glm::mat4> s(skin.inverse_bind.size(), glm::mat4(1.0f));
  for (std::size_t j = 0; j < s.size() && j < joint_world.size(); ++j)
    s[j] = joint_world[j] * skin.inverse_bind[j];
  return s;
}

void pose_mesh(const MeshData& base, std::span<const float> weights,
               std::span<const glm::mat4> skin, MeshData& out) {
  const std::size_t n = base.positions.size();
  out.positions.resize(n);
  out.normals.resize(base.normals.size());
  out.tangents.resize(base.tangents.size());
  const MeshDeform& d = base.deform;
  const std::size_t influences = std::size_t(d.influences);
  for (std::size_t v = 0; v < n; ++v) {
    glm::vec3 p = base.positions[v];
    glm::vec3 nrm = v < base.normals.size() ? base.normals[v] : glm::vec3(0.0f);
    glm::vec3 tan = v < base.tangents.size() ? glm::vec3(base.tangents[v]) : glm::vec3(0.0f);
    for (std::size_t k = 0; k < d.targets.size(); ++k) {
      const float w = weight_of(weights, k);
      if (w == 0.0f) continue;
      const MeshDeform::Target& t = d.targets[k];
      p += w * t.positions[v];
      nrm += w * t.normals[v];
      if (!t.tangents.empty()) tan += w * t.tangents[v];
    }
    if (d.skinned() && !skin.empty()) {
      glm::mat4 m(0.0f);
      for (std::size_t i = 0; i < influences; ++i) {
        const float w = d.weights[v * influences + i];
        const std::uint32_t j = d.joints[v * influences + i];
        if (w != 0.0f && j < skin.size()) m += w * skin[j];
      }
      p = glm::vec3(m * glm::vec4(p, 1.0f));
      nrm = cofactor(glm::mat3(m)) * nrm;
      tan = glm::mat3(m) * tan;
    }
    out.positions[v] = p;
    if (v < out.normals.size()) out.normals[v] = normalized_or_zero(nrm);
    if (v < out.tangents.size()) out.tangents[v] = glm::vec4(normalized_or_zero(tan), base.tangents[v].w);
  }
}

std::vector<Aabb> joint_boxes(const MeshData& mesh, const SkinData& skin) {
  std::vector<Aabb> boxes(skin.inverse_bind.size());
  const MeshDeform& d = mesh.deform;
  const std::size_t influences = std::size_t(d.influences);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    for (std::size_t i = 0; i < influences; ++i) {
      const std::uint32_t j = d.joints[v * influences + i];
      if (d.weights[v * influences + i] > 0.0f && j < boxes.size())
        boxes[j].expand(glm::vec3(skin.inverse_bind[j] * glm::vec4(mesh.positions[v], 1.0f)));
    }
  return boxes;
}

Aabb pose_bounds(const MeshData& base, std::span<const float> weights,
                 std::span<const glm::mat4> joint_world, const SkinData* skin,
                 std::span<const Aabb> boxes) {
  const MeshDeform& d = base.deform;
  // The morph displacement's box: each weighted target's box (which holds the origin) scaled.
  Aabb morph = Aabb::from_corners(glm::vec3(0.0f), glm::vec3(0.0f));
  for (std::size_t k = 0; k < d.targets.size(); ++k) {
    const float w = weight_of(weights, k);
    if (w == 0.0f) continue;
    const Aabb& t = d.targets[k].delta_bounds;
    morph.min += glm::min(w * t.min, w * t.max);
    morph.max += glm::max(w * t.min, w * t.max);
  }
  if (!(d.skinned() && skin != nullptr)) {
    Aabb out = base.bounds;
    if (out.empty()) return out;
    out.min += morph.min;
    out.max += morph.max;
    return out;
  }
  // Every posed vertex is a weighted mean of S[j] p over its joints, so it lies in the union of
  // world(j) * (box_j grown by the morph displacement in bind space).
  const glm::vec3 reach = glm::max(glm::abs(morph.min), glm::abs(morph.max));
  Aabb out;
  for (std::size_t j = 0; j < boxes.size() && j < joint_world.size(); ++j) {
    if (boxes[j].empty()) continue;
    const glm::mat3 ib(skin->inverse_bind[j]);
    // |ib| reach: the extent a displacement within +-reach can have after ib.
    const glm::vec3 grow = glm::vec3(glm::abs(ib[0]) * reach.x + glm::abs(ib[1]) * reach.y +
                                     glm::abs(ib[2]) * reach.z);
    Aabb b = boxes[j];
    b.min -= grow;
    b.max += grow;
    out.expand(b.transformed(joint_world[j]));
  }
  return out;
}

}  // namespace kaskad
