#include "runtime/assets/primitives.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <string>
#include <tuple>

namespace kaskad {
namespace {

constexpr PrimitiveShape kAllShapes[] = {PrimitiveShape::plane, PrimitiveShape::box,
                                         PrimitiveShape::sphere, PrimitiveShape::cylinder,
                                         PrimitiveShape::cone};
constexpr PrimitiveShape kClosedShapes[] = {PrimitiveShape::box, PrimitiveShape::sphere,
                                            PrimitiveShape::cylinder, PrimitiveShape::cone};
constexpr int kSegmentCounts[] = {3, 4, 5, 8, 32, 33, 1024};

std::string shape_name(PrimitiveShape s) {
  switch (s) {
    case PrimitiveShape::plane:
      return "plane";
    case PrimitiveShape::box:
      return "box";
    case PrimitiveShape::sphere:
      return "sphere";
    case PrimitiveShape::cylinder:
      return "cylinder";
    case PrimitiveShape::cone:
      return "cone";
    case PrimitiveShape::terrain:
      return "terrain";
  }
  return "?";
}

TEST(Primitives, AttributesAreConsistentAndIndicesInRange) {
  for (PrimitiveShape shape : kAllShapes) {
    for (int segments : kSegmentCounts) {
      SCOPED_TRACE(shape_name(shape) + " " + std::to_string(segments));
      const MeshData m = make_primitive(shape, segments);
      ASSERT_FALSE(m.positions.empty());
      EXPECT_EQ(m.normals.size(), m.positions.size());
      EXPECT_EQ(m.uvs.size(), m.positions.size());
      ASSERT_EQ(m.indices.size() % 3, 0u);
      ASSERT_GT(m.triangle_count(), 0u);
      for (std::uint32_t i : m.indices) ASSERT_LT(i, m.positions.size());
      for (const glm::vec2& uv : m.uvs) {
        ASSERT_GE(uv.x, 0.0f);
        ASSERT_LE(uv.x, 1.0f);
        ASSERT_GE(uv.y, 0.0f);
        ASSERT_LE(uv.y, 1.0f);
      }
    }
  }
}

TEST(Primitives, BoundsAreTheUnitSizes) {
  const float h = 0.5f;
  auto expect_box = [](const Aabb& b, glm::vec3 lo, glm::vec3 hi) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_FLOAT_EQ(b.min[a], lo[a]) << "axis " << a;
      EXPECT_FLOAT_EQ(b.max[a], hi[a]) << "axis " << a;
    }
  };
  expect_box(make_primitive(PrimitiveShape::plane, 3).bounds, {-h, 0, -h}, {h, 0, h});
  expect_box(make_primitive(PrimitiveShape::box, 3).bounds, {-h, -h, -h}, {h, h, h});
  // With segments a multiple of 4, a column lies on each of +-X and +-Z.
  for (PrimitiveShape round :
       {PrimitiveShape::sphere, PrimitiveShape::cylinder, PrimitiveShape::cone}) {
    SCOPED_TRACE(shape_name(round));
    expect_box(make_primitive(round, 32).bounds, {-h, -h, -h}, {h, h, h});
    // Any other count still stays inside the unit box and reaches its top and bottom.
    const Aabb b = make_primitive(round, 7).bounds;
    EXPECT_FLOAT_EQ(b.min.y, -h);
    EXPECT_FLOAT_EQ(b.max.y, h);
    EXPECT_GE(b.min.x, -h);
    EXPECT_LE(b.max.x, h);
    EXPECT_GT(b.max.x, 0.4f);  // coarse: the widest ring of a 7-segment sphere is at 60 degrees
  }
}

TEST(Primitives, NormalsAreUnitLength) {
  for (PrimitiveShape shape : kAllShapes) {
    for (int segments : kSegmentCounts) {
      SCOPED_TRACE(shape_name(shape) + " " + std::to_string(segments));
      for (const glm::vec3& n : make_primitive(shape, segments).normals)
        ASSERT_NEAR(glm::length(n), 1.0f, 1e-5f);
    }
  }
}

TEST(Primitives, SphereNormalsPointAwayFromTheCentre) {
  for (int segments : kSegmentCounts) {
    const MeshData m = make_primitive(PrimitiveShape::sphere, segments);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
      ASSERT_GE(glm::dot(m.normals[i], m.positions[i]), 0.0f);
      ASSERT_NEAR(glm::length(m.positions[i]), 0.5f, 1e-6f);
      // A sphere's normal is its position direction.
      ASSERT_NEAR(glm::length(m.normals[i] - 2.0f * m.positions[i]), 0.0f, 1e-5f);
    }
  }
}

