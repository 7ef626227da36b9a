#include "runtime/assets/mesh_tangents.h"

#include <cmath>

namespace kaskad {
namespace {

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// v projected onto the plane of unit n, normalised; zero when nothing is left.
glm::vec3 in_plane(const glm::vec3& v, const glm::vec3& n) {
  const glm::vec3 p = v - n * glm::dot(n, v);
  const float len = glm::length(p);
  return len > 1e-20f && std::isfinite(len) ? p / len : glm::vec3(0.0f);
}

}  // namespace

std::vector<glm::vec4> generate_tangents(const MeshData& mesh) {
  const std::size_t n = mesh.positions.size();
  if (n == 0 || mesh.uvs.size() != n || mesh.normals.size() != n) return {};
  std::vector<glm::vec3> t(n, glm::vec3(0.0f)), b(n, glm::vec3(0.0f));
  for (std::size_t f = 0; f + 2 < mesh.indices.size(); f += 3) {
    const std::uint32_t i[3] = {mesh.indices[f], mesh.indices[f + 1], mesh.indices[f + 2]};
    if (i[0] >= n || i[1] >= n || i[2] >= n) continue;
    const glm::vec3 e1 = mesh.positions[i[1]] - mesh.positions[i[0]];
    const glm::vec3 e2 = mesh.positions[i[2]] - mesh.positions[i[0]];
    const glm::vec2 d1 = mesh.uvs[i[1]] - mesh.uvs[i[0]];
    const glm::vec2 d2 = mesh.uvs[i[2]] - mesh.uvs[i[0]];
    const float det = d1.x * d2.y - d2.x * d1.y;
    if (!(std::abs(det) > 1e-20f)) continue;  // degenerate uvs (or NaN): no direction
    // p(u, v) over the triangle: dp/du and dp/dv.
    const glm::vec3 face_t = (e1 * d2.y - e2 * d1.y) / det;
    const glm::vec3 face_b = (e2 * d1.x - e1 * d2.x) / det;
    if (!finite(face_t) || !finite(face_b)) continue;
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 p = mesh.positions[i[k]];
      const glm::vec3 a = mesh.positions[i[(k + 1) % 3]] - p, c = mesh.positions[i[(k + 2) % 3]] - p;
      const float la = glm::length(a), lc = glm::length(c);
      if (!(la > 0.0f && lc > 0.0f)) continue;
      const float angle = std::acos(std::clamp(glm::dot(a, c) / (la * lc), -1.0f, 1.0f));
      const glm::vec3 nv = mesh.normals[i[k]];
      t[i[k]] += in_plane(face_t, nv) * angle;
      b[i[k]] += in_plane(face_b, nv) * angle;
    }
  }
  std::vector<glm::vec4> out(n);
  for (std::size_t v = 0; v < n; ++v) {
    const glm::vec3 nv = mesh.normals[v];
    glm::vec3 tv = in_plane(t[v], nv);
    if (tv == glm::vec3(0.0f)) {  // no uv gradient here: any direction in the plane
      tv = in_plane(std::abs(nv.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0), nv);
      out[v] = glm::vec4(tv, 1.0f);
      continue;
    }
    const float w = glm::dot(glm::cross(nv, tv), b[v]) < 0.0f ? -1.0f : 1.0f;
    out[v] = glm::vec4(tv, w);
  }
  return out;
}

}  // namespace kaskad
