// Cascaded shadow map maths (runtime/math/cascade_math.h): invariants first (STYLE.md 12). Splits
// cover [near, far] and increase; every slice corner lies inside its cascade's light clip
// volume; casters outside the view are kept; a stable cascade moves in whole texels and keeps its
// size; ComputeNearAndFar matches a brute-force reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "components/shadow_settings.h"
#include "runtime/math/cascade_math.h"

namespace kaskad {
namespace {

constexpr float kPi = 3.14159265358979f;

glm::mat4 pose(const glm::vec3& position, const glm::quat& rotation) {
  return glm::translate(glm::mat4(1.0f), position) * glm::mat4_cast(rotation);
}

/// A camera at `eye` looking at `target` (view -> world, rigid).
glm::mat4 look(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up) {
  return glm::inverse(glm::lookAt(eye, target, up));
}

struct Rng {
  std::mt19937 gen{12345u};
  float uniform(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(gen); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(gen); }
  glm::vec3 unit() {
    std::normal_distribution<float> n;
    glm::vec3 v;
    do v = {n(gen), n(gen), n(gen)};
    while (glm::length(v) < 1e-3f);
    return glm::normalize(v);
  }
  glm::quat rotation() {
    std::normal_distribution<float> n;
    glm::quat q;
    do q = glm::quat(n(gen), n(gen), n(gen), n(gen));
    while (glm::length(q) < 1e-3f);
    return glm::normalize(q);
  }
  glm::vec3 point(float r) { return {uniform(-r, r), uniform(-r, r), uniform(-r, r)}; }
};

// ---- Splits
// ---------------------------------------------------------------------------------------

TEST(CascadeSplits, HandComputedValues) {
  // near 1, far 1000, N = 4; S0 eq. (1): 1 + 999 i / 4; eq. (2): 1000^(i/4); eq. (3) the mean.
  const std::vector<float> u = split_distances(SplitScheme::uniform, 4, 1.0f, 1000.0f, 0.5f);
  const std::vector<float> l = split_distances(SplitScheme::log, 4, 1.0f, 1000.0f, 0.5f);
  const std::vector<float> m = split_distances(SplitScheme::mixed, 4, 1.0f, 1000.0f, 0.5f);
  const float eu[] = {1.0f, 250.75f, 500.5f, 750.25f, 1000.0f};
  const float el[] = {1.0f, 5.6234133f, 31.622777f, 177.82794f, 1000.0f};
  const float em[] = {1.0f, 128.18671f, 266.06139f, 464.03897f, 1000.0f};
  ASSERT_EQ(u.size(), 5u);
  ASSERT_EQ(l.size(), 5u);
  ASSERT_EQ(m.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_FLOAT_EQ(u[i], eu[i]) << i;
    EXPECT_FLOAT_EQ(l[i], el[i]) << i;
    EXPECT_FLOAT_EQ(m[i], em[i]) << i;
  }
  // N = 1 is just [near, far]; N = 2 log is the geometric mean.
  EXPECT_EQ(split_distances(SplitScheme::mixed, 1, 0.1f, 100.0f, 0.5f),
            (std::vector<float>{0.1f, 100.0f}));
  EXPECT_FLOAT_EQ(split_distances(SplitScheme::log, 2, 0.1f, 100.0f, 0.0f)[1], std::sqrt(10.0f));
  // lambda 0.3 with near 0.1, far 100, N = 2: 0.3 sqrt(10) + 0.7 * 50.05.
  EXPECT_FLOAT_EQ(split_distances(SplitScheme::mixed, 2, 0.1f, 100.0f, 0.3f)[1],
                  0.3f * std::sqrt(10.0f) + 0.7f * 50.05f);
}

TEST(CascadeSplits, FollowEquationsCoverRangeAndIncrease) {
  const float ranges[][2] = {{0.1f, 100.0f}, {1.0f, 1000.0f}, {1e-4f, 1e4f}};
  for (const auto& r : ranges)
    for (int n : {1, 2, 4, 8})
      for (float lambda : {0.0f, 0.5f, 1.0f, 0.3f})
        for (SplitScheme s : {SplitScheme::uniform, SplitScheme::log, SplitScheme::mixed}) {
          SCOPED_TRACE(::testing::Message()
                       << "near " << r[0] << " far " << r[1] << " N " << n << " lambda " << lambda
                       << " scheme " << static_cast<int>(s));
          const std::vector<float> d = split_distances(s, n, r[0], r[1], lambda);
          ASSERT_EQ(d.size(), static_cast<size_t>(n) + 1);
          EXPECT_EQ(d.front(), r[0]);  // exact, no drift
          EXPECT_EQ(d.back(), r[1]);
          for (int i = 1; i <= n; ++i) EXPECT_LT(d[i - 1], d[i]) << i;
          for (int i = 0; i <= n; ++i) {
            const double dn = r[0], df = r[1], t = static_cast<double>(i) / n;
            const double uni = dn + (df - dn) * t;                // (1)
            const double lg = dn * std::pow(df / dn, t);          // (2)
            const double mix = lambda * lg + (1 - lambda) * uni;  // (3)
            const double want = s == SplitScheme::uniform ? uni : s == SplitScheme::log ? lg : mix;
            EXPECT_NEAR(d[i], want, 2e-6 * want) << i;
          }
        }
  // lambda = 1 mixed equals log, lambda = 0 mixed equals uniform.
  EXPECT_EQ(split_distances(SplitScheme::mixed, 5, 0.5f, 300.0f, 1.0f),
            split_distances(SplitScheme::log, 5, 0.5f, 300.0f, 0.7f));
  EXPECT_EQ(split_distances(SplitScheme::mixed, 5, 0.5f, 300.0f, 0.0f),
            split_distances(SplitScheme::uniform, 5, 0.5f, 300.0f, 0.7f));
}

TEST(CascadeSplits, StayStrictlyIncreasingWhenFloatsRunShort) {
  // 8 splits in a range only a handful of floats wide.
  const float near = 1.0f;
  const float far = std::nextafter(
      std::nextafter(
          std::nextafter(
              std::nextafter(
                  std::nextafter(
                      std::nextafter(std::nextafter(std::nextafter(near, 2.0f), 2.0f), 2.0f), 2.0f),
                  2.0f),
              2.0f),
          2.0f),
      2.0f);
  const std::vector<float> d = split_distances(SplitScheme::log, 8, near, far, 0.5f);
  for (int i = 1; i <= 8; ++i) EXPECT_LT(d[i - 1], d[i]);
  EXPECT_EQ(d.back(), far);
}

TEST(CascadeSplitsDeathTest, PreconditionsNameTheValue) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(split_distances(SplitScheme::mixed, 4, 0.1f, 100.0f, 1.2f),
               "lambda must be in \\[0, 1\\], was 1.2");
  EXPECT_DEATH(split_distances(SplitScheme::mixed, 9, 0.1f, 100.0f, 0.5f), "was 9");
  EXPECT_DEATH(split_distances(SplitScheme::mixed, 0, 0.1f, 100.0f, 0.5f), "was 0");
  EXPECT_DEATH(split_distances(SplitScheme::log, 4, 0.0f, 100.0f, 0.5f), "near 0");
  EXPECT_DEATH(split_distances(SplitScheme::log, 4, 10.0f, 5.0f, 0.5f), "far 5");
  EXPECT_DEATH(split_distances(SplitScheme::log, 4, 0.1f, INFINITY, 0.5f), "far inf");
  EXPECT_DEATH(split_distances(SplitScheme::log, 8, 1.0f, std::nextafter(1.0f, 2.0f), 0.5f),
               "too close");
}

// ---- Slices
// ---------------------------------------------------------------------------------------

TEST(CascadeSlices, CornersFollowS0Step1) {
  const glm::mat4 cam = glm::translate(glm::mat4(1.0f), glm::vec3(1, 2, 3));
  const float fov = glm::radians(90.0f);  // tan(45 deg) = 1: h = d
  const auto c = slice_corners_world(cam, fov, 2.0f, 1.0f, 4.0f);
  const glm::vec3 o(1, 2, 3);
  const glm::vec3 want[8] = {{-2, 1, -1}, {2, 1, -1}, {2, -1, -1}, {-2, -1, -1},
                             {-8, 4, -4}, {8, 4, -4}, {8, -4, -4}, {-8, -4, -4}};
  for (int j = 0; j < 8; ++j)
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(c[j][a], (o + want[j])[a], 1e-5f) << j << " " << a;
  const auto b = slice_corners_world_ortho(cam, 4.0f, 1.5f, 1.0f, 4.0f);
  EXPECT_NEAR(b[0].x, 1.0f - 3.0f, 1e-5f);
  EXPECT_NEAR(b[0].y, 2.0f + 2.0f, 1e-5f);
  EXPECT_NEAR(b[6].x, 1.0f + 3.0f, 1e-5f);
  EXPECT_NEAR(b[6].y, 2.0f - 2.0f, 1e-5f);
  EXPECT_NEAR(b[6].z, 3.0f - 4.0f, 1e-5f);
}

TEST(CascadeSlices, BoundingSphereIsTightAndShapeOnly) {
  Rng rng;
  for (int trial = 0; trial < 300; ++trial) {
    CameraSlice s;
    s.projection = trial % 3 == 0 ? Projection::orthographic : Projection::perspective;
    s.fov_y_rad = glm::radians(rng.uniform(10.0f, 150.0f));
    s.ortho_height = rng.uniform(0.5f, 50.0f);
    s.aspect = rng.uniform(0.3f, 3.0f);
    s.near = rng.uniform(0.0f, 20.0f);
    s.far = s.near + rng.uniform(0.01f, 200.0f);
    s.camera_world = pose(rng.point(100.0f), rng.rotation());
    const BoundingSphere sphere = slice_bounding_sphere(s);
    float farthest = 0.0f;
    for (const glm::vec3& p : slice_corners_world(s)) {
      const float d = glm::length(p - sphere.center);
      EXPECT_LE(d, sphere.radius * (1.0f + 1e-5f) + 1e-4f) << trial;
      farthest = std::max(farthest, d);
    }
    EXPECT_NEAR(farthest, sphere.radius, 1e-4f * sphere.radius + 1e-4f) << trial;
    // Moving or turning the camera leaves the radius bit-identical.
    CameraSlice moved = s;
    moved.camera_world = pose(rng.point(100.0f), rng.rotation());
    EXPECT_EQ(slice_bounding_sphere(moved).radius, sphere.radius);
  }
}

// ---- Light view
// -----------------------------------------------------------------------------------

TEST(CascadeLight, ViewIsRigidAndLooksAlongTheLightForEveryDirection) {
  std::vector<glm::vec3> dirs = {{0, -1, 0}, {0, 1, 0},      {1, 0, 0}, {-1, 0, 0}, {0, 0, 1},
                                 {0, 0, -1}, {1e-7f, -1, 0}, {1, 1, 1}, {0, -3, 0}};
  Rng rng;
  for (int i = 0; i < 100; ++i) dirs.push_back(rng.unit());
  for (const glm::vec3& d : dirs) {
    const glm::vec3 origin(3, -4, 5);
    const glm::mat4 v = light_view_matrix(d, origin);
    EXPECT_TRUE(validate_transform(v).empty());
    EXPECT_NEAR(glm::determinant(v), 1.0f, 1e-5f);
    // The origin maps to 0, a point further along the light to -z (depth grows along the light).
    const glm::vec3 o = glm::vec3(v * glm::vec4(origin, 1.0f));
    EXPECT_NEAR(glm::length(o), 0.0f, 1e-5f);
    const glm::vec3 a = glm::vec3(v * glm::vec4(origin + 2.0f * glm::normalize(d), 1.0f));
    EXPECT_NEAR(a.x, 0.0f, 1e-5f);
    EXPECT_NEAR(a.y, 0.0f, 1e-5f);
    EXPECT_NEAR(a.z, -2.0f, 1e-5f);
  }
}

// ---- Fit: every slice corner inside the light clip volume
// -----------------------------------------

struct CameraSetup {
  glm::mat4 world{1.0f};
  Projection projection = Projection::perspective;
  float fov_y_rad = glm::radians(60.0f);
  float ortho_height = 10.0f;
  float aspect = 1.5f;
  float near = 0.1f;
  float far = 100.0f;

