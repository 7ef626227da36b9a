// Built-in unit primitives.
//
// Conventions shared by every shape, each checked by a test in
// tests/unit/assets/primitives_test.cpp (Primitives.FrontFacesAreCounterClockwiseFromOutside,
// TexturesReadUnmirroredFromOutsideAndVGrowsDownTheSides,
// ClosedShapesShareEveryEdgeBetweenExactlyTwoTriangles):
// - right-handed, +Y up; front faces are counter-clockwise seen from outside (OpenGL default);
// - angle theta runs around +Y from +Z towards +X: x = r sin(theta), z = r cos(theta), so that u
//   grows to the right for a viewer outside the surface;
// - uvs follow glTF: (0,0) is the top-left of the image, v grows downwards;
// - vertices are split along hard edges (box edges, cap rims) and along the uv seam, but split
//   copies have bit-identical positions, so the meshes are closed once welded by position (what a
//   shadow pass sees): no cracks for light to leak through.
#include "runtime/assets/primitives.h"

#include <cmath>
#include <numbers>
#include <string>

#include "runtime/result/result.h"

namespace kaskad {
namespace {

constexpr float kRadius = 0.5f;      // diameter 1
constexpr float kHalfHeight = 0.5f;  // height 1, centred on the origin

/// Appends a vertex and returns its index.
std::uint32_t add_vertex(MeshData& m, glm::vec3 p, glm::vec3 n, glm::vec2 uv) {
  m.positions.push_back(p);
  m.normals.push_back(n);
  m.uvs.push_back(uv);
  return std::uint32_t(m.positions.size() - 1);
}

void add_triangle(MeshData& m, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  m.indices.insert(m.indices.end(), {a, b, c});
}

/// (sin, cos) of the angle of column j of `segments`; column `segments` reuses column 0's angle
/// so that the seam's duplicated vertices have exactly the same position.
glm::vec2 ring_direction(int j, int segments) {
  const double theta = 2.0 * std::numbers::pi * double(j % segments) / double(segments);
  return {float(std::sin(theta)), float(std::cos(theta))};
}

/// Point on a horizontal circle of radius r at height y, column j.
glm::vec3 ring_point(int j, int segments, float r, float y) {
  const glm::vec2 d = ring_direction(j, segments);
  return {r * d.x, y, r * d.y};
}

/// 1 x 1 square in XZ at y = 0, facing +Y.
MeshData make_plane() {
  MeshData m;
  m.name = "plane";
  const glm::vec3 up{0, 1, 0};
  // Looking down from +Y with -Z at the top of the view: (-x,-z) is the image's top-left.
  const auto a = add_vertex(m, {-0.5f, 0, -0.5f}, up, {0, 0});
  const auto b = add_vertex(m, {-0.5f, 0, 0.5f}, up, {0, 1});
  const auto c = add_vertex(m, {0.5f, 0, 0.5f}, up, {1, 1});
  const auto d = add_vertex(m, {0.5f, 0, -0.5f}, up, {1, 0});
  add_triangle(m, a, b, c);
  add_triangle(m, a, c, d);
  return m;
}

/// 1 x 1 x 1 cube, 4 vertices per face for hard normals.
MeshData make_box() {
  MeshData m;
  m.name = "box";
  // Each face: outward normal n and the right/up axes of a viewer looking at it from outside,
  // with right x up = n (so bl, br, tr is counter-clockwise from outside).
  struct Face {
    glm::vec3 n, right, up;
  };
  const Face faces[] = {
      {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}}, {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
      {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}}, {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
      {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}},
  };
  for (const Face& f : faces) {
    const glm::vec3 c = 0.5f * f.n;
    const auto bl = add_vertex(m, c - 0.5f * f.right - 0.5f * f.up, f.n, {0, 1});
    const auto br = add_vertex(m, c + 0.5f * f.right - 0.5f * f.up, f.n, {1, 1});
    const auto tr = add_vertex(m, c + 0.5f * f.right + 0.5f * f.up, f.n, {1, 0});
    const auto tl = add_vertex(m, c - 0.5f * f.right + 0.5f * f.up, f.n, {0, 0});
    add_triangle(m, bl, br, tr);
    add_triangle(m, bl, tr, tl);
  }
  return m;
}

/// UV sphere of diameter 1: `segments` columns, max(2, segments / 2) latitude bands. The poles are
/// triangle fans (one pole vertex per column, for its uv) so that no triangle is degenerate.
MeshData make_sphere(int segments) {
  MeshData m;
  m.name = "sphere";
  const int rings = std::max(2, segments / 2);
  // rows[i][j]: vertex of latitude row i (0 = north pole, rings = south pole), column j.
  std::vector<std::vector<std::uint32_t>> rows(rings + 1);
  for (int i = 0; i <= rings; ++i) {
    const double phi = std::numbers::pi * double(i) / double(rings);  // from +Y
    const bool pole = i == 0 || i == rings;
    // Poles are set exactly (sin(pi) is not 0 in floating point).
    const float y = i == 0 ? kRadius : i == rings ? -kRadius : float(kRadius * std::cos(phi));
    const float r = pole ? 0.0f : float(kRadius * std::sin(phi));
    const int columns = pole ? segments : segments + 1;
    for (int j = 0; j < columns; ++j) {
      const float u = (float(j) + (pole ? 0.5f : 0.0f)) / float(segments);
      const glm::vec3 p = pole ? glm::vec3(0, y, 0) : ring_point(j, segments, r, y);
      rows[i].push_back(add_vertex(m, p, p / kRadius, {u, float(i) / float(rings)}));
    }
  }
  for (int i = 0; i < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      // Quad a-b (row i) over d-c (row i + 1); pole rows collapse a=b or c=d into one vertex.
      if (i == 0) {
        add_triangle(m, rows[0][j], rows[1][j], rows[1][j + 1]);
      } else if (i == rings - 1) {
        add_triangle(m, rows[i][j], rows[rings][j], rows[i][j + 1]);
      } else {
        const auto a = rows[i][j], b = rows[i][j + 1], c = rows[i + 1][j + 1], d = rows[i + 1][j];
        add_triangle(m, a, d, c);
        add_triangle(m, a, c, b);
      }
    }
  }
  return m;
}

