// Environment maps: cube face maths against OpenGL's table 8.19 and S3, sphere maps against S3
// eq. (2), (4), (5), and the static layouts (faces, crosses, equirect, 3ds Max) against each other.
#include "runtime/assets/env_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "runtime/assets/image_io.h"
#include "tests/unit/assets/asset_test_util.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

constexpr std::array<CubeFace, 6> kFaces = {CubeFace::pos_x, CubeFace::neg_x, CubeFace::pos_y,
                                            CubeFace::neg_y, CubeFace::pos_z, CubeFace::neg_z};

/// S3's coloured-cube environment: one distinct colour per face (by the direction's major axis).
const std::array<glm::vec4, 6> kFaceColour = {glm::vec4(1, 0, 0, 1), glm::vec4(0, 1, 1, 1),
                                              glm::vec4(0, 1, 0, 1), glm::vec4(1, 0, 1, 1),
                                              glm::vec4(0, 0, 1, 1), glm::vec4(1, 1, 0, 1)};

/// Major axis of a direction as a face, computed here without cube_coord().
int major_axis_face(const glm::vec3& d) {
  const glm::vec3 a = glm::abs(d);
  if (a.x >= a.y && a.x >= a.z) return d.x > 0 ? 0 : 1;
  if (a.y >= a.z) return d.y > 0 ? 2 : 3;
  return d.z > 0 ? 4 : 5;
}

/// How far from a tie between two major axes a direction is (0 on a cube edge).
float axis_margin(const glm::vec3& d) {
  glm::vec3 a = glm::abs(glm::normalize(d));
  float m1 = std::max({a.x, a.y, a.z});
  float m2 = a.x + a.y + a.z - m1 - std::min({a.x, a.y, a.z});
  return m1 - m2;
}

CubeMap coloured_cube(int size) {
  return make_cube_map(
      size, [](const glm::vec3& d) { return kFaceColour[std::size_t(major_axis_face(d))]; });
}

/// A smooth environment: a different smooth function of the direction per channel, in [0,1].
glm::vec4 smooth_env(const glm::vec3& d) {
  return {0.5f + 0.5f * d.x, 0.5f + 0.5f * d.y, 0.5f + 0.5f * d.z, 0.5f + 0.25f * d.x * d.y};
}

float max_diff(const glm::vec4& a, const glm::vec4& b) {
  const glm::vec4 d = glm::abs(a - b);
  return std::max({d.x, d.y, d.z, d.w});
}

/// Largest texel difference between two cube maps of the same size.
float cube_max_diff(const CubeMap& a, const CubeMap& b) {
  EXPECT_EQ(a.size, b.size);
  float m = 0.0f;
  for (std::size_t f = 0; f < 6; ++f) {
    EXPECT_EQ(a.faces[f].size(), b.faces[f].size());
    for (std::size_t i = 0; i < std::min(a.faces[f].size(), b.faces[f].size()); ++i)
      m = std::max(m, max_diff(a.faces[f][i], b.faces[f][i]));
  }
  return m;
}

Image image_of(const std::vector<glm::vec4>& texels, int w, int h) {
  Image img;
  img.width = w;
  img.height = h;
  img.channels = 4;
  img.channel_names = {"R", "G", "B", "A"};
  for (const glm::vec4& t : texels)
    for (int c = 0; c < 4; ++c) img.pixels.push_back(t[c]);
  return img;
}

fs::path dir_for(const std::string& name) {
  const fs::path d = test::temp_dir() / ("env_map_" + name);
  fs::create_directories(d);
  return d;
}

// --- cube face maths ---------------------------------------------------------------------------

TEST(CubeMath, FaceCoordinatesFollowGlTable819) {
  // Face centres are the axes.
  EXPECT_EQ(cube_direction(CubeFace::pos_x, 0.5f, 0.5f), glm::vec3(1, 0, 0));
  EXPECT_EQ(cube_direction(CubeFace::neg_y, 0.5f, 0.5f), glm::vec3(0, -1, 0));
  EXPECT_EQ(cube_direction(CubeFace::neg_z, 0.5f, 0.5f), glm::vec3(0, 0, -1));
  // Corners (s, t) = (0, 0), written out from table 8.19: sc = tc = -1.
  const float k = 1.0f / std::sqrt(3.0f);
  auto near = [&](glm::vec3 a, glm::vec3 b) { return glm::length(a - b * k) < 1e-6f; };
  EXPECT_TRUE(near(cube_direction(CubeFace::pos_x, 0, 0), {1, 1, 1}));    // sc=-z, tc=-y
  EXPECT_TRUE(near(cube_direction(CubeFace::neg_x, 0, 0), {-1, 1, -1}));  // sc=+z, tc=-y
  EXPECT_TRUE(near(cube_direction(CubeFace::pos_y, 0, 0), {-1, 1, -1}));  // sc=+x, tc=+z
  EXPECT_TRUE(near(cube_direction(CubeFace::neg_y, 0, 0), {-1, -1, 1}));  // sc=+x, tc=-z
  EXPECT_TRUE(near(cube_direction(CubeFace::pos_z, 0, 0), {-1, 1, 1}));   // sc=+x, tc=-y
  EXPECT_TRUE(near(cube_direction(CubeFace::neg_z, 0, 0), {1, 1, -1}));   // sc=-x, tc=-y
  // S3's +X formulas: s = -z / (2|x|) + 1/2, t = -y / (2|x|) + 1/2.
  const glm::vec3 d(2.0f, -0.6f, 1.2f);
  const CubeCoord c = cube_coord(d);
  EXPECT_EQ(c.face, CubeFace::pos_x);
  EXPECT_NEAR(c.s, -d.z / (2 * std::abs(d.x)) + 0.5f, 1e-6f);
  EXPECT_NEAR(c.t, -d.y / (2 * std::abs(d.x)) + 0.5f, 1e-6f);
  EXPECT_STREQ(cube_face_suffix(CubeFace::neg_y), "ny");
}