  CameraSlice slice(float d0, float d1) const {
    CameraSlice s;
    s.camera_world = world;
    s.projection = projection;
    s.fov_y_rad = fov_y_rad;
    s.ortho_height = ortho_height;
    s.aspect = aspect;
    s.near = d0;
    s.far = d1;
    return s;
  }
};

/// Max over the clip coordinates of `p` of (|clip| - 1) / tolerance, where the tolerance is the
/// float evaluation error of view_proj * p (bounded by the sum of the magnitudes of its terms)
/// plus 1e-5. <= 1 means inside [-1, 1]^3 up to float resolution.
double outside_ratio(const glm::mat4& vp, const glm::vec3& p) {
  double worst = -1e9;
  for (int r = 0; r < 3; ++r) {
    double value = vp[3][r], magnitude = std::abs(vp[3][r]);
    for (int j = 0; j < 3; ++j) {
      value += static_cast<double>(vp[j][r]) * p[j];
      magnitude += std::abs(static_cast<double>(vp[j][r]) * p[j]);
    }
    const double tol = 1e-5 + 16.0 * FLT_EPSILON * magnitude;
    worst = std::max(worst, (std::abs(value) - 1.0) / tol);
  }
  return worst;
}

void expect_corners_inside(const CascadeFit& fit, const std::array<glm::vec3, 8>& corners,
                           const char* what) {
  ASSERT_TRUE(validate_transform(fit.view).empty()) << what;
  ASSERT_TRUE(validate_transform(fit.proj).empty()) << what;
  const glm::mat4 vp = fit.view_proj();
  for (int j = 0; j < 8; ++j) {
    const glm::vec4 clip = vp * glm::vec4(corners[j], 1.0f);
    EXPECT_LE(outside_ratio(vp, corners[j]), 1.0)
        << what << ": corner " << j << " clip " << clip.x << " " << clip.y << " " << clip.z;
  }
}

/// Fits every cascade of `cam` in every mode and checks the corners.
void check_all_cascades(const CameraSetup& cam, const LightFrame& light, SplitScheme scheme,
                        int count, float lambda, const ShadowGeometry& geometry,
                        int map_size = 1024) {
  const std::vector<float> d = split_distances(scheme, count, cam.near, cam.far, lambda);
  for (int i = 0; i < count; ++i) {
    SCOPED_TRACE(::testing::Message()
                 << "cascade " << i << " [" << d[i] << ", " << d[i + 1] << "]");
    const CameraSlice s = cam.slice(d[i], d[i + 1]);
    const auto corners = slice_corners_world(s);
    CascadeFitOptions o;
    o.map_size = map_size;
    o.mode = FitMode::stable;
    expect_corners_inside(fit_cascade(s, light, o), corners, "stable");
    expect_corners_inside(fit_cascade(s, light, o, geometry), corners, "stable+geometry");
    o.mode = FitMode::crop;
    expect_corners_inside(fit_cascade(s, light, o), corners, "crop");
    expect_corners_inside(fit_cascade(s, light, o, geometry), corners, "crop+geometry");
    o.beam_radius = 7.0f;
    expect_corners_inside(fit_cascade(s, light, o, geometry), corners, "crop beam");
  }
}

TEST(CascadeFit, SliceCornersInsideLightClipVolumeRandom) {
  Rng rng;
  const SplitScheme schemes[] = {SplitScheme::uniform, SplitScheme::log, SplitScheme::mixed};
  for (int trial = 0; trial < 300; ++trial) {
    SCOPED_TRACE(::testing::Message() << "trial " << trial);
    CameraSetup cam;
    cam.world = pose(rng.point(60.0f), rng.rotation());
    cam.projection = trial % 5 == 0 ? Projection::orthographic : Projection::perspective;
    cam.fov_y_rad = glm::radians(rng.uniform(15.0f, 120.0f));
    cam.ortho_height = rng.uniform(1.0f, 40.0f);
    cam.aspect = rng.uniform(0.4f, 2.5f);
    cam.near = rng.uniform(0.01f, 2.0f);
    cam.far = cam.near * rng.uniform(5.0f, 3000.0f);
    LightFrame light{rng.unit(), rng.point(50.0f)};
    // Random geometry: a scene box, boxes as casters and receivers.
    std::vector<Aabb> objects;
    Aabb scene;
    for (int k = 0; k < 6; ++k) {
      const glm::vec3 c = rng.point(80.0f);
      objects.push_back(Aabb::from_corners(c, c + glm::vec3(rng.uniform(0.1f, 20.0f), rng.uniform(0.1f, 20.0f),
                                             rng.uniform(0.1f, 20.0f))));
      scene.expand(objects.back());
    }
    const ShadowGeometry geometry{scene, objects, objects};
    check_all_cascades(cam, light, schemes[trial % 3], rng.integer(1, 8), rng.uniform(0.0f, 1.0f),
                       geometry);
    if (HasFailure()) return;
  }
}

TEST(CascadeFit, SliceCornersInsideLightClipVolumeDegenerate) {
  const glm::vec3 eye(3, 2, 1);
  const glm::vec3 forward = glm::normalize(glm::vec3(0.3f, -0.2f, -1.0f));
  const glm::vec3 up_hint(0, 1, 0);
  CameraSetup cam;
  cam.world = look(eye, eye + forward, up_hint);
  const glm::vec3 cam_up = glm::vec3(cam.world[1]);
  const Aabb ground = Aabb::from_corners({-100, -1, -100}, {100, 0, 100});
  const std::vector<Aabb> objects = {ground, Aabb::from_corners({0, 0, -10}, {2, 5, -8})};
  const ShadowGeometry geometry{ground, objects, objects};
  struct Case {
    const char* name;
    glm::mat4 camera;
    glm::vec3 light;
  };
  const Case cases[] = {
      {"light straight down", cam.world, {0, -1, 0}},
      {"light straight up", cam.world, {0, 1, 0}},
      {"light along the view", cam.world, forward},
      {"light against the view", cam.world, -forward},
      {"light along the camera up", cam.world, cam_up},
      {"light against the camera up", cam.world, -cam_up},
      {"camera and light straight down",
       look(eye, eye - glm::vec3(0, 1, 0), {0, 0, -1}),
       {0, -1, 0}},
      {"light along x", cam.world, {1, 0, 0}},
      {"light along z", cam.world, {0, 0, 1}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    CameraSetup setup = cam;
    setup.world = c.camera;
    for (auto [near, far] : {std::pair{0.1f, 100.0f}, std::pair{1e-4f, 1e4f}})
      for (int n : {1, 4, 8})
        for (SplitScheme s : {SplitScheme::uniform, SplitScheme::log, SplitScheme::mixed}) {
          setup.near = near;
          setup.far = far;
          check_all_cascades(setup, LightFrame{c.light, {0, 50, 0}}, s, n, 0.5f, geometry);
          setup.projection = Projection::orthographic;
          check_all_cascades(setup, LightFrame{c.light, {0, 50, 0}}, s, n, 0.5f, geometry);
          setup.projection = Projection::perspective;
        }
  }
}

TEST(CascadeFit, CropIsTightAndEqualsSlicesLightSpaceBox) {
  Rng rng;
  for (int trial = 0; trial < 100; ++trial) {
    CameraSetup cam;
    cam.world = pose(rng.point(30.0f), rng.rotation());
    const CameraSlice s = cam.slice(rng.uniform(0.1f, 10.0f), rng.uniform(11.0f, 60.0f));
    const LightFrame light{rng.unit(), rng.point(20.0f)};
    CascadeFitOptions o;
    o.mode = FitMode::crop;
    o.beam_radius = trial % 2 ? 0.0f : 25.0f;  // R does not change an unclipped crop
    const CascadeFit fit = fit_cascade(s, light, o);
    glm::vec2 lo(1e9f), hi(-1e9f);
    for (const glm::vec3& p : slice_corners_world(s)) {
      const glm::vec4 clip = fit.view_proj() * glm::vec4(p, 1.0f);
      lo = glm::min(lo, glm::vec2(clip));
      hi = glm::max(hi, glm::vec2(clip));
    }
    for (int a = 0; a < 2; ++a) {
      EXPECT_NEAR(lo[a], -1.0f, 1e-4f) << trial;
      EXPECT_NEAR(hi[a], 1.0f, 1e-4f) << trial;
    }
    // ortho_min/max are the same rectangle in light-view metres.
    const float w = fit.ortho_max.x - fit.ortho_min.x, h = fit.ortho_max.y - fit.ortho_min.y;
    EXPECT_NEAR(fit.world_units_per_texel, std::max(w, h) / o.map_size, 1e-6f);
    EXPECT_NEAR(fit.proj[0][0] * fit.proj[0][0] * w * w / 4.0f, 1.0f, 1e-4f);  // |2/w|
    EXPECT_FALSE(fit.empty);
  }
}

TEST(CascadeFit, CropClippedToTheBeam) {
  CameraSetup cam;
  cam.world = look({0, 10, 20}, {0, 0, -10}, {0, 1, 0});
  const CameraSlice s = cam.slice(5.0f, 60.0f);
  const LightFrame light{{0, -1, 0}, {0, 100, 0}};  // beam axis: the world y axis
  CascadeFitOptions o;
  o.mode = FitMode::crop;
  o.beam_radius = 4.0f;
  o.clip_to_light_bounds = true;
  const CascadeFit fit = fit_cascade(s, light, o);
  EXPECT_FALSE(fit.empty);
  EXPECT_GE(fit.ortho_min.x, -4.0f - 1e-4f);
  EXPECT_GE(fit.ortho_min.y, -4.0f - 1e-4f);
  EXPECT_LE(fit.ortho_max.x, 4.0f + 1e-4f);
  EXPECT_LE(fit.ortho_max.y, 4.0f + 1e-4f);
  // A point of the slice on the beam axis is inside.
  const glm::vec4 clip = fit.view_proj() * glm::vec4(0, 0, 0, 1);
  EXPECT_LE(std::abs(clip.x), 1.0f);
  EXPECT_LE(std::abs(clip.y), 1.0f);
  // The slice far away from the beam: flagged empty, matrices still finite.
  LightFrame away = light;
  away.origin = {500, 100, 0};
  const CascadeFit none = fit_cascade(s, away, o);
  EXPECT_TRUE(none.empty);
  EXPECT_TRUE(validate_transform(none.view_proj()).empty());
}

TEST(CascadeFit, CasterOutsideTheViewIsPulledIntoTheDepthRange) {
  // Camera looking horizontally along -z; sun straight down. A caster high above the slice is
  // outside the view frustum but shadows it.
  CameraSetup cam;
  cam.world = look({0, 1, 0}, {0, 1, -1}, {0, 1, 0});
  cam.fov_y_rad = glm::radians(40.0f);
  const CameraSlice s = cam.slice(10.0f, 20.0f);
  const Aabb caster = Aabb::from_corners({-1, 40, -16}, {1, 42, -14});
  const Aabb ground = Aabb::from_corners({-50, -1, -50}, {50, 0, 50});
  for (const glm::vec3& p : slice_corners_world(s)) ASSERT_LT(p.y, 40.0f);  // outside the view
  const LightFrame light{{0, -1, 0.05f}, {0, 100, 0}};
  const std::vector<Aabb> casters = {caster, ground};
  const std::vector<Aabb> receivers = {ground};
  Aabb scene = ground;
  scene.expand(caster);
  for (FitMode mode : {FitMode::crop, FitMode::stable})
    for (DepthFit depth : {DepthFit::enclose_slice, DepthFit::tight})
      for (int source = 0; source < 2; ++source) {
        SCOPED_TRACE(::testing::Message() << "mode " << static_cast<int>(mode) << " depth "
                                          << static_cast<int>(depth) << " source " << source);
        CascadeFitOptions o;
        o.mode = mode;
        o.depth = depth;
        const ShadowGeometry geometry = source == 0 ? ShadowGeometry{Aabb{}, casters, receivers}
                                                    : ShadowGeometry{scene, {}, {}};
        const CascadeFit fit = fit_cascade(s, light, o, geometry);
        EXPECT_FALSE(fit.empty);
        const glm::mat4 vp = fit.view_proj();
        for (int i = 0; i < 8; ++i) {
          const glm::vec3 c{(i & 1) ? caster.max.x : caster.min.x,
                            (i & 2) ? caster.max.y : caster.min.y,
                            (i & 4) ? caster.max.z : caster.min.z};
          const glm::vec4 clip = vp * glm::vec4(c, 1.0f);
          EXPECT_GE(clip.z, -1.0f - 1e-5f) << "caster corner " << i;
          EXPECT_LE(clip.z, 1.0f + 1e-5f) << "caster corner " << i;
        }
        if (depth == DepthFit::enclose_slice)
          expect_corners_inside(fit, slice_corners_world(s), "");
      }
  // Without geometry the caster would be clipped: the pull-back is what keeps it.
  const CascadeFit bare = fit_cascade(s, light, CascadeFitOptions{});
  const glm::vec4 clip = bare.view_proj() * glm::vec4(0, 41, -15, 1);
  EXPECT_LT(clip.z, -1.0f);
}

TEST(CascadeFit, TightDepthIsTighterAndEmptyWithoutReceivers) {
  CameraSetup cam;
  cam.world = look({0, 30, 0}, {0, 0, -40}, {0, 1, 0});
  const CameraSlice s = cam.slice(10.0f, 50.0f);
  const LightFrame light{glm::normalize(glm::vec3(0.2f, -1, 0.1f)), {0, 100, 0}};
  const Aabb ground = Aabb::from_corners({-200, -1, -200}, {200, 0, 200});
  const std::vector<Aabb> objects = {ground};
  CascadeFitOptions o;
  const CascadeFit loose = fit_cascade(s, light, o, {ground, objects, objects});
  o.depth = DepthFit::tight;
  const CascadeFit tight = fit_cascade(s, light, o, {ground, objects, objects});
  EXPECT_LT(tight.far - tight.near, loose.far - loose.near);
  EXPECT_FALSE(tight.empty);
  // The ground inside the map's rectangle is within the tight range.
  const NearFar g = compute_near_far(tight.view, ground, tight.ortho_min.x, tight.ortho_max.x,
                                     tight.ortho_min.y, tight.ortho_max.y);
  EXPECT_LE(tight.near, g.near);
  EXPECT_GE(tight.far, g.far);
  // Only a caster, nothing receives: empty.
  const std::vector<Aabb> casters = {Aabb::from_corners({0, 5, -20}, {1, 6, -19})};
  EXPECT_TRUE(fit_cascade(s, light, o, {Aabb{}, casters, {}}).empty);
  // Receivers far behind the slice only: empty too.
  const std::vector<Aabb> far_away = {Aabb::from_corners({0, -500, 0}, {1, -499, 1})};
  EXPECT_TRUE(fit_cascade(s, light, o, {Aabb{}, far_away, far_away}).empty);
}

// ---- Stable fit: texel snapping and constant size
// -------------------------------------------------

TEST(CascadeStable, SubTexelCameraMotionMovesTheMapInWholeTexels) {
  Rng rng;
  CameraSetup cam;
  const glm::quat rot = rng.rotation();
  const glm::vec3 start(4.0f, 3.0f, -2.0f);
  const LightFrame light{glm::normalize(glm::vec3(-0.4f, -0.8f, 0.45f)), {0, 0, 0}};
  CascadeFitOptions o;
  o.mode = FitMode::stable;
  o.map_size = 1024;
  cam.world = pose(start, rot);
  const CascadeFit first = fit_cascade(cam.slice(2.0f, 20.0f), light, o);
  const float u = first.world_units_per_texel;
  const glm::vec2 width = first.ortho_max - first.ortho_min;
  EXPECT_NEAR(width.x, o.map_size * u, 1e-5f * width.x);
  // A fixed world point's position inside its texel (the sub-texel phase) must not change.
  const glm::vec3 probe(5.0f, 1.0f, -10.0f);
  auto phase = [&](const CascadeFit& f) {
    const glm::vec4 clip = f.view_proj() * glm::vec4(probe, 1.0f);
    const glm::vec2 texel = (glm::vec2(clip) * 0.5f + 0.5f) * static_cast<float>(o.map_size);
    return texel - glm::floor(texel);
  };
  const glm::vec2 phase0 = phase(first);
  const glm::vec3 step = rng.unit() * (u / 7.0f);
  for (int i = 1; i <= 200; ++i) {
    cam.world = pose(start + static_cast<float>(i) * step, rot);
    const CascadeFit fit = fit_cascade(cam.slice(2.0f, 20.0f), light, o);
    EXPECT_EQ(fit.world_units_per_texel, u);
    for (int a = 0; a < 2; ++a) {
      const float t = fit.ortho_min[a] / u;
      EXPECT_NEAR(t, std::round(t), 1e-3f) << i << " axis " << a;
      EXPECT_NEAR(fit.ortho_max[a] - fit.ortho_min[a], width[a], 1e-5f * width[a]) << i;
      // Wrap-aware phase comparison.
      const float dp = std::abs(phase(fit)[a] - phase0[a]);
      EXPECT_LT(std::min(dp, 1.0f - dp), 2e-2f) << i << " axis " << a;
    }
  }
}

// The depth range is snapped to whole steps of r / 2 and holds the slice's sphere: a camera moving
// a little at a time keeps it (to the bit) on most fits, and then the matrix differs from the
// fit before only by a whole-texel x/y translation, which is what lets the renderer scroll a
// layer (ShadowMapPass). Fails if the range follows the camera continuously.
TEST(CascadeStable, SmallCameraMovesKeepTheDepthRangeAndMoveByWholeTexels) {
  Rng rng;
  CameraSetup cam;
  const glm::quat rot = rng.rotation();
  const LightFrame light{glm::normalize(glm::vec3(-0.4f, -0.8f, 0.45f)), {0, 0, 0}};
  CascadeFitOptions o;
  o.mode = FitMode::stable;
  o.map_size = 1024;
  const glm::vec3 step = rng.unit() * 0.01f;  // 1 cm a fit, in a random direction
  CascadeFit before;
  int kept = 0, moves = 0;
  for (int i = 0; i <= 300; ++i) {
    cam.world = pose(glm::vec3(4.0f, 3.0f, -2.0f) + float(i) * step, rot);
    const CameraSlice slice = cam.slice(2.0f, 20.0f);
    const CascadeFit fit = fit_cascade(slice, light, o);
    // The range holds the slice's corners (depth along the light).
    for (const glm::vec3& c : slice_corners_world(slice)) {
      const float z = -(fit.view * glm::vec4(c, 1.0f)).z;
      EXPECT_LE(fit.near, z + 1e-4f) << i;
      EXPECT_GE(fit.far, z - 1e-4f) << i;
    }
    if (i > 0) {
      ++moves;
      if (fit.near == before.near && fit.far == before.far) {
        ++kept;
        const glm::mat4 a = before.view_proj(), b = fit.view_proj();
        for (int col = 0; col < 3; ++col)
          for (int row = 0; row < 4; ++row) EXPECT_EQ(a[col][row], b[col][row]) << i;
        EXPECT_EQ(a[3][2], b[3][2]) << i;
        for (int axis = 0; axis < 2; ++axis) {
          const float texels = (b[3][axis] - a[3][axis]) * 0.5f * float(o.map_size);
          EXPECT_NEAR(texels, std::round(texels), 1e-2f) << i << " axis " << axis;
        }
      }
    }
    before = fit;
  }
  EXPECT_GT(kept, moves * 9 / 10);
}

TEST(CascadeStable, RotatingTheCameraKeepsTheSize) {
  Rng rng;
  CameraSetup cam;
  const LightFrame light{glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f)), {10, 50, 0}};
  for (Projection p : {Projection::perspective, Projection::orthographic}) {
    cam.projection = p;
    CascadeFitOptions o;
    o.mode = FitMode::stable;
    cam.world = pose({1, 2, 3}, rng.rotation());
    const CascadeFit first = fit_cascade(cam.slice(5.0f, 40.0f), light, o);
    const glm::vec2 size = first.ortho_max - first.ortho_min;
    for (int i = 0; i < 100; ++i) {
      cam.world = pose({1, 2, 3}, rng.rotation());
      const CascadeFit fit = fit_cascade(cam.slice(5.0f, 40.0f), light, o);
      EXPECT_EQ(fit.world_units_per_texel, first.world_units_per_texel);
      const glm::vec2 s = fit.ortho_max - fit.ortho_min;
      EXPECT_NEAR(s.x, size.x, 1e-5f * size.x);
      EXPECT_NEAR(s.y, size.y, 1e-5f * size.y);
      EXPECT_NEAR(size.x, size.y, 1e-5f * size.x);
      // The unpadded depth span is 2r: constant as well (no geometry given).
      EXPECT_NEAR(fit.far - fit.near, first.far - first.near, 1e-4f * (first.far - first.near));
    }
  }
}