TEST(Primitives, NormalsPointOutwardFromTheAxis) {
  // Convex shapes centred on the origin: every normal faces away from the centre of its face,
  // i.e. dot(normal, position) > 0 on the curved sides and caps.
  for (PrimitiveShape shape : kClosedShapes) {
    for (int segments : kSegmentCounts) {
      SCOPED_TRACE(shape_name(shape) + " " + std::to_string(segments));
      const MeshData m = make_primitive(shape, segments);
      for (std::size_t i = 0; i < m.positions.size(); ++i)
        ASSERT_GT(glm::dot(m.normals[i], m.positions[i]), 0.0f) << "vertex " << i;
    }
  }
}

TEST(Primitives, FrontFacesAreCounterClockwiseFromOutside) {
  // The right-handed geometric normal cross(b - a, c - a) must agree with the vertex normals and
  // point away from the origin (all shapes are convex and contain the origin, or are the plane).
  for (PrimitiveShape shape : kAllShapes) {
    for (int segments : kSegmentCounts) {
      SCOPED_TRACE(shape_name(shape) + " " + std::to_string(segments));
      const MeshData m = make_primitive(shape, segments);
      for (std::size_t t = 0; t < m.triangle_count(); ++t) {
        const auto ia = m.indices[3 * t], ib = m.indices[3 * t + 1], ic = m.indices[3 * t + 2];
        const glm::vec3 a = m.positions[ia], b = m.positions[ib], c = m.positions[ic];
        const glm::vec3 face = glm::cross(b - a, c - a);
        ASSERT_GT(glm::length(face), 0.0f) << "degenerate triangle " << t;
        for (auto i : {ia, ib, ic}) ASSERT_GT(glm::dot(face, m.normals[i]), 0.0f) << "tri " << t;
        if (shape != PrimitiveShape::plane) {
          ASSERT_GT(glm::dot(face, (a + b + c) / 3.0f), 0.0f) << "tri " << t;
        }
      }
    }
  }
}

TEST(Primitives, TexturesReadUnmirroredFromOutsideAndVGrowsDownTheSides) {
  // primitives.cpp's uv conventions: u grows to the right for a viewer outside, v downwards
  // (glTF: (0,0) the image's top-left). Then a triangle's uvs wind clockwise in (u, v) where its
  // positions wind counter-clockwise from outside: cross(dP/du, dP/dv) = cross(b - a, c - a) / det
  // with det = du1 dv2 - du2 dv1 < 0. On the sides (normal within 60 degrees of horizontal) of
  // the sphere and cylinder, dP/dv also points down.
  for (PrimitiveShape shape : kAllShapes) {
    for (int segments : kSegmentCounts) {
      SCOPED_TRACE(shape_name(shape) + " " + std::to_string(segments));
      const MeshData m = make_primitive(shape, segments);
      for (std::size_t t = 0; t < m.triangle_count(); ++t) {
        const auto ia = m.indices[3 * t], ib = m.indices[3 * t + 1], ic = m.indices[3 * t + 2];
        const glm::vec3 e1 = m.positions[ib] - m.positions[ia];
        const glm::vec3 e2 = m.positions[ic] - m.positions[ia];
        const glm::vec2 d1 = m.uvs[ib] - m.uvs[ia], d2 = m.uvs[ic] - m.uvs[ia];
        const float det = d1.x * d2.y - d2.x * d1.y;
        if (std::abs(det) < 1e-12f) continue;  // a pole's fan: no u extent
        ASSERT_LT(det, 0.0f) << "mirrored uvs on triangle " << t;
        const glm::vec3 n = glm::normalize(glm::cross(e1, e2));
        if ((shape == PrimitiveShape::sphere || shape == PrimitiveShape::cylinder) &&
            std::abs(n.y) < 0.5f) {
          const glm::vec3 dp_dv = (e2 * d1.x - e1 * d2.x) / det;
          ASSERT_LT(dp_dv.y, 0.0f) << "v does not grow downwards on triangle " << t;
        }
      }
    }
  }
}