TEST(CubeMath, DirectionAndCoordRoundTrip) {
  for (CubeFace f : kFaces) {
    for (float s = 0.05f; s < 1.0f; s += 0.1f) {
      for (float t = 0.05f; t < 1.0f; t += 0.1f) {
        const glm::vec3 d = cube_direction(f, s, t);
        EXPECT_NEAR(glm::length(d), 1.0f, 1e-6f);
        const CubeCoord c = cube_coord(d);
        EXPECT_EQ(c.face, f) << s << " " << t;
        EXPECT_NEAR(c.s, s, 1e-5f);
        EXPECT_NEAR(c.t, t, 1e-5f);
      }
    }
  }
  std::mt19937 rng(7);
  std::normal_distribution<float> g;
  for (int i = 0; i < 1000; ++i) {
    const glm::vec3 d(g(rng), g(rng), g(rng));
    const CubeCoord c = cube_coord(3.0f * d);  // any length
    EXPECT_EQ(int(c.face), major_axis_face(d));
    EXPECT_LT(glm::length(cube_direction(c.face, c.s, c.t) - glm::normalize(d)), 1e-5f);
  }
  // Degenerate input does not crash and stays in range.
  const CubeCoord z = cube_coord(glm::vec3(0.0f));
  EXPECT_GE(z.s, 0.0f);
  EXPECT_LE(z.s, 1.0f);
  EXPECT_EQ(cube_coord(glm::vec3(NAN, 0, 1)).face, CubeFace::pos_z);
}

TEST(CubeMath, ColouredCubeAxesGiveTheirFaceColour) {
  const CubeMap cube = coloured_cube(8);
  const std::array<glm::vec3, 6> axes = {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0),
                                         glm::vec3(0, 1, 0), glm::vec3(0, -1, 0),
                                         glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)};
  for (std::size_t f = 0; f < 6; ++f) {
    EXPECT_EQ(sample_cube(cube, axes[f]), kFaceColour[f]) << f;
    // Off-centre but well inside the face, and at a corner (bilinear clamped to the face).
    EXPECT_EQ(
        sample_cube(cube, axes[f] + glm::vec3(0.3f, -0.2f, 0.25f) * (1.0f - glm::abs(axes[f]))),
        kFaceColour[f]);
    EXPECT_EQ(sample_cube(cube, cube_direction(kFaces[f], 0.001f, 0.999f)), kFaceColour[f]);
  }
  EXPECT_EQ(sample_cube(CubeMap{}, {1, 0, 0}), glm::vec4(0.0f));
}

TEST(CubeMath, SampleCubeIsBilinearInsideAFace) {
  // A smooth environment sampled between texel centres is close to the function itself.
  const CubeMap cube = make_cube_map(32, smooth_env);
  std::mt19937 rng(3);
  std::normal_distribution<float> g;
  for (int i = 0; i < 500; ++i) {
    const glm::vec3 d = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
    EXPECT_LT(max_diff(sample_cube(cube, d), smooth_env(d)), 0.03f);
  }
  // Exactly the texel value at texel centres.
  EXPECT_EQ(sample_cube(cube, cube_direction(CubeFace::neg_x, 5.5f / 32, 20.5f / 32)),
            cube.at(CubeFace::neg_x, 5, 20));
}

// --- sphere maps -------------------------------------------------------------------------------

/// S3 eq. (2) written out here: texel (i, j) of a size x size map, j counted from the BOTTOM as
/// in S3, at the texel centre.
glm::vec3 s3_eq2(int i, int j_from_bottom, int size) {
  const float s = 2.0f * ((float(i) + 0.5f) / float(size) - 0.5f);
  const float t = 2.0f * ((float(j_from_bottom) + 0.5f) / float(size) - 0.5f);
  const float az = std::sqrt(std::max(0.0f, 1.0f - s * s - t * t));
  return {2 * az * s, 2 * az * t, 2 * az * az - 1};
}