TEST(CascadeStable, TexelSizeLeavesOneSpareTexel) {
  CameraSetup cam;
  const CameraSlice s = cam.slice(1.0f, 30.0f);
  const BoundingSphere sphere = slice_bounding_sphere(s);
  CascadeFitOptions o;
  o.map_size = 512;
  const CascadeFit fit = fit_cascade(s, LightFrame{}, o);
  EXPECT_NEAR(fit.world_units_per_texel, 2.0f * sphere.radius / 511.0f, 1e-6f * sphere.radius);
  EXPECT_NEAR(fit.ortho_max.x - fit.ortho_min.x, 2.0f * sphere.radius + fit.world_units_per_texel,
              1e-4f);
}

// ---- ComputeNearAndFar against brute force
// --------------------------------------------------------

TEST(CascadeNearFar, MatchesBruteForceSurfaceSampling) {
  Rng rng;
  int non_empty = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const glm::vec3 lo = rng.point(20.0f);
    const Aabb b = Aabb::from_corners(lo, lo + glm::vec3(rng.uniform(0.5f, 10.0f), rng.uniform(0.5f, 10.0f),
                                          rng.uniform(0.0f, 10.0f)));  // may be flat
    const glm::vec3 dir = trial % 10 == 0 ? glm::vec3(0, -1, 0) : rng.unit();
    const glm::mat4 v = light_view_matrix(dir, rng.point(30.0f));
    // A rectangle around part of the box's light-space footprint.
    const Aabb ls = b.transformed(v);
    const float ex = ls.max.x - ls.min.x, ey = ls.max.y - ls.min.y;
    float x0 = rng.uniform(ls.min.x - 0.3f * ex, ls.max.x), x1 = x0 + rng.uniform(0.2f, 1.0f) * ex;
    float y0 = rng.uniform(ls.min.y - 0.3f * ey, ls.max.y), y1 = y0 + rng.uniform(0.2f, 1.0f) * ey;
    const NearFar nf = compute_near_far(v, b, x0, x1, y0, y1);
    // Reference: dense samples on the 6 faces (and the 12 edges), kept when inside the rectangle.
    const int n = 120;
    double bn = 1e30, bf = -1e30;
    auto sample = [&](const glm::vec3& p) {
      const glm::vec3 q = glm::vec3(v * glm::vec4(p, 1.0f));
      if (q.x < x0 || q.x > x1 || q.y < y0 || q.y > y1) return;
      bn = std::min(bn, -static_cast<double>(q.z));
      bf = std::max(bf, -static_cast<double>(q.z));
    };
    const glm::vec3 e = b.extent();
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side)
        for (int i = 0; i <= n; ++i)
          for (int j = 0; j <= n; ++j) {
            glm::vec3 p = b.min;
            p[axis] += side * e[axis];
            p[(axis + 1) % 3] += e[(axis + 1) % 3] * i / n;
            p[(axis + 2) % 3] += e[(axis + 2) % 3] * j / n;
            sample(p);
          }
    const float spacing = glm::length(e) / n;
    if (bn > bf) {  // no sample inside: the exact answer is empty or a sliver
      if (!nf.empty) {
        EXPECT_LT(nf.far - nf.near, 2.0f * glm::length(e)) << trial;
      }
      continue;
    }
    ++non_empty;
    ASSERT_FALSE(nf.empty) << trial;
    // Exact range contains every sample, and no sample is far from its ends.
    EXPECT_LE(nf.near, bn + 1e-4) << trial;
    EXPECT_GE(nf.far, bf - 1e-4) << trial;
    EXPECT_NEAR(nf.near, bn, 2.0f * spacing + 1e-4f) << trial;
    EXPECT_NEAR(nf.far, bf, 2.0f * spacing + 1e-4f) << trial;
  }
  EXPECT_GT(non_empty, 40);
}