TEST(Primitives, ClosedShapesShareEveryEdgeBetweenExactlyTwoTriangles) {
  // Weld vertices by exact position (split copies must be bit-identical), then count each
  // undirected edge; a closed, consistently wound mesh uses each directed edge exactly once.
  for (PrimitiveShape shape : kClosedShapes) {
    for (int segments : kSegmentCounts) {
      SCOPED_TRACE(shape_name(shape) + " " + std::to_string(segments));
      const MeshData m = make_primitive(shape, segments);
      std::map<std::tuple<float, float, float>, int> ids;
      std::vector<int> welded;
      for (const glm::vec3& p : m.positions)
        welded.push_back(
            ids.emplace(std::make_tuple(p.x, p.y, p.z), int(ids.size())).first->second);

      std::map<std::pair<int, int>, int> undirected, directed;
      for (std::size_t t = 0; t < m.triangle_count(); ++t) {
        for (int e = 0; e < 3; ++e) {
          const int a = welded[m.indices[3 * t + e]];
          const int b = welded[m.indices[3 * t + (e + 1) % 3]];
          ASSERT_NE(a, b) << "triangle " << t << " is degenerate after welding";
          ++undirected[{std::min(a, b), std::max(a, b)}];
          ++directed[{a, b}];
        }
      }
      for (const auto& [edge, count] : undirected)
        ASSERT_EQ(count, 2) << "edge " << edge.first << "-" << edge.second;
      for (const auto& [edge, count] : directed) ASSERT_EQ(count, 1) << "inconsistent winding";
      // Euler characteristic of a sphere-like closed surface: V - E + F = 2.
      EXPECT_EQ(int(ids.size()) - int(undirected.size()) + int(m.triangle_count()), 2);
    }
  }
}

TEST(Primitives, SegmentsOutsideTheRangeAreAPreconditionFailure) {
  // Other tests of this binary may have started threads (OIIO's pool): re-exec, do not just fork.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH((void)make_primitive(PrimitiveShape::sphere, 2), "segments must be in");
  EXPECT_DEATH((void)make_primitive(PrimitiveShape::cone, 1025), "segments must be in");
}

}  // namespace
}  // namespace kaskad

namespace kaskad {
namespace {

TEST(Primitives, TerrainIsADeterministicUnitHeightfield) {
  const MeshData a = make_primitive(PrimitiveShape::terrain, 64);
  const MeshData b = make_primitive(PrimitiveShape::terrain, 64);
  EXPECT_EQ(a.positions, b.positions);  // same heights every time, on every machine
  EXPECT_EQ(a.triangle_count(), 2u * 64u * 64u);
  EXPECT_EQ(a.positions.size(), 65u * 65u);
  EXPECT_NEAR(a.bounds.min.x, -0.5f, 1e-6f);
  EXPECT_NEAR(a.bounds.max.z, 0.5f, 1e-6f);
  EXPECT_GE(a.bounds.min.y, 0.0f);
  EXPECT_LE(a.bounds.max.y, 1.0f);
  EXPECT_GT(a.bounds.max.y - a.bounds.min.y, 0.2f);  // not flat
  for (const auto& n : a.normals) {
    EXPECT_NEAR(glm::length(n), 1.0f, 1e-4f);
    EXPECT_GT(n.y, 0.0f);  // a heightfield's normals point up
  }
  // Faces wind counter-clockwise seen from above: geometric normals agree with vertex normals.
  for (std::size_t t = 0; t < a.indices.size(); t += 3) {
    const glm::vec3 p0 = a.positions[a.indices[t]], p1 = a.positions[a.indices[t + 1]],
                    p2 = a.positions[a.indices[t + 2]];
    ASSERT_GT(glm::cross(p1 - p0, p2 - p0).y, 0.0f) << t;
  }
}

// Tiles partition the whole terrain: every tile vertex is the whole mesh's vertex at the same
// grid index (bit for bit, so shared edges have no cracks) and the triangles add up.
TEST(Primitives, TerrainTilesPartitionTheWholeHeightfield) {
  constexpr int kSegments = 48, kTiles = 4, kCells = kSegments / kTiles;
  const MeshData whole = make_primitive(PrimitiveShape::terrain, kSegments);
  std::size_t triangles = 0;
  for (int tz = 0; tz < kTiles; ++tz)
    for (int tx = 0; tx < kTiles; ++tx) {
      const MeshData tile = make_terrain_tile(kSegments, kTiles, tx, tz);
      triangles += tile.triangle_count();
      ASSERT_EQ(tile.positions.size(), std::size_t((kCells + 1) * (kCells + 1)));
      for (int j = 0; j <= kCells; ++j)
        for (int i = 0; i <= kCells; ++i) {
          const std::size_t w = std::size_t((tz * kCells + j) * (kSegments + 1) + tx * kCells + i);
          const std::size_t t = std::size_t(j * (kCells + 1) + i);
          ASSERT_EQ(tile.positions[t], whole.positions[w]) << tx << "," << tz << " " << i << "," << j;
          ASSERT_EQ(tile.normals[t], whole.normals[w]);
        }
      EXPECT_LE(tile.bounds.max.x - tile.bounds.min.x, 1.0f / kTiles + 1e-6f);
    }
  EXPECT_EQ(triangles, whole.triangle_count());
}

}  // namespace
}  // namespace kaskad