TEST(SphereMap, ColouredCubeCentreIsPlusZRimIsMinusZ) {
  const int n = 64;
  const SphereMap map = sphere_map_from_cube(coloured_cube(16), n);
  ASSERT_EQ(map.size, n);
  ASSERT_EQ(map.texels.size(), std::size_t(n * n));
  // Centre: R = +Z of view space (towards the eye): the +Z face.
  for (int j : {n / 2 - 1, n / 2})
    for (int i : {n / 2 - 1, n / 2}) EXPECT_EQ(map.at(i, j), kFaceColour[4]);
  // Rim, inside the circle, at the four compass points: R = -Z, the back.
  EXPECT_EQ(map.at(0, n / 2), kFaceColour[5]);
  EXPECT_EQ(map.at(n - 1, n / 2), kFaceColour[5]);
  EXPECT_EQ(map.at(n / 2, 0), kFaceColour[5]);
  EXPECT_EQ(map.at(n / 2, n - 1), kFaceColour[5]);
  // Up in the image is +Y of view space, right is +X: halfway out the reflection is sideways.
  EXPECT_EQ(map.at(n / 2, n / 2 - int(0.7f * n / 2)), kFaceColour[2]);      // top: +Y
  EXPECT_EQ(map.at(n / 2, n / 2 + int(0.7f * n / 2)), kFaceColour[3]);      // bottom: -Y
  EXPECT_EQ(map.at(n / 2 + int(0.7f * n / 2), n / 2), kFaceColour[0]);      // right: +X
  EXPECT_EQ(map.at(n / 2 - 1 - int(0.7f * n / 2), n / 2), kFaceColour[1]);  // left: -X
  // Outside the circle: the rim value.
  EXPECT_EQ(map.at(0, 0), kFaceColour[5]);
}

TEST(SphereMap, EveryTexelIsFormulaExact) {
  const int n = 48;
  const CubeMap cube = coloured_cube(8);
  const SphereMap map = sphere_map_from_cube(cube, n);
  int checked = 0;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const glm::vec3 r = s3_eq2(i, n - 1 - j, n);  // image rows run downwards
      EXPECT_LT(glm::length(sphere_map_direction(i, j, n) - r), 1e-5f) << i << " " << j;
      if (axis_margin(r) < 0.05f) continue;  // near a cube edge: the colour is a blend
      EXPECT_EQ(map.at(i, j), kFaceColour[std::size_t(major_axis_face(r))]) << i << " " << j;
      ++checked;
    }
  }
  EXPECT_GT(checked, n * n / 2);
}

TEST(SphereMap, ViewRotationPicksWhatTheViewerFaces) {
  // A camera looking down world +X (turned -90 degrees about Y): view -Z is world +X, so the rim
  // shows +X and the centre (towards the eye) -X; view +Y stays world +Y.
  const glm::mat4 camera_to_world =
      glm::rotate(glm::mat4(1.0f), glm::radians(-90.0f), glm::vec3(0, 1, 0));
  const glm::mat3 view_to_world(camera_to_world);
  ASSERT_LT(glm::length(view_to_world * glm::vec3(0, 0, -1) - glm::vec3(1, 0, 0)), 1e-6f);
  const int n = 64;
  const CubeMap cube = coloured_cube(8);
  const SphereMap map = sphere_map_from_cube(cube, n, view_to_world);
  EXPECT_EQ(map.at(n / 2, n / 2), kFaceColour[1]);                      // centre: -X
  EXPECT_EQ(map.at(0, n / 2), kFaceColour[0]);                          // rim: +X
  EXPECT_EQ(map.at(n / 2, n / 2 - int(0.7f * n / 2)), kFaceColour[2]);  // up: +Y
  // Looking up a view-space direction gives the cube along its world direction.
  const SphereMap smooth = sphere_map_from_cube(make_cube_map(64, smooth_env), 256, view_to_world);
  const glm::vec3 r_view = glm::normalize(glm::vec3(0.3f, -0.4f, 0.6f));
  EXPECT_LT(max_diff(sample_sphere(smooth, r_view), smooth_env(view_to_world * r_view)), 0.02f);
}

TEST(SphereMap, UvIsS3Eq4And5AndInvertsEq2) {
  EXPECT_EQ(sphere_map_uv({0, 0, 1}), glm::vec2(0.5f, 0.5f));
  // R = (1, 0, 0): A_z = sqrt(1/2), s = 1 / (2 A_z) = sqrt(1/2).
  EXPECT_NEAR(sphere_map_uv({1, 0, 0}).x, (std::sqrt(0.5f) + 1) / 2, 1e-6f);
  EXPECT_NEAR(sphere_map_uv({0, 2, 0}).y, (std::sqrt(0.5f) + 1) / 2, 1e-6f);  // any length
  EXPECT_EQ(sphere_map_uv({0, 0, -1}), glm::vec2(1.0f, 0.5f));  // the singular rim point
  const int n = 40;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const float s = 2.0f * (float(i) + 0.5f) / n - 1, t = 1 - 2.0f * (float(j) + 0.5f) / n;
      if (s * s + t * t > 0.98f) continue;
      const glm::vec2 uv = sphere_map_uv(sphere_map_direction(i, j, n));
      EXPECT_NEAR(uv.x, (float(i) + 0.5f) / n, 2e-5f);
      EXPECT_NEAR(uv.y, 1.0f - (float(j) + 0.5f) / n, 2e-5f);  // t' upwards
    }
  }
}