// The depths of the part of `b` inside the light-space prism over the rectangle, in double:
// every face clipped by the four side planes (the reference the tighten test compares with).
std::pair<double, double> clipped_depths(const glm::dmat4& v, const Aabb& b, double x0, double x1,
                                         double y0, double y1) {
  double near = 1e300, far = -1e300;
  const glm::dvec3 lo(b.min), hi(b.max);
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      std::vector<glm::dvec3> poly;
      for (int k = 0; k < 4; ++k) {
        glm::dvec3 p;
        p[axis] = side ? hi[axis] : lo[axis];
        p[(axis + 1) % 3] = (k == 1 || k == 2) ? hi[(axis + 1) % 3] : lo[(axis + 1) % 3];
        p[(axis + 2) % 3] = k >= 2 ? hi[(axis + 2) % 3] : lo[(axis + 2) % 3];
        poly.push_back(glm::dvec3(v * glm::dvec4(p, 1.0)));
      }
      // Keep a * (coordinate - bound) >= 0: x >= x0, x <= x1, y >= y0, y <= y1.
      const std::array<std::tuple<int, double, double>, 4> planes = {
          std::tuple{0, x0, 1.0}, {0, x1, -1.0}, {1, y0, 1.0}, {1, y1, -1.0}};
      for (const auto& [c, bound, a] : planes) {
        std::vector<glm::dvec3> next;
        for (std::size_t k = 0; k < poly.size(); ++k) {
          const glm::dvec3 p = poly[k], q = poly[(k + 1) % poly.size()];
          const double dp = a * (p[c] - bound), dq = a * (q[c] - bound);
          if (dp >= 0.0) next.push_back(p);
          if ((dp >= 0.0) != (dq >= 0.0)) next.push_back(p + (q - p) * (dp / (dp - dq)));
        }
        poly = next;
      }
      for (const glm::dvec3& p : poly) {
        near = std::min(near, -p.z);
        far = std::max(far, -p.z);
      }
    }
  return {near, far};
}