/// Flat disc cap of radius kRadius at height y, facing +Y (top) or -Y (bottom), as a fan.
void add_cap(MeshData& m, int segments, float y, bool top) {
  const glm::vec3 n{0, top ? 1.0f : -1.0f, 0};
  // Planar uvs: seen from outside, image top-left at (-x, -z) for the top cap, (-x, +z) below.
  auto cap_uv = [&](glm::vec3 p) { return glm::vec2(0.5f + p.x, top ? 0.5f + p.z : 0.5f - p.z); };
  const auto centre = add_vertex(m, {0, y, 0}, n, {0.5f, 0.5f});
  const auto first = std::uint32_t(m.positions.size());
  for (int j = 0; j < segments; ++j) {
    const glm::vec3 p = ring_point(j, segments, kRadius, y);
    add_vertex(m, p, n, cap_uv(p));
  }
  for (int j = 0; j < segments; ++j) {
    const auto a = first + std::uint32_t(j), b = first + std::uint32_t((j + 1) % segments);
    if (top) {
      add_triangle(m, centre, a, b);
    } else {
      add_triangle(m, centre, b, a);
    }
  }
}

/// Cylinder of diameter 1 and height 1 along Y, with both caps.
MeshData make_cylinder(int segments) {
  MeshData m;
  m.name = "cylinder";
  const auto first = std::uint32_t(m.positions.size());
  for (int j = 0; j <= segments; ++j) {
    const glm::vec2 d = ring_direction(j, segments);
    const glm::vec3 n{d.x, 0, d.y};
    const float u = float(j) / float(segments);
    add_vertex(m, ring_point(j, segments, kRadius, -kHalfHeight), n, {u, 1});
    add_vertex(m, ring_point(j, segments, kRadius, kHalfHeight), n, {u, 0});
  }
  for (int j = 0; j < segments; ++j) {
    const auto b0 = first + 2 * std::uint32_t(j), t0 = b0 + 1, b1 = b0 + 2, t1 = b0 + 3;
    add_triangle(m, b0, b1, t1);
    add_triangle(m, b0, t1, t0);
  }
  add_cap(m, segments, kHalfHeight, true);
  add_cap(m, segments, -kHalfHeight, false);
  return m;
}

/// Cone of base diameter 1 at y = -0.5 and apex at y = +0.5, with its base cap. The apex is one
/// vertex per column (same position) so each side triangle gets the normal of its middle angle.
MeshData make_cone(int segments) {
  MeshData m;
  m.name = "cone";
  // Outward normal of the slanted side at angle theta: (H sin, R, H cos) normalised, H = height.
  const float height = 2.0f * kHalfHeight;
  auto side_normal = [&](double theta) {
    return glm::normalize(
        glm::vec3(height * float(std::sin(theta)), kRadius, height * float(std::cos(theta))));
  };
  const auto base = std::uint32_t(m.positions.size());
  for (int j = 0; j <= segments; ++j) {
    const double theta = 2.0 * std::numbers::pi * double(j % segments) / double(segments);
    add_vertex(m, ring_point(j, segments, kRadius, -kHalfHeight), side_normal(theta),
               {float(j) / float(segments), 1});
  }
  for (int j = 0; j < segments; ++j) {
    const double mid = 2.0 * std::numbers::pi * (double(j) + 0.5) / double(segments);
    const auto apex = add_vertex(m, {0, kHalfHeight, 0}, side_normal(mid),
                                 {(float(j) + 0.5f) / float(segments), 0});
    add_triangle(m, base + std::uint32_t(j), base + std::uint32_t(j + 1), apex);
  }
  add_cap(m, segments, -kHalfHeight, false);
  return m;
}

}  // namespace