TEST(SphereMap, LookupsMatchTheCubeAwayFromTheRim) {
  const CubeMap cube = make_cube_map(64, smooth_env);
  const SphereMap map = sphere_map_from_cube(cube, 256);
  const SphereMap coloured = sphere_map_from_cube(coloured_cube(16), 256);
  const CubeMap coloured_c = coloured_cube(16);
  std::mt19937 rng(11);
  std::normal_distribution<float> g;
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const glm::vec3 d = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
    if (d.z < -0.5f) continue;  // the rim: one texel covers a wide angle there
    EXPECT_LT(max_diff(sample_sphere(map, d), sample_cube(cube, d)), 0.02f) << d.x << d.y << d.z;
    if (axis_margin(d) > 0.1f) {
      EXPECT_EQ(sample_sphere(coloured, d), sample_cube(coloured_c, d));
    }
    ++checked;
  }
  EXPECT_GT(checked, 1000);
  EXPECT_EQ(sample_sphere(SphereMap{}, {0, 0, 1}), glm::vec4(0.0f));
}

// --- layouts -----------------------------------------------------------------------------------

/// Face cells of the documented crosses (env_map.h), in CubeFace order, written out here.
struct CrossCell {
  int col, row;
  bool rotate_180;
};
const std::array<CrossCell, 6> kHorizontal = {
    {{2, 1, false}, {0, 1, false}, {1, 0, false}, {1, 2, false}, {1, 1, false}, {3, 1, false}}};
const std::array<CrossCell, 6> kVertical = {
    {{2, 1, false}, {0, 1, false}, {1, 0, false}, {1, 2, false}, {1, 1, false}, {1, 3, true}}};

/// A cross image of `cube`; cells outside the cross are black.
Image cross_image(const CubeMap& cube, bool vertical) {
  const int n = cube.size, w = n * (vertical ? 3 : 4), h = n * (vertical ? 4 : 3);
  std::vector<glm::vec4> texels(std::size_t(w * h), glm::vec4(0, 0, 0, 1));
  const auto& cells = vertical ? kVertical : kHorizontal;
  for (int f = 0; f < 6; ++f) {
    const CrossCell& c = cells[std::size_t(f)];
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const int fx = c.rotate_180 ? n - 1 - x : x, fy = c.rotate_180 ? n - 1 - y : y;
        texels[std::size_t((c.row * n + y) * w + c.col * n + x)] = cube.at(CubeFace(f), fx, fy);
      }
  }
  return image_of(texels, w, h);
}

/// The direction at each cross pixel (cube_direction of its face texel), NaN outside the cross.
std::vector<glm::vec3> cross_directions(int n, bool vertical) {
  const int w = n * (vertical ? 3 : 4), h = n * (vertical ? 4 : 3);
  std::vector<glm::vec3> dirs(std::size_t(w * h), glm::vec3(NAN));
  const auto& cells = vertical ? kVertical : kHorizontal;
  for (int f = 0; f < 6; ++f) {
    const CrossCell& c = cells[std::size_t(f)];
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const int fx = c.rotate_180 ? n - 1 - x : x, fy = c.rotate_180 ? n - 1 - y : y;
        dirs[std::size_t((c.row * n + y) * w + c.col * n + x)] =
            cube_direction(CubeFace(f), (fx + 0.5f) / n, (fy + 0.5f) / n);
      }
  }
  return dirs;
}

TEST(EnvLayouts, CrossesAreContinuousAcrossEveryInnerCellBorder) {
  // The convention is right when neighbouring pixels of the cross look in neighbouring
  // directions wherever two cells touch (a wrong face or orientation jumps by ~90 degrees).
  const int n = 16;
  for (bool vertical : {false, true}) {
    const int w = n * (vertical ? 3 : 4), h = n * (vertical ? 4 : 3);
    const auto dirs = cross_directions(n, vertical);
    int borders = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const glm::vec3 a = dirs[std::size_t(y * w + x)];
        if (std::isnan(a.x)) continue;
        for (auto [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}}) {
          if (x + dx >= w || y + dy >= h) continue;
          const glm::vec3 b = dirs[std::size_t((y + dy) * w + x + dx)];
          if (std::isnan(b.x)) continue;
          EXPECT_LT(std::acos(std::min(1.0f, glm::dot(a, b))),
                    3.0f * (std::numbers::pi_v<float> / 2) / n)
              << (vertical ? "vertical" : "horizontal") << " at " << x << "," << y;
          if (dx == 1 ? (x + 1) % n == 0 : (y + 1) % n == 0) ++borders;
        }
      }
    EXPECT_EQ(borders, 5 * n);  // 5 shared cell edges in either cross
  }
}