// Fields of boxes under a tilted light, the rectangle over part of a field: boxes well inside
// it, outside it and across its edges, near the origin and 4 km from it. tighten_near_far()
// follows its rule (the farthest and nearest receiver point in the slice, the near end pulled to
// casters in front of that far) with every box's part in the rectangle clipped exactly. Fields
// of 1-3 boxes make every box count; in the large fields the boxes come in the order that moves
// an end a little at a time (receivers by their near or far end, casters nearest last), so
// that passing over any box that moves an end shows.
TEST(CascadeNearFar, TightenFollowsItsRuleOnFieldsOfBoxes) {
  Rng rng;
  int pulled = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const glm::vec3 origin = trial % 2 ? glm::vec3(0.0f) : rng.point(4000.0f);
    const int count = trial < 150 ? rng.integer(1, 3) : 300;
    const float spread = count < 10 ? 3.0f : 60.0f;
    std::vector<Aabb> boxes;
    for (int i = 0; i < count; ++i) {
      const glm::vec3 lo =
          origin + glm::vec3(rng.uniform(-spread, spread), rng.uniform(0, 8), rng.uniform(-spread, spread));
      boxes.push_back(Aabb::from_corners(
          lo, lo + glm::vec3(rng.uniform(0.2f, 3), rng.uniform(0.2f, 3), rng.uniform(0.2f, 3))));
    }
    glm::vec3 dir = rng.unit();
    if (dir.y > -0.2f) dir.y = -0.2f - std::abs(dir.y);
    dir = glm::normalize(dir);
    const glm::mat4 v = light_view_matrix(dir, origin - 200.0f * dir);
    const glm::vec3 c = glm::vec3(v * glm::vec4(origin, 1.0f));
    // Around part of the field, or for the small ones, around part of the first box's footprint.
    float x0 = c.x + rng.uniform(-40, 0), x1 = x0 + rng.uniform(15, 50);
    float y0 = c.y + rng.uniform(-40, 0), y1 = y0 + rng.uniform(15, 50);
    if (count < 10) {
      const Aabb ls = boxes[0].transformed(v);
      const float ex = ls.max.x - ls.min.x, ey = ls.max.y - ls.min.y;
      x0 = rng.uniform(ls.min.x - 0.3f * ex, ls.max.x);
      x1 = x0 + rng.uniform(0.2f, 1.5f) * ex;
      y0 = rng.uniform(ls.min.y - 0.3f * ey, ls.max.y);
      y1 = y0 + rng.uniform(0.2f, 1.5f) * ey;
    }
    // Every fourth slice cuts the field's depths (the receivers clamped to it); the others hold them.
    const bool cut = trial % 4 == 0;
    const float slice_near = cut ? 185.0f + rng.uniform(0, 10) : 100.0f;
    const float slice_far = cut ? slice_near + rng.uniform(5, 30) : 300.0f;
    const glm::dmat4 vd(v);
    struct Clipped {
      Aabb box;
      double near, far;
    };
    std::vector<Clipped> rs, cs;
    for (int i = 0; i < count; ++i) {
      const auto [n, f] = clipped_depths(vd, boxes[std::size_t(i)], x0, x1, y0, y1);
      if (i % 3 != 1 || count < 10) rs.push_back({boxes[std::size_t(i)], n, f});
      if (i % 2 == 0 || count < 10) cs.push_back({boxes[std::size_t(i)], n, f});
    }
    std::sort(rs.begin(), rs.end(), [&](const Clipped& a, const Clipped& b) {
      return trial % 2 ? a.near > b.near : a.far < b.far;
    });
    std::sort(cs.begin(), cs.end(), [](const Clipped& a, const Clipped& b) { return a.near > b.near; });
    std::vector<Aabb> receivers, casters;
    double near = 1e300, far = -1e300;
    for (const Clipped& r : rs) {
      receivers.push_back(r.box);
      if (r.near > r.far || r.far < slice_near || r.near > slice_far) continue;
      near = std::min(near, std::max(r.near, double(slice_near)));
      far = std::max(far, std::min(r.far, double(slice_far)));
    }
    const double receivers_near = near;
    for (const Clipped& k : cs) {
      casters.push_back(k.box);
      if (k.near <= k.far && k.near < far) near = std::min(near, k.near);
    }
    const NearFar nf = tighten_near_far(v, casters, receivers, x0, x1, y0, y1, slice_near, slice_far);
    if (far < -1e299) {
      EXPECT_TRUE(nf.empty) << trial;
      continue;
    }
    pulled += near < receivers_near;
    ASSERT_FALSE(nf.empty) << trial;
    EXPECT_NEAR(nf.near, near, 1e-4) << trial;
    EXPECT_NEAR(nf.far, far, 1e-4) << trial;
  }
  EXPECT_GT(pulled, 10);  // casters in front of the receivers were found
}