// Value noise on the integer lattice, hashed (no tables: the same heights on every machine).
float lattice(int x, int z) {
  std::uint32_t h = std::uint32_t(x) * 0x8da6b343u ^ std::uint32_t(z) * 0xd8163841u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return float(h & 0xffffffu) / float(0xffffff);
}

float value_noise(float x, float z) {
  const float fx = std::floor(x), fz = std::floor(z);
  const int ix = int(fx), iz = int(fz);
  float tx = x - fx, tz = z - fz;
  tx = tx * tx * (3.0f - 2.0f * tx);  // smoothstep fade
  tz = tz * tz * (3.0f - 2.0f * tz);
  const float a = lattice(ix, iz), b = lattice(ix + 1, iz);
  const float c = lattice(ix, iz + 1), d = lattice(ix + 1, iz + 1);
  return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * tz;
}

/// Height in [0, 1] at (u, v) in [0, 1]^2: six octaves of value noise (fBm).
float terrain_height(float u, float v) {
  float sum = 0.0f, amplitude = 0.5f, frequency = 4.0f, norm = 0.0f;
  for (int octave = 0; octave < 6; ++octave) {
    sum += amplitude * value_noise(u * frequency + 17.0f * float(octave), v * frequency);
    norm += amplitude;
    amplitude *= 0.5f;
    frequency *= 2.0f;
  }
  return sum / norm;
}

MeshData make_terrain_tile(int segments, int tiles, int tile_x, int tile_z) {
  KASKAD_CHECK(segments >= 1 && tiles >= 1 && segments % tiles == 0 && tile_x >= 0 &&
                   tile_x < tiles && tile_z >= 0 && tile_z < tiles,
               "terrain tile " + std::to_string(tile_x) + "," + std::to_string(tile_z) + " of " +
                   std::to_string(tiles) + " with " + std::to_string(segments) + " segments");
  MeshData m;
  m.name = tiles == 1 ? "terrain" : "terrain tile " + std::to_string(tile_x) + "," + std::to_string(tile_z);
  const int n = segments / tiles;  // cells per tile side
  const float step = 1.0f / float(segments);
  // Grid vertices are computed from their global index, so neighbouring tiles share edge
  // vertices bit for bit (no cracks).
  const int i0 = tile_x * n, j0 = tile_z * n;
  for (int j = j0; j <= j0 + n; ++j) {
    for (int i = i0; i <= i0 + n; ++i) {
      const float u = float(i) * step, v = float(j) * step;
      // Normal from central differences of the height (local space; the normal matrix handles
      // the transform's non-uniform scale).
      const float dx = terrain_height(u + step, v) - terrain_height(u - step, v);
      const float dz = terrain_height(u, v + step) - terrain_height(u, v - step);
      const glm::vec3 normal = glm::normalize(glm::vec3(-dx, 2.0f * step, -dz));
      add_vertex(m, {u - 0.5f, terrain_height(u, v), v - 0.5f}, normal, {u, v});
    }
  }
  const auto at = [n](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {  // counter-clockwise seen from +Y, as the plane
      add_triangle(m, at(i, j), at(i, j + 1), at(i + 1, j + 1));
      add_triangle(m, at(i, j), at(i + 1, j + 1), at(i + 1, j));
    }
  m.compute_bounds();
  return m;
}

MeshData make_primitive(PrimitiveShape shape, int segments) {
  KASKAD_CHECK(segments >= 3 && segments <= 1024,
               "segments must be in [3, 1024], was " + std::to_string(segments));
  MeshData mesh;
  switch (shape) {
    case PrimitiveShape::plane:
      mesh = make_plane();
      break;
    case PrimitiveShape::box:
      mesh = make_box();
      break;
    case PrimitiveShape::sphere:
      mesh = make_sphere(segments);
      break;
    case PrimitiveShape::cylinder:
      mesh = make_cylinder(segments);
      break;
    case PrimitiveShape::cone:
      mesh = make_cone(segments);
      break;
    case PrimitiveShape::terrain:
      mesh = make_terrain_tile(segments, 1, 0, 0);
      break;
  }
  mesh.compute_bounds();
  return mesh;
}

}  // namespace kaskad