TEST(EnvLayouts, AllLayoutsOfOneEnvironmentGiveTheSameCube) {
  const int n = 32;
  const CubeMap original = make_cube_map(n, smooth_env);
  const fs::path d = dir_for("layouts");
  ASSERT_TRUE(save_cube_faces(original, d / "sky_*.exr").ok());
  ASSERT_TRUE(save_image(d / "hcross.exr", cross_image(original, false)).ok());
  ASSERT_TRUE(save_image(d / "vcross.exr", cross_image(original, true)).ok());
  // Equirect, 8n x 4n, written from the documented direction formula.
  const int ew = 8 * n, eh = 4 * n;
  std::vector<glm::vec4> eq;
  constexpr float kPi = std::numbers::pi_v<float>;
  for (int y = 0; y < eh; ++y)
    for (int x = 0; x < ew; ++x) {
      const float lon = 2 * kPi * ((x + 0.5f) / ew - 0.5f), lat = kPi * (0.5f - (y + 0.5f) / eh);
      eq.push_back(smooth_env(
          {std::cos(lat) * std::sin(lon), std::sin(lat), -std::cos(lat) * std::cos(lon)}));
    }
  ASSERT_TRUE(save_image(d / "pano.exr", image_of(eq, ew, eh)).ok());

  struct Case {
    fs::path path;
    EnvLayout layout;
    float tolerance;
  };
  const std::vector<Case> cases = {
      {d / "sky_*.exr", EnvLayout::faces, 1e-6f},
      {d / "sky_ny.exr", EnvLayout::faces, 1e-6f},
      {d / "hcross.exr", EnvLayout::horizontal_cross, 1e-6f},
      {d / "vcross.exr", EnvLayout::vertical_cross, 1e-6f},
      {d / "pano.exr", EnvLayout::equirect, 0.01f},
  };
  for (const Case& c : cases) {
    for (EnvLayout layout : {c.layout, EnvLayout::auto_detect}) {
      EnvLoadOptions options;
      options.layout = layout;
      options.face_size = c.layout == EnvLayout::equirect ? n : 0;
      auto cube = load_cube_map(c.path, options);
      ASSERT_TRUE(cube.ok()) << c.path << ": " << cube.error().to_string();
      ASSERT_EQ(cube->size, n) << c.path;
      EXPECT_LE(cube_max_diff(*cube, original), c.tolerance)
          << c.path << " " << env_layout_name(layout);
    }
  }
  // Equirect default face size: width / 4.
  auto pano = load_cube_map(d / "pano.exr");
  ASSERT_TRUE(pano.ok());
  EXPECT_EQ(pano->size, ew / 4);
  // face_size resamples any layout.
  EnvLoadOptions half;
  half.face_size = n / 2;
  auto small = load_cube_map(d / "hcross.exr", half);
  ASSERT_TRUE(small.ok());
  EXPECT_EQ(small->size, n / 2);
  EXPECT_LT(cube_max_diff(*small, make_cube_map(n / 2, smooth_env)), 0.02f);
}

TEST(EnvLayouts, EightBitFacesAndSphereMapImagesLoad) {
  const CubeMap original = coloured_cube(8);
  const fs::path d = dir_for("png");
  ASSERT_TRUE(save_cube_faces(original, d / "c_*.png").ok());
  auto cube = load_cube_map(d / "c_pz.png");
  ASSERT_TRUE(cube.ok()) << cube.error().to_string();
  EXPECT_EQ(cube_max_diff(*cube, original), 0.0f);  // 0 and 1 survive 8 bits

  const SphereMap sphere = sphere_map_from_cube(make_cube_map(32, smooth_env), 64);
  ASSERT_TRUE(save_sphere_map(sphere, d / "ball.exr").ok());
  auto loaded = load_sphere_map(d / "ball.exr");
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  ASSERT_EQ(loaded->size, 64);
  EXPECT_EQ(loaded->texels, sphere.texels);
  // As a cube (auto-detected 1:1): the sphere map's valid part matches the environment.
  auto as_cube = load_cube_map(d / "ball.exr");
  ASSERT_TRUE(as_cube.ok()) << as_cube.error().to_string();
  EXPECT_EQ(as_cube->size, 32);
  EXPECT_LT(max_diff(sample_cube(*as_cube, glm::normalize(glm::vec3(0.3f, 0.2f, 1.0f))),
                     smooth_env(glm::normalize(glm::vec3(0.3f, 0.2f, 1.0f)))),
            0.03f);
  // Saving into a directory names the faces px.exr ... nz.exr.
  ASSERT_TRUE(save_cube_faces(original, d / "dump").ok());
  for (CubeFace f : kFaces)
    EXPECT_TRUE(fs::exists(d / "dump" / (std::string(cube_face_suffix(f)) + ".exr")));
}

// --- 3ds Max (Z-up) ----------------------------------------------------------------------------