TEST(CascadeNearFar, EmptyWhenTheRectangleMissesTheBox) {
  const glm::mat4 v = light_view_matrix({0, -1, 0}, {0, 10, 0});
  const Aabb b = Aabb::from_corners({-1, 0, -1}, {1, 1, 1});
  EXPECT_TRUE(compute_near_far(v, b, 5, 6, 5, 6).empty);
  EXPECT_TRUE(compute_near_far(v, Aabb{}, -1, 1, -1, 1).empty);
  const NearFar nf = compute_near_far(v, b, -0.5f, 0.5f, -0.5f, 0.5f);
  ASSERT_FALSE(nf.empty);
  EXPECT_NEAR(nf.near, 9.0f, 1e-5f);  // top face y = 1, light at y = 10
  EXPECT_NEAR(nf.far, 10.0f, 1e-5f);
}

TEST(CascadeNearFar, TightenUsesReceiversInTheSliceAndCastersInFront) {
  const glm::mat4 v = light_view_matrix({0, -1, 0}, {0, 100, 0});       // depth = 100 - y
  const std::vector<Aabb> receivers = {Aabb::from_corners({-5, 0, -5}, {5, 1, 5})};    // depths 99..100
  const std::vector<Aabb> casters = {Aabb::from_corners({-1, 50, -1}, {1, 51, 1}),     // 49..50, in front
                                     Aabb::from_corners({-1, -20, -1}, {1, -19, 1}),   // behind the receiver
                                     Aabb::from_corners({30, 60, 30}, {31, 61, 31})};  // outside the rectangle
  const NearFar nf = tighten_near_far(v, casters, receivers, -10, 10, -10, 10, 90.0f, 110.0f);
  ASSERT_FALSE(nf.empty);
  EXPECT_NEAR(nf.near, 49.0f, 1e-4f);
  EXPECT_NEAR(nf.far, 100.0f, 1e-4f);
  // The receiver clamped to the slice's depth range.
  const NearFar clamped = tighten_near_far(v, {}, receivers, -10, 10, -10, 10, 99.5f, 99.75f);
  ASSERT_FALSE(clamped.empty);
  EXPECT_NEAR(clamped.near, 99.5f, 1e-4f);
  EXPECT_NEAR(clamped.far, 99.75f, 1e-4f);
  EXPECT_TRUE(tighten_near_far(v, casters, receivers, -10, 10, -10, 10, 0.0f, 50.0f).empty);
  EXPECT_TRUE(tighten_near_far(v, casters, {}, -10, 10, -10, 10, 0.0f, 200.0f).empty);
}