TEST(EnvLayouts, ThreeDsMaxFacesConvertToTheYUpOriginal) {
  // Author the 3ds Max images of a Y-up environment by S3's route: a Max direction m is looked
  // up in S3's GL cube at M_rot m (eq. 7), and engine direction e is Max direction M_rot e. So
  // S3's cube holds, along c, the engine environment at M_rot^-2 c = (x, -y, -z); its faces are
  // the Max images by the face table: RIGHT +X, LEFT -X, BACK +Z, FRONT -Z, UP -Y, DOWN +Y.
  const int n = 16;
  const CubeMap original = make_cube_map(n, smooth_env);
  const CubeMap s3 = make_cube_map(n, [&](const glm::vec3& c) {
    return smooth_env({c.x, -c.y, -c.z});
  });
  const fs::path d = dir_for("max");
  const std::array<std::pair<const char*, CubeFace>, 6> table = {{{"right", CubeFace::pos_x},
                                                                  {"left", CubeFace::neg_x},
                                                                  {"back", CubeFace::pos_z},
                                                                  {"front", CubeFace::neg_z},
                                                                  {"up", CubeFace::neg_y},
                                                                  {"down", CubeFace::pos_y}}};
  const std::array<const char*, 6> axis_names = {"px", "nx", "py", "ny", "pz", "nz"};
  for (std::size_t a = 0; a < 6; ++a) {
    const auto& face = s3.faces[std::size_t(table[a].second)];
    ASSERT_TRUE(
        save_image(d / (std::string("word_") + table[a].first + ".exr"), image_of(face, n, n))
            .ok());
    ASSERT_TRUE(
        save_image(d / (std::string("axis_") + axis_names[a] + ".exr"), image_of(face, n, n)).ok());
  }
  EnvLoadOptions max;
  max.z_up_3dsmax = true;
  for (const char* path : {"word_*.exr", "word_front.exr", "axis_*.exr"}) {
    auto cube = load_cube_map(d / path, max);
    ASSERT_TRUE(cube.ok()) << path << ": " << cube.error().to_string();
    EXPECT_LT(cube_max_diff(*cube, original), 1e-6f) << path;
  }
  // Without the option the same files are a different (wrong) environment.
  auto raw = load_cube_map(d / "axis_*.exr");
  ASSERT_TRUE(raw.ok());
  EXPECT_GT(cube_max_diff(*raw, original), 0.5f);

  // Which image lands where: UP is the engine's up, FRONT (-Y in Max) the engine's +Z.
  CubeMap solid;
  solid.size = 4;
  for (std::size_t a = 0; a < 6; ++a) solid.faces[a].assign(16, kFaceColour[a]);
  const CubeMap converted = cube_from_3dsmax(solid);
  EXPECT_EQ(sample_cube(converted, {0, 1, 0}), kFaceColour[4]);   // UP (+Z in Max)
  EXPECT_EQ(sample_cube(converted, {0, -1, 0}), kFaceColour[5]);  // DOWN
  EXPECT_EQ(sample_cube(converted, {0, 0, 1}), kFaceColour[3]);   // FRONT (-Y in Max)
  EXPECT_EQ(sample_cube(converted, {0, 0, -1}), kFaceColour[2]);  // BACK
  EXPECT_EQ(sample_cube(converted, {1, 0, 0}), kFaceColour[0]);   // RIGHT
  EXPECT_EQ(sample_cube(converted, {-1, 0, 0}), kFaceColour[1]);  // LEFT
  EXPECT_EQ(m_rot({1, 2, 3}), glm::vec3(1, -3, 2));
}

// --- errors ------------------------------------------------------------------------------------

void expect_error(const Result<CubeMap>& r, const fs::path& file, const std::string& words) {
  ASSERT_FALSE(r.ok()) << "expected an error about: " << words;
  EXPECT_EQ(r.error().file, file.string());
  EXPECT_NE(r.error().message.find(words), std::string::npos) << r.error().to_string();
}

TEST(EnvLayouts, BadInputGivesClearErrors) {
  const fs::path d = dir_for("errors");
  const CubeMap cube = coloured_cube(8);
  ASSERT_TRUE(save_cube_faces(cube, d / "ok_*.png").ok());

  // Missing face file.
  ASSERT_TRUE(save_cube_faces(cube, d / "gap_*.png").ok());
  fs::remove(d / "gap_ny.png");
  expect_error(load_cube_map(d / "gap_*.png"), d / "gap_*.png",
               "missing face file " + (d / "gap_ny.png").string());
  // Non-square face, mismatched sizes.
  ASSERT_TRUE(save_cube_faces(cube, d / "rect_*.png").ok());
  ASSERT_TRUE(save_image(d / "rect_py.png", image_of(std::vector<glm::vec4>(8 * 6), 8, 6)).ok());
  expect_error(load_cube_map(d / "rect_px.png"), d / "rect_py.png",
               "must be square, this one is 8x6");
  ASSERT_TRUE(save_cube_faces(cube, d / "mix_*.png").ok());
  ASSERT_TRUE(save_image(d / "mix_nz.png", image_of(std::vector<glm::vec4>(16 * 16), 16, 16)).ok());
  expect_error(load_cube_map(d / "mix_*.png"), d / "mix_nz.png",
               "face size 16x16 differs from 8x8");
  // Unreadable image.
  ASSERT_TRUE(save_cube_faces(cube, d / "bad_*.png").ok());
  test::write_text(d / "bad_pz.png", "\x89PNG\r\n\x1a\n not really a png");
  EXPECT_FALSE(load_cube_map(d / "bad_*.png").ok());
  EXPECT_EQ(load_cube_map(d / "bad_*.png").error().file, (d / "bad_pz.png").string());
  // Two stars; a faces layout without a face name.
  expect_error(load_cube_map(d / "ok_*_*.png"), d / "ok_*_*.png", "only one '*'");
  EnvLoadOptions faces;
  faces.layout = EnvLayout::faces;
  expect_error(load_cube_map(d / "whatever.png", faces), d / "whatever.png",
               "must contain one '*'");

  // Wrong aspects.
  const fs::path wide = d / "wide.png", tall = d / "tall.png", odd = d / "odd.png";
  ASSERT_TRUE(save_image(wide, image_of(std::vector<glm::vec4>(16 * 8), 16, 8)).ok());
  ASSERT_TRUE(save_image(tall, image_of(std::vector<glm::vec4>(12 * 16), 12, 16)).ok());
  ASSERT_TRUE(save_image(odd, image_of(std::vector<glm::vec4>(10 * 6), 10, 6)).ok());
  EnvLoadOptions h;
  h.layout = EnvLayout::horizontal_cross;
  expect_error(load_cube_map(wide, h), wide, "a horizontal cross must be 4:3");
  EnvLoadOptions v;
  v.layout = EnvLayout::vertical_cross;
  expect_error(load_cube_map(wide, v), wide, "a vertical cross must be 3:4");
  EnvLoadOptions e;
  e.layout = EnvLayout::equirect;
  expect_error(load_cube_map(tall, e), tall, "must be 2:1");
  EnvLoadOptions s;
  s.layout = EnvLayout::sphere;
  expect_error(load_cube_map(tall, s), tall, "must be square");
  expect_error(load_cube_map(odd), odd, "cannot tell the environment layout of a 10x6 image");
  EnvLoadOptions max;
  max.z_up_3dsmax = true;
  expect_error(load_cube_map(wide, max), wide, "3ds Max");
  auto sphere = load_sphere_map(tall);
  ASSERT_FALSE(sphere.ok());
  EXPECT_NE(sphere.error().message.find("must be square"), std::string::npos);
  // Missing file.
  expect_error(load_cube_map(d / "nothing.hdr"), d / "nothing.hdr", "not found");
  EXPECT_FALSE(load_sphere_map(d / "nothing.hdr").ok());
  // A directory.
  EXPECT_FALSE(load_cube_map(d).ok());
  // The good set still loads.
  EXPECT_TRUE(load_cube_map(d / "ok_*.png").ok());
}

}  // namespace
}  // namespace kaskad

namespace kaskad {
namespace {

/// Mean |difference| (RGB) between each border texel of every face and the texel across the
/// cube edge (found through cube_direction() beyond [0,1] and cube_coord()), and between
/// horizontally adjacent texels inside the faces, for comparison.
std::pair<double, double> seam_and_interior_difference(const CubeMap& cube) {
  const int n = cube.size;
  double seam = 0.0, interior = 0.0;
  int seams = 0, interiors = 0;
  auto rgb_diff = [](const glm::vec4& a, const glm::vec4& b) {
    const glm::vec3 d = glm::abs(glm::vec3(a) - glm::vec3(b));
    return double(d.x + d.y + d.z) / 3.0;
  };
  for (int f = 0; f < 6; ++f) {
    for (int i = 0; i < n; ++i) {
      // The four edges: (x, y) of the border texel and the texel centre one step outside.
      const std::array<std::array<float, 4>, 4> edges = {{
          {0.0f, float(i), -0.5f, i + 0.5f},
          {float(n - 1), float(i), n + 0.5f, i + 0.5f},
          {float(i), 0.0f, i + 0.5f, -0.5f},
          {float(i), float(n - 1), i + 0.5f, n + 0.5f},
      }};
      for (const auto& e : edges) {
        const CubeCoord c = cube_coord(cube_direction(CubeFace(f), e[2] / n, e[3] / n));
        EXPECT_NE(int(c.face), f);
        const int x = std::clamp(int(c.s * n), 0, n - 1), y = std::clamp(int(c.t * n), 0, n - 1);
        seam += rgb_diff(cube.at(CubeFace(f), int(e[0]), int(e[1])), cube.at(c.face, x, y));
        ++seams;
      }
      for (int x = 0; x + 1 < n; x += 7) {
        interior += rgb_diff(cube.at(CubeFace(f), x, i), cube.at(CubeFace(f), x + 1, i));
        ++interiors;
      }
    }
  }
  return {seam / seams, interior / interiors};
}

// A NaN or infinite pixel would spread over the SH sums and the prefiltered radiance: every
// layout refuses it, naming the file and the first such pixel in file order, before any
// resampling (a bilinear lookup could have missed it).
TEST(EnvLayouts, NonFinitePixelsAreErrorsNamingTheFirst) {
  const fs::path d = dir_for("non_finite");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  // Equirect 16x8: a NaN at (5, 3) G, an infinity after it (row 6) that is not the one named.
  std::vector<glm::vec4> pano(16 * 8, glm::vec4(0.5f, 0.5f, 0.5f, 1.0f));
  pano[3 * 16 + 5].g = nan;
  pano[6 * 16 + 9].r = inf;
  ASSERT_TRUE(save_image(d / "pano.exr", image_of(pano, 16, 8)).ok());
  expect_error(load_cube_map(d / "pano.exr"), d / "pano.exr", "pixel (5, 3), channel G, is NaN");
  EnvLoadOptions small;
  small.face_size = 1;  // a 1-texel cube samples 6 directions only, never (5, 3)
  expect_error(load_cube_map(d / "pano.exr", small), d / "pano.exr", "pixel (5, 3), channel G");
  // Horizontal cross 16x12: -Inf at (6, 5) B, in the +Z cell.
  std::vector<glm::vec4> cross(16 * 12, glm::vec4(1.0f));
  cross[5 * 16 + 6].b = -inf;
  ASSERT_TRUE(save_image(d / "cross.exr", image_of(cross, 16, 12)).ok());
  expect_error(load_cube_map(d / "cross.exr"), d / "cross.exr", "pixel (6, 5), channel B, is -Inf");
  // A cross cell nothing reads (the top-left corner) is checked too: the whole file is.
  cross[5 * 16 + 6].b = 1.0f;
  cross[0].a = nan;
  ASSERT_TRUE(save_image(d / "corner.exr", image_of(cross, 16, 12)).ok());
  expect_error(load_cube_map(d / "corner.exr"), d / "corner.exr", "pixel (0, 0), channel A, is NaN");
  // Six faces: +Inf in nz's texel (2, 1), R; the error names that face's file.
  CubeMap cube = coloured_cube(4);
  cube.at(CubeFace::neg_z, 2, 1).r = inf;
  ASSERT_TRUE(save_cube_faces(cube, d / "faces_*.exr").ok());
  expect_error(load_cube_map(d / "faces_*.exr"), d / "faces_nz.exr",
               "pixel (2, 1), channel R, is +Inf");
  // Sphere maps, through load_cube_map and load_sphere_map.
  std::vector<glm::vec4> ball(8 * 8, glm::vec4(0.25f));
  ball[7 * 8 + 7].g = nan;
  ASSERT_TRUE(save_image(d / "ball.exr", image_of(ball, 8, 8)).ok());
  expect_error(load_cube_map(d / "ball.exr"), d / "ball.exr", "pixel (7, 7), channel G, is NaN");
  auto sphere = load_sphere_map(d / "ball.exr");
  ASSERT_FALSE(sphere.ok());
  EXPECT_EQ(sphere.error().file, (d / "ball.exr").string());
  EXPECT_NE(sphere.error().message.find("pixel (7, 7), channel G, is NaN"), std::string::npos)
      << sphere.error().to_string();
  // The largest finite float still loads, clamped to the largest half float (the maps are
  // GL_RGBA16F textures, where it would be infinite), as is a bright sun of 10^5.
  ball[7 * 8 + 7].g = std::numeric_limits<float>::max();
  ball[0].r = -1e5f;
  ASSERT_TRUE(save_image(d / "big.exr", image_of(ball, 8, 8)).ok());
  auto big = load_sphere_map(d / "big.exr");
  ASSERT_TRUE(big.ok()) << big.error().to_string();
  EXPECT_EQ(big->at(7, 7).g, 65504.0f);
  EXPECT_EQ(big->at(0, 0).r, -65504.0f);
  EXPECT_EQ(big->at(3, 3).g, 0.25f);
}

TEST(EnvLayouts, SeamsOfASmoothEnvironmentAreContinuous) {
  const auto [seam, interior] = seam_and_interior_difference(make_cube_map(32, smooth_env));
  EXPECT_LT(seam, 2.0 * interior);
  // A face turned by 90 degrees breaks the seams: the check can fail.
  CubeMap turned = make_cube_map(32, smooth_env);
  auto& face = turned.faces[std::size_t(CubeFace::pos_z)];
  const auto copy = face;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) face[std::size_t(y * 32 + x)] = copy[std::size_t(x * 32 + 31 - y)];
  EXPECT_GT(seam_and_interior_difference(turned).first, 3.0 * interior);
}

TEST(EnvLayouts, ShippedSkyBoxLoadsFromItsFolderWithSeamlessEdges) {
  const fs::path folder = test::content_path("env/cube/SwedishRoyalCastle");
  auto cube = load_cube_map(folder);
  ASSERT_TRUE(cube.ok()) << cube.error().to_string();
  EXPECT_EQ(cube->size, 512);
  auto same = load_cube_map(folder / "nz.jpg");
  ASSERT_TRUE(same.ok());
  EXPECT_EQ(cube_max_diff(*cube, *same), 0.0f);
  // The photos meet at the cube's edges in GL's face convention (a wrongly oriented or placed
  // face would differ by a lot more than neighbouring texels do).
  const auto [seam, interior] = seam_and_interior_difference(*cube);
  EXPECT_LT(seam, 1.5 * interior) << "seam " << seam << " interior " << interior;
  // The sky is above: +Y is brighter than -Y.
  const glm::vec4 up = sample_cube(*cube, {0, 1, 0}), down = sample_cube(*cube, {0, -1, 0});
  EXPECT_GT(up.r + up.g + up.b, down.r + down.g + down.b);
}

TEST(EnvLayouts, ShippedEquirectHdrLoads) {
  auto cube = load_cube_map(test::content_path("env/equirect/venice_sunset_1k.hdr"));
  ASSERT_TRUE(cube.ok()) << cube.error().to_string();
  EXPECT_EQ(cube->size, 256);  // 1024 / 4
  float brightest = 0.0f;
  for (const auto& face : cube->faces)
    for (const glm::vec4& t : face) brightest = std::max(brightest, t.r);
  EXPECT_GT(brightest, 1.0f);  // HDR values survive
  const glm::vec4 up = sample_cube(*cube, {0, 1, 0}), down = sample_cube(*cube, {0, -1, 0});
  EXPECT_GT(up.b, down.b);  // sky above, ground below
}

TEST(EnvLayouts, FolderAndOptionErrors) {
  const fs::path d = dir_for("folder_errors");
  fs::create_directories(d / "empty");
  auto empty = load_cube_map(d / "empty");
  ASSERT_FALSE(empty.ok());
  EXPECT_EQ(empty.error().file, (d / "empty").string());
  EnvLoadOptions big;
  big.face_size = 100000;
  auto too_big = load_cube_map(test::content_path("env/cube/SwedishRoyalCastle"), big);
  ASSERT_FALSE(too_big.ok());
  EXPECT_NE(too_big.error().message.find("face_size must be in [0, 8192]"), std::string::npos);
}

}  // namespace
}  // namespace kaskad