// ---- Shading helpers
// ------------------------------------------------------------------------------

TEST(CascadeSelect, ByDepthHalfOpen) {
  const std::vector<float> d = {0.1f, 5.0f, 20.0f, 100.0f};
  EXPECT_EQ(select_cascade_by_depth(d, 0.05f), -1);
  EXPECT_EQ(select_cascade_by_depth(d, 0.1f), 0);
  EXPECT_EQ(select_cascade_by_depth(d, 4.99f), 0);
  EXPECT_EQ(select_cascade_by_depth(d, 5.0f), 1);
  EXPECT_EQ(select_cascade_by_depth(d, 50.0f), 2);
  EXPECT_EQ(select_cascade_by_depth(d, 100.0f), -1);
  EXPECT_EQ(select_cascade_by_depth(std::vector<float>{1.0f}, 1.0f), -1);
}

TEST(CascadeSelect, ByMapBoundsPicksTheFirstContainingMap) {
  const glm::mat4 v = light_view_matrix({0, -1, 0}, {0, 100, 0});
  const std::vector<glm::mat4> vp = {glm::ortho(-1.0f, 1.0f, -1.0f, 1.0f, 90.0f, 110.0f) * v,
                                     glm::ortho(-10.0f, 10.0f, -10.0f, 10.0f, 90.0f, 110.0f) * v};
  EXPECT_EQ(select_cascade_by_map(vp, {0.5f, 0, 0.5f}), 0);
  EXPECT_EQ(select_cascade_by_map(vp, {3, 0, 0}), 1);
  EXPECT_EQ(select_cascade_by_map(vp, {0.5f, 50, 0}), -1);  // outside the depth range
  EXPECT_EQ(select_cascade_by_map(vp, {30, 0, 0}), -1);
  EXPECT_EQ(select_cascade_by_map(vp, {0.95f, 0, 0}, 0.1f), 1);  // in cascade 0's border
  // Real fits: a point of each slice selects a cascade no later than its own.
  CameraSetup cam;
  const std::vector<float> d = split_distances(SplitScheme::mixed, 4, cam.near, 60.0f, 0.5f);
  std::vector<glm::mat4> fits;
  for (int i = 0; i < 4; ++i)
    fits.push_back(fit_cascade(cam.slice(d[i], d[i + 1]), LightFrame{{0.3f, -1, 0.2f}, {}},
                               CascadeFitOptions{})
                       .view_proj());
  for (int i = 0; i < 4; ++i) {
    const float depth = 0.5f * (d[i] + d[i + 1]);
    const int sel = select_cascade_by_map(fits, {0.1f, -0.1f, -depth});
    EXPECT_GE(sel, 0);
    EXPECT_LE(sel, i);
    EXPECT_EQ(select_cascade_by_depth(d, depth), i);
  }
}

TEST(CascadeSelect, BlendWeights) {
  const std::vector<float> d = {0.0f, 10.0f, 20.0f};
  EXPECT_EQ(cascade_blend_weight(d, 0, 5.0f, 0.1f), 0.0f);
  EXPECT_EQ(cascade_blend_weight(d, 0, 9.0f, 0.1f), 0.0f);
  EXPECT_NEAR(cascade_blend_weight(d, 0, 9.5f, 0.1f), 0.5f, 1e-5f);
  EXPECT_NEAR(cascade_blend_weight(d, 0, 10.0f, 0.1f), 1.0f, 1e-5f);
  EXPECT_EQ(cascade_blend_weight(d, 1, 19.9f, 0.1f), 0.0f);  // last cascade
  EXPECT_EQ(cascade_blend_weight(d, 0, 9.9f, 0.0f), 0.0f);   // no band
  EXPECT_EQ(cascade_blend_weight(d, -1, 9.9f, 0.1f), 0.0f);
  EXPECT_EQ(cascade_blend_weight_map({0.5f, 0.2f, 0}, 0.1f), 0.0f);
  EXPECT_NEAR(cascade_blend_weight_map({0.95f, 0.2f, 0}, 0.1f), 0.5f, 1e-5f);
  EXPECT_NEAR(cascade_blend_weight_map({0.1f, -1.0f, 0}, 0.1f), 1.0f, 1e-5f);
  // With a border kept free the band ends where selection ends, at 1 - border.
  EXPECT_NEAR(cascade_blend_weight_map({0.8f, 0.2f, 0}, 0.1f, 0.2f), 1.0f, 1e-5f);
  EXPECT_NEAR(cascade_blend_weight_map({0.76f, 0.2f, 0}, 0.1f, 0.2f), 0.5f, 1e-5f);
  EXPECT_EQ(cascade_blend_weight_map({0.7f, 0.2f, 0}, 0.1f, 0.2f), 0.0f);
}

TEST(CascadeSelect, BiasMatrixMapsNdcToTextureSpace) {
  const glm::mat4 b = shadow_bias_matrix();
  const glm::vec4 lo = b * glm::vec4(-1, -1, -1, 1), hi = b * glm::vec4(1, 1, 1, 1);
  const glm::vec4 mid = b * glm::vec4(0, 0.5f, 0, 1);
  EXPECT_EQ(lo, glm::vec4(0, 0, 0, 1));
  EXPECT_EQ(hi, glm::vec4(1, 1, 1, 1));
  EXPECT_EQ(mid, glm::vec4(0.5f, 0.75f, 0.5f, 1));
}

// ---- Validation
// -----------------------------------------------------------------------------------

TEST(CascadeValidate, NonFiniteTransformsAreReported) {
  EXPECT_EQ(validate_transform(glm::mat4(1.0f)), "");
  glm::mat4 m(1.0f);
  m[3][1] = NAN;
  EXPECT_EQ(validate_transform(m), "element [3][1] is NaN");
  m = glm::mat4(1.0f);
  m[0][2] = INFINITY;
  EXPECT_EQ(validate_transform(m), "element [0][2] is +inf");
  m[0][2] = -INFINITY;
  EXPECT_EQ(validate_transform(m), "element [0][2] is -inf");
  // Bad camera transforms and lights are reported before any fit.
  CameraSlice s;
  s.camera_world[3][0] = NAN;
  EXPECT_NE(validate_camera_slice(s).find("NaN"), std::string::npos);
  s = CameraSlice{};
  s.camera_world = glm::scale(glm::mat4(1.0f), glm::vec3(2.0f));
  EXPECT_NE(validate_camera_slice(s).find("not rigid"), std::string::npos);
  s = CameraSlice{};
  s.far = s.near;
  EXPECT_NE(validate_camera_slice(s).find("far must be"), std::string::npos);
  s = CameraSlice{};
  s.fov_y_rad = kPi;
  EXPECT_NE(validate_camera_slice(s).find("fov_y_rad"), std::string::npos);
  s = CameraSlice{};
  s.aspect = INFINITY;
  EXPECT_NE(validate_camera_slice(s).find("aspect"), std::string::npos);
  EXPECT_EQ(validate_camera_slice(CameraSlice{}), "");
  EXPECT_EQ(validate_light_frame(LightFrame{}), "");
  EXPECT_EQ(validate_light_frame(LightFrame{{0, 0, 0}, {}}), "direction has zero length");
  EXPECT_EQ(validate_light_frame(LightFrame{{NAN, 1, 0}, {}}), "direction is not finite");
  EXPECT_EQ(validate_light_frame(LightFrame{{0, -1, 0}, {INFINITY, 0, 0}}), "origin is not finite");
}

TEST(CascadeValidateDeathTest, FitRejectsBadInputWithAMessage) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  CameraSlice s;
  s.camera_world[0][0] = NAN;
  EXPECT_DEATH(fit_cascade(s, LightFrame{}, CascadeFitOptions{}), "camera_world element");
  EXPECT_DEATH(fit_cascade(CameraSlice{}, LightFrame{{0, 0, 0}, {}}, CascadeFitOptions{}),
               "zero length");
  CascadeFitOptions o;
  o.map_size = 1;
  EXPECT_DEATH(fit_cascade(CameraSlice{}, LightFrame{}, o), "map_size");
}

TEST(ShadowSettingsValidate, DefaultsAreValidAndBadValuesNamed) {
  EXPECT_EQ(validate_shadow_settings(ShadowSettings{}), "");
  ShadowSettings s;
  s.lambda = 1.2f;
  EXPECT_EQ(validate_shadow_settings(s), "lambda must be in [0, 1], was 1.2");
  s = ShadowSettings{};
  s.lambda = NAN;
  EXPECT_NE(validate_shadow_settings(s).find("lambda"), std::string::npos);
  s = ShadowSettings{};
  s.cascade_count = 9;
  EXPECT_EQ(validate_shadow_settings(s), "cascade_count must be in [1, 8], was 9");
  s = ShadowSettings{};
  s.map_size = 1000;
  EXPECT_NE(validate_shadow_settings(s).find("was 1000"), std::string::npos);
  s = ShadowSettings{};
  s.max_distance = -1.0f;
  EXPECT_NE(validate_shadow_settings(s).find("max_distance"), std::string::npos);
  s = ShadowSettings{};
  s.beam_radius = INFINITY;
  EXPECT_NE(validate_shadow_settings(s).find("beam_radius"), std::string::npos);
  s = ShadowSettings{};
  s.blend_band = 1.5f;
  EXPECT_EQ(validate_shadow_settings(s), "blend_band must be in [0, 1], was 1.5");
  s = ShadowSettings{};
  s.normal_offset_bias = -1.0f;
  EXPECT_NE(validate_shadow_settings(s).find("normal_offset_bias"), std::string::npos);
  s = ShadowSettings{};
  s.fit_mode = static_cast<FitMode>(7);
  EXPECT_NE(validate_shadow_settings(s).find("fit_mode"), std::string::npos);
  s = ShadowSettings{};
  s.fit_mode = FitMode::scene;
  EXPECT_EQ(validate_shadow_settings(s), "fit_mode scene needs cascade_count 1, was 4");
  s.cascade_count = 1;
  EXPECT_EQ(validate_shadow_settings(s), "");
}

}  // namespace
}  // namespace kaskad
