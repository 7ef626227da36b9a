// Reflection probes on the GPU (S3): S3's coloured-cube environment seen in a mirror sphere and a
// mirror plane, checked per pixel against the CPU formulas (eq. (1) from the AOV position and
// normal, then env_map.h's sample_cube); the same with a 3ds Max-authored cube; captured probes
// (face centres show the surrounding walls; the reflector itself is excluded); schedules end to
// end (faces per frame, time slicing never shows a partial cube, on_change).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>

#include "components/bounds.h"
#include "components/material.h"
#include "components/name.h"
#include "components/probe_state.h"
#include "components/reflector.h"
#include "runtime/assets/env_map.h"
#include "runtime/app/player.h"
#include "tests/render/player_fixture.h"
#include "runtime/gpu/context.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir() {
  const fs::path d = testing_util::test_tmp();
  fs::create_directories(d);
  return d;
}

// S3's test environment: one distinct colour per GL face.
const std::array<glm::vec4, 6> kFaceColours = {
    glm::vec4(1, 0, 0, 1), glm::vec4(0, 1, 1, 1),      // +X red, -X cyan
    glm::vec4(0, 1, 0, 1), glm::vec4(1, 0, 1, 1),      // +Y green, -Y magenta
    glm::vec4(0, 0, 1, 1), glm::vec4(1, 1, 0, 1)};     // +Z blue, -Z yellow

CubeMap coloured_cube(int size) {
  return make_cube_map(size, [](const glm::vec3& d) {
    return kFaceColours[std::size_t(cube_coord(d).face)];
  });
}

std::string write_scene(const std::string& name, const std::string& entities) {
  const fs::path p = temp_dir() / name;
  std::ofstream(p) << R"({"kaskad_scene": 1,
    "render": {"width": 240, "height": 160, "ambient": [0, 0, 0], "clear_color": [0, 0, 0], "exposure": 1},
    "entities": [)" << entities << "]}";
  return p.string();
}

class ProbeTest : public PlayerTest {
 protected:
  static Scene load(const std::string& file, std::vector<std::string> sets = {}) {
    auto s = load_scene(file, sets);
    EXPECT_TRUE(s.ok()) << s.error().to_string();
    return s.ok() ? std::move(s.value()) : Scene{};
  }

  static ecs::Entity named(const Scene& s, const std::string& name) {
    ecs::Entity found;
    s.world.view<Name>().each([&](ecs::Entity e, const Name& n) {
      if (n.value == name) found = e;
    });
    return found;
  }

  struct Comparison {
    int compared = 0, bad = 0;
    std::set<int> faces;  // faces seen by compared pixels
    float max_error = 0.0f;
  };

  // For every geometry pixel: R from eq. (1) with the AOV's P and N and the camera position,
  // expected C_t = sample_cube(expected, R); compared with the AOV's reflection channels where R
  // is at least `margin` (in face coordinates) away from a face edge.
  static Comparison compare_reflection(const Image& aov, const glm::vec3& eye,
                                       const CubeMap& expected, float margin = 0.04f,
                                       float sphere_radius = 2.0f) {
    Comparison c;
    for (int y = 0; y < aov.height; ++y)
      for (int x = 0; x < aov.width; ++x) {
        if (aov.at(x, y, 8) < 0.5f) continue;
        const glm::vec3 p(aov.at(x, y, 0), aov.at(x, y, 1), aov.at(x, y, 2));
        const glm::vec3 n = glm::normalize(glm::vec3(aov.at(x, y, 3), aov.at(x, y, 4), aov.at(x, y, 5)));
        const glm::vec3 u = glm::normalize(p - eye);
        const glm::vec3 r = u - 2.0f * glm::dot(n, u) * n;  // S3 eq. (1)
        const CubeCoord cc = cube_coord(r);
        if (std::min({cc.s, cc.t, 1.0f - cc.s, 1.0f - cc.t}) < margin) continue;
        // Sphere maps (camera with identity rotation: view space = world space): only where the
        // map's radius (eq. (4)-(5)) is below `sphere_radius`, away from the rim.
        if (glm::length(sphere_map_uv(r) - glm::vec2(0.5f)) * 2.0f > sphere_radius) continue;
        const glm::vec4 want = sample_cube(expected, r);
        const glm::vec3 got(aov.at(x, y, 10), aov.at(x, y, 11), aov.at(x, y, 12));
        const float err = glm::length(got - glm::vec3(want));
        c.max_error = std::max(c.max_error, err);
        ++c.compared;
        c.bad += err > 0.02f || aov.at(x, y, 13) != 1.0f;  // the "reflector" channel says so too
        c.faces.insert(int(cc.face));
      }
    return c;
  }

};

constexpr const char* kMirrorMaterial =
    R"("material": {"base_color": [0, 0, 0, 1], "metallic": 0, "roughness": 1, "k_s": 0.5})";

TEST_F(ProbeTest, ColouredCubeInAMirrorSphereAndPlane) {
  const CubeMap env = coloured_cube(32);
  ASSERT_TRUE(save_cube_faces(env, temp_dir() / "coloured_*.exr").ok());
  const std::string reflector =
      R"("reflector": {"update": "static_file", "file": "coloured_*.exr", "resolution": 32, "amount": 0.8})";
  for (const bool plane : {false, true}) {
    SCOPED_TRACE(plane ? "mirror plane" : "mirror sphere");
    const std::string mirror =
        plane ? std::string(R"({"name": "mirror", "transform": {"euler_deg": [90, 0, 0], "scale": [6, 1, 6]},
                   "primitive": {"shape": "plane"}, )") + kMirrorMaterial + ", " + reflector + "}"
              : std::string(R"({"name": "mirror", "transform": {"scale": [2, 2, 2]},
                   "primitive": {"shape": "sphere", "segments": 96}, )") + kMirrorMaterial + ", " + reflector + "}";
    // The plane is seen from close by with a wide lens, so its reflection spans five faces.
    const std::string camera =
        plane ? R"({"name": "camera", "transform": {"translation": [0.3, 0.2, 1.0], "look_at": [0, 0, 0]},
                   "camera": {"fov_y_deg": 110, "near": 0.05, "far": 50, "active": true}})"
              : R"({"name": "camera", "transform": {"translation": [0.4, 0.6, 4.0], "look_at": [0, 0, 0]},
                   "camera": {"fov_y_deg": 40, "near": 0.1, "far": 50, "active": true}})";
    Scene scene = load(write_scene("coloured_mirror.json", mirror + ", " + camera));
    RenderRun run;
    run.frames = 2;
    auto t = render_frames(*player_, scene, run);
    ASSERT_TRUE(t.ok()) << t.error().to_string();
    EXPECT_EQ(t->last.probes.captures_total, 1u);  // the file was uploaded once
    EXPECT_EQ(t->last.stats.probe_faces, 0);       // and nothing was captured
    const Image aov = player_->renderer->read_aovs();
    const Comparison c = compare_reflection(aov, t->last.camera.position, env);
    EXPECT_GT(c.compared, plane ? 10000 : 4000);
    EXPECT_EQ(c.bad, 0) << "max error " << c.max_error;
    EXPECT_GE(c.faces.size(), plane ? 5u : 5u);
    // The colour is I' = I + k_s p_r C_t (eq. (3)) with I = 0 here (no light, black material).
    const Image color = player_->renderer->read_color();
    const int x = aov.width / 2, y = aov.height / 2;
    const glm::vec3 ct(aov.at(x, y, 10), aov.at(x, y, 11), aov.at(x, y, 12));
    for (int ch = 0; ch < 3; ++ch) {
      const float linear = 0.5f * 0.8f * ct[ch];
      const float srgb = linear <= 0.0031308f ? 12.92f * linear
                                              : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
      EXPECT_NEAR(color.at(x, y, ch), srgb, 2.0f / 255.0f) << "channel " << ch;
    }
  }
}

// A glTF model as the reflector: its meshes (imported child entities) reflect the model's probe,
// and the probe's centre is the centre of the meshes' bounds (the model entity has none).
TEST_F(ProbeTest, ModelReflectorsShadeTheirImportedMeshes) {
  const CubeMap env = coloured_cube(32);
  ASSERT_TRUE(save_cube_faces(env, temp_dir() / "model_env_*.exr").ok());
  const std::string box = (content_dir() / "models/Box/glTF-Binary/Box.glb").string();
  Scene scene = load(write_scene("model_mirror.json",
      R"({"name": "mirror", "transform": {"translation": [0.5, 0, 0], "euler_deg": [20, 35, 0], "scale": [2, 2, 2]},
          "model": {"path": ")" + box + R"("},
          "reflector": {"update": "static_file", "file": "model_env_*.exr", "resolution": 32}},
         {"name": "camera", "transform": {"translation": [0.9, 0.8, 5.0], "look_at": [0.5, 0, 0]},
          "camera": {"fov_y_deg": 40, "near": 0.1, "far": 50, "active": true}})"));
  RenderRun run;
  run.frames = 2;
  auto t = render_frames(*player_, scene, run);
  ASSERT_TRUE(t.ok()) << t.error().to_string();
  const ProbeState& ps = scene.world.get<ProbeState>(named(scene, "mirror"));
  EXPECT_NEAR(glm::length(ps.center - glm::vec3(0.5f, 0.0f, 0.0f)), 0.0f, 1e-4f);
  const Comparison c =
      compare_reflection(player_->renderer->read_aovs(), t->last.camera.position, env);
  EXPECT_GT(c.compared, 3000);
  EXPECT_EQ(c.bad, 0) << "max error " << c.max_error;
  EXPECT_GE(c.faces.size(), 2u);
}

TEST_F(ProbeTest, ThreeDsMaxCubeIsConvertedOnLoad) {
  // Faces named by 3ds Max axes (Z up): px RIGHT, nx LEFT, py BACK, ny FRONT, pz UP, nz DOWN.
  CubeMap max_faces = coloured_cube(16);
  ASSERT_TRUE(save_cube_faces(max_faces, temp_dir() / "max_*.exr").ok());
  const CubeMap expected = cube_from_3dsmax(max_faces);
  // Independently of that conversion: the engine's up (+Y) is 3ds Max's UP (its pz face, blue).
  EXPECT_EQ(sample_cube(expected, glm::vec3(0, 1, 0)), kFaceColours[4]);
  Scene scene = load(write_scene("max_mirror.json",
      std::string(R"({"name": "mirror", "transform": {"scale": [2, 2, 2]},
         "primitive": {"shape": "sphere", "segments": 96}, )") + kMirrorMaterial +
      R"(, "reflector": {"update": "static_file", "file": "max_*.exr", "z_up_3dsmax": true, "resolution": 16}},
       {"name": "camera", "transform": {"translation": [0.4, 0.6, 4.0], "look_at": [0, 0, 0]},
        "camera": {"fov_y_deg": 40, "near": 0.1, "far": 50, "active": true}})"));
  RenderRun run;
  run.frames = 1;
  auto t = render_frames(*player_, scene, run);
  ASSERT_TRUE(t.ok()) << t.error().to_string();
  const Comparison c = compare_reflection(player_->renderer->read_aovs(), t->last.camera.position, expected);
  EXPECT_GT(c.compared, 4000);
  EXPECT_EQ(c.bad, 0) << "max error " << c.max_error;
  // The top of the sphere reflects up: 3ds Max's UP colour.
  const Image aov = player_->renderer->read_aovs();
  int top = -1;
  for (int y = 0; y < aov.height && top < 0; ++y)
    if (aov.at(aov.width / 2, y, 8) > 0.5f) top = y;
  ASSERT_GE(top, 0);
  const int y = top + 4;
  EXPECT_NEAR(aov.at(aov.width / 2, y, 12), 1.0f, 0.02f);  // blue
  EXPECT_NEAR(aov.at(aov.width / 2, y, 10), 0.0f, 0.02f);
}

// Six emissive walls around a probe; the reflector is a double-sided black box around the probe
// centre, which would hide every wall if it were drawn into its own probe.
std::string walls_scene(const std::string& update) {
  const char* axes[6] = {"[4, 0, 0]", "[-4, 0, 0]", "[0, 4, 0]", "[0, -4, 0]", "[0, 0, 4]", "[0, 0, -4]"};
  const char* sizes[6] = {"[0.2, 8, 8]", "[0.2, 8, 8]", "[8, 0.2, 8]", "[8, 0.2, 8]", "[8, 8, 0.2]", "[8, 8, 0.2]"};
  std::string s;
  for (int f = 0; f < 6; ++f) {
    const glm::vec4 c = kFaceColours[std::size_t(f)];
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  R"({"name": "wall%d", "transform": {"translation": %s, "scale": %s},
                     "primitive": {"shape": "box"},
                     "material": {"base_color": [0, 0, 0, 1], "emissive": [%g, %g, %g]}}, )",
                  f, axes[f], sizes[f], double(c.r), double(c.g), double(c.b));
    s += buf;
  }
  s += R"({"name": "probe", "transform": {"translation": [0.5, -0.25, 0.25]},
           "primitive": {"shape": "box"},
           "material": {"base_color": [0, 0, 0, 1], "double_sided": true},
           "reflector": {"update": ")";
  s += update;
  s += R"(", "resolution": 32, "near": 0.05, "far": 20}},
         {"name": "camera", "transform": {"translation": [0, 0, 3], "look_at": [0, 0, 0]},
          "camera": {"fov_y_deg": 60, "active": true}})";
  return write_scene("walls_" + update + ".json", s);
}

glm::vec4 face_centre(const CubeMap& cube, int face) {
  const int m = cube.size / 2;
  return 0.25f * (cube.at(CubeFace(face), m - 1, m - 1) + cube.at(CubeFace(face), m, m - 1) +
                  cube.at(CubeFace(face), m - 1, m) + cube.at(CubeFace(face), m, m));
}

TEST_F(ProbeTest, CapturedFacesShowTheSurroundingWalls) {
  Scene scene = load(walls_scene("first_frame"));
  RenderRun run;
  run.frames = 3;
  auto t = render_frames(*player_, scene, run);
  ASSERT_TRUE(t.ok()) << t.error().to_string();
  const ecs::Entity probe = named(scene, "probe");
  const ProbeState& ps = scene.world.get<ProbeState>(probe);
  EXPECT_EQ(ps.captures, 1u);
  EXPECT_EQ(ps.faces_rendered, 6u);
  const CubeMap cube = player_->renderer->read_probe_cube(ps.handle, ps.front);
  ASSERT_EQ(cube.size, 32);
  for (int f = 0; f < 6; ++f) {
    const glm::vec4 c = face_centre(cube, f);
    for (int ch = 0; ch < 3; ++ch)
      EXPECT_NEAR(c[ch], kFaceColours[std::size_t(f)][ch], 0.01f) << "face " << f << " channel " << ch;
  }
  // Off-centre samples too: the direction through texel (x, y) of face +X sees the +X wall
  // unless it leaves it; with the probe at (0.5, -0.25, 0.25) every face's inner 60% does.
  for (int f = 0; f < 6; ++f)
    for (int y = 7; y < 25; y += 8)
      for (int x = 7; x < 25; x += 8)
        EXPECT_NEAR(cube.at(CubeFace(f), x, y).r, kFaceColours[std::size_t(f)].r, 0.01f)
            << "face " << f << " texel " << x << "," << y;
}

TEST_F(ProbeTest, EveryNCapturesOnExactlyTheScheduledFrames) {
  Scene scene = load(walls_scene("every_n"), {"probe.reflector.every_n=3"});
  ecs::Entity probe = named(scene, "probe");
  FrameContext ctx;
  ctx.width = 64;
  ctx.height = 48;
  ctx.write_aovs = false;
  SystemState systems;
  FrameReport report;
  for (int k = 0; k < 8; ++k) {
    ctx.index = std::uint64_t(k);
    ASSERT_TRUE(run_frame(scene, *player_->renderer, ctx, systems, report).ok());
    EXPECT_EQ(report.stats.probe_faces, k % 3 == 0 ? 6 : 0) << "frame " << k;
  }
  EXPECT_EQ(scene.world.get<ProbeState>(probe).captures, 3u);
}

// The editor renders one frame per render_frames() call (editor/main.cpp): the frame index must
// carry on across calls (Scene::frames_rendered), so every_n = 3 still captures on every third
// frame, not on every call.
TEST_F(ProbeTest, EveryNHoldsWhenDrivenOneFramePerCall) {
  Scene scene = load(walls_scene("every_n"), {"probe.reflector.every_n=3"});
  RenderRun run;
  run.frames = 1;
  run.width = 64;
  run.height = 48;
  run.write_aovs = false;
  for (int k = 0; k < 8; ++k) {
    run.prewarm = k == 0;
    auto t = render_frames(*player_, scene, run);
    ASSERT_TRUE(t.ok()) << t.error().to_string();
    EXPECT_EQ(t->last.stats.probe_faces, k % 3 == 0 ? 6 : 0) << "call " << k;
  }
  EXPECT_EQ(scene.frames_rendered, 8u);
  EXPECT_EQ(scene.world.get<ProbeState>(named(scene, "probe")).captures, 3u);
}

// Captures select cascades by map bounds (capture_frame_variant()): a probe 10 m behind the main
// camera, under a slab, sees the ground below it in the slab's shadow. With the main camera's
// view depth (negative there) the capture picked cascade 0, whose map does not reach that far
// behind the camera, and the ground came out lit.
TEST_F(ProbeTest, ProbeSeesAShadowBehindTheMainCamera) {
  const std::string file = write_scene("shadow_behind.json",
      R"({"name": "ground", "transform": {"scale": [100, 1, 100]}, "primitive": {"shape": "plane"},
          "material": {"base_color": [0.5, 0.5, 0.5, 1], "roughness": 1}},
         {"name": "slab", "transform": {"translation": [0, 1.5, 10], "scale": [4, 0.2, 4]},
          "primitive": {"shape": "box"}, "material": {"base_color": [0.5, 0.5, 0.5, 1]}},
         {"name": "probe", "transform": {"translation": [0, 0.5, 10], "scale": [0.2, 0.2, 0.2]},
          "primitive": {"shape": "sphere"}, "renderer": {"cast_shadows": false},
          "reflector": {"update": "first_frame", "resolution": 32, "near": 0.05, "far": 50}},
         {"name": "sun", "transform": {"direction": [0.1, -1, 0.05]},
          "light": {"type": "directional", "intensity": 1, "cast_shadows": true}},
         {"name": "camera", "transform": {"translation": [0, 2, 0], "look_at": [0, 1.5, -10]},
          "camera": {"fov_y_deg": 90, "near": 0.5, "far": 20, "active": true}})");
  // The ground seen by the probe's -Y face (GL face 3), as linear radiance.
  auto ground_below_probe = [&](const std::vector<std::string>& sets, ShadowData* shadow) {
    Scene scene = load(file, sets);
    RenderRun run;
    run.frames = 1;
    run.write_aovs = false;
    auto t = render_frames(*player_, scene, run);
    EXPECT_TRUE(t.ok()) << t.error().to_string();
    if (!t.ok()) return glm::vec4(-1.0f);
    if (shadow) *shadow = t->last.shadow();
    const ProbeState& ps = scene.world.get<ProbeState>(named(scene, "probe"));
    return face_centre(player_->renderer->read_probe_cube(ps.handle, ps.front), 3);
  };
  ShadowData shadow;
  const glm::vec4 shaded = ground_below_probe({"shadow.cascade_count=2"}, &shadow);
  // The setup: the ground point lies outside cascade 0's map and inside cascade 1's.
  ASSERT_EQ(shadow.cascade_count, 2);
  auto in_map = [&](int c) {
    const glm::vec4 clip = shadow.view_proj[std::size_t(c)] * glm::vec4(0, 0, 10, 1);
    const glm::vec3 ndc = glm::vec3(clip) / clip.w;
    return std::max({std::abs(ndc.x), std::abs(ndc.y), std::abs(ndc.z)}) < 0.9f;
  };
  EXPECT_FALSE(in_map(0));
  EXPECT_TRUE(in_map(1));
  // Without the slab over it the same ground is lit (the contrast that makes the check mean
  // something); with it, the probe sees it shadowed (ambient and clear colour are black).
  const glm::vec4 lit =
      ground_below_probe({"shadow.cascade_count=2", "slab.transform.translation=[30, 1.5, 10]"}, nullptr);
  EXPECT_GT(lit.r, 0.05f);
  EXPECT_LT(shaded.r, 0.1f * lit.r) << "lit " << lit.r << ", under the slab " << shaded.r;
}

TEST_F(ProbeTest, TimeSlicedCaptureNeverShowsAPartialCube) {
  // on_change, one face per frame. After the first capture (whole at once) the walls change
  // colour; the visible cube must keep the old colours on all faces until the new capture has all
  // six, then switch all at once.
  Scene scene = load(walls_scene("on_change"), {"probe.reflector.faces_per_frame=1"});
  const ecs::Entity probe = named(scene, "probe");
  FrameContext ctx;
  ctx.width = 64;
  ctx.height = 48;
  ctx.write_aovs = false;
  SystemState systems;
  FrameReport report;
  auto visible = [&] {
    const ProbeState& ps = scene.world.get<ProbeState>(probe);
    return player_->renderer->read_probe_cube(ps.handle, ps.front);
  };
  // The first capture is whole on frame 0 (there is no map to show meanwhile).
  std::uint64_t k = 0;
  ctx.index = k++;
  ASSERT_TRUE(run_frame(scene, *player_->renderer, ctx, systems, report).ok());
  EXPECT_EQ(report.stats.probe_faces, 6);
  EXPECT_TRUE(scene.world.get<ProbeState>(probe).has_map);
  for (int f = 0; f < 6; ++f)
    EXPECT_NEAR(face_centre(visible(), f).r, kFaceColours[std::size_t(f)].r, 0.01f);
  // A static scene does not re-capture.
  for (; k < 9; ++k) {
    ctx.index = k;
    ASSERT_TRUE(run_frame(scene, *player_->renderer, ctx, systems, report).ok());
    EXPECT_EQ(report.stats.probe_faces, 0) << "frame " << k;
  }
  // Every wall turns white: a change in range.
  for (int f = 0; f < 6; ++f)
    scene.world.get<Material>(named(scene, "wall" + std::to_string(f))).emissive = glm::vec3(1.0f);
  int new_faces = 0;
  for (int i = 0; i < 6; ++i, ++k) {
    ctx.index = k;
    ASSERT_TRUE(run_frame(scene, *player_->renderer, ctx, systems, report).ok());
    EXPECT_EQ(report.stats.probe_faces, 1);
    const CubeMap cube = visible();
    int white = 0;
    for (int f = 0; f < 6; ++f) white += face_centre(cube, f) == glm::vec4(1.0f);
    EXPECT_TRUE(white == 0 || white == 6) << "frame " << k << ": " << white << " faces new";
    new_faces = white;
  }
  EXPECT_EQ(new_faces, 6);
  EXPECT_EQ(scene.world.get<ProbeState>(probe).captures, 2u);
}

TEST_F(ProbeTest, SphereMapFromTheCubeAndRuntimeSwitch) {
  // A sphere map made on the GPU from the coloured cube for a camera looking down -Z (identity
  // view rotation): centre = +Z (towards the eye, blue), rim = -Z (yellow), formula-exact at
  // texel centres against env_map.h's sphere_map_from_cube.
  const CubeMap env = coloured_cube(32);
  ASSERT_TRUE(save_cube_faces(env, temp_dir() / "sphere_env_*.exr").ok());
  const std::string file = write_scene("sphere_mirror.json",
      std::string(R"({"name": "mirror", "transform": {"scale": [2, 2, 2]},
         "primitive": {"shape": "sphere", "segments": 96}, )") + kMirrorMaterial +
      R"(, "reflector": {"map": "sphere", "update": "static_file", "file": "sphere_env_*.exr", "resolution": 128}},
       {"name": "camera", "transform": {"translation": [0, 0, 4]},
        "camera": {"fov_y_deg": 40, "near": 0.1, "far": 50, "active": true}})");
  Scene scene = load(file);
  RenderRun run;
  run.frames = 2;
  auto t = render_frames(*player_, scene, run);
  ASSERT_TRUE(t.ok()) << t.error().to_string();
  const ProbeState& ps = scene.world.get<ProbeState>(named(scene, "mirror"));
  const SphereMap gpu = player_->renderer->read_probe_sphere(ps.handle);
  ASSERT_EQ(gpu.size, 128);  // the probe's resolution (the 32-texel faces are resampled)
  const SphereMap cpu = sphere_map_from_cube(env, 128);
  int compared = 0, bad = 0;
  for (int j = 0; j < 128; ++j)
    for (int i = 0; i < 128; ++i) {
      const glm::vec3 r = sphere_map_direction(i, j, 128);
      const CubeCoord cc = cube_coord(r);
      if (std::min({cc.s, cc.t, 1.0f - cc.s, 1.0f - cc.t}) < 0.05f) continue;
      ++compared;
      bad += glm::length(gpu.at(i, j) - cpu.at(i, j)) > 0.02f;
    }
  EXPECT_GT(compared, 8000);
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(gpu.at(64, 64), kFaceColours[4]);  // centre: +Z
  EXPECT_EQ(gpu.at(0, 0), kFaceColours[5]);    // outside the circle: the rim value, -Z
  // Shading through the sphere map matches the cube lookup where the sphere map is good: inside
  // 0.7 of its radius (towards the rim one texel spans ever more solid angle) and away from
  // cube seams (a seam is a curve across sphere-map texels, smeared over one texel by filtering).
  const Image aov = player_->renderer->read_aovs();
  const Comparison c = compare_reflection(aov, t->last.camera.position, env, 0.08f, 0.7f);
  EXPECT_GT(c.compared, 1000);
  EXPECT_EQ(c.bad, 0) << "max error " << c.max_error;
  // Switch to the cube at runtime: the next frame uses the cube feature.
  scene.world.get<Reflector>(named(scene, "mirror")).map = ReflectionMap::cube;
  FrameContext ctx;
  ctx.width = 240;
  ctx.height = 160;
  ctx.index = 2;
  SystemState systems;
  FrameReport report;
  ASSERT_TRUE(run_frame(scene, *player_->renderer, ctx, systems, report).ok());
  ASSERT_EQ(report.probes.probes.size(), 1u);
  EXPECT_FALSE(report.probes.probes[0].sphere);
  const Comparison cube = compare_reflection(player_->renderer->read_aovs(), t->last.camera.position, env);
  EXPECT_EQ(cube.bad, 0) << "max error " << cube.max_error;
}

// Box projection: a mirror sphere off the probe centre inside the six-wall room. The expected
// C_t is the colour of the wall that the true mirror ray (from the surface point along R) meets,
// computed analytically; with the room's inner box as the reflector's box this must hold nearly
// everywhere, and without it parallax makes many pixels wrong.
TEST_F(ProbeTest, BoxProjectionCorrectsParallaxInARoom) {
  std::string walls = walls_scene("first_frame");
  std::ifstream in(walls);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Replace the black box probe by a mirror sphere; walls' inner faces are at +-3.9.
  const auto at = text.find(R"({"name": "probe")");
  ASSERT_NE(at, std::string::npos);
  text = text.substr(0, at) + R"({"name": "probe", "transform": {"translation": [1.2, -0.6, 0.4], "scale": [1.5, 1.5, 1.5]},
      "primitive": {"shape": "sphere", "segments": 96}, "material": {"base_color": [0, 0, 0, 1]},
      "reflector": {"update": "first_frame", "resolution": 128, "far": 20,
                    "box": {"min": [-3.9, -3.9, -3.9], "max": [3.9, 3.9, 3.9]}}},
     {"name": "camera", "transform": {"translation": [0, 0, 3.5], "look_at": [1.2, -0.6, 0.4]},
      "camera": {"fov_y_deg": 40, "active": true}}]})";
  const fs::path file = temp_dir() / "box_room.json";
  std::ofstream(file) << text;
  for (const bool box : {true, false}) {
    SCOPED_TRACE(box ? "box projection" : "plain cube");
    std::vector<std::string> sets;
    if (!box) sets.push_back("probe.reflector={\"update\": \"first_frame\", \"resolution\": 128, \"far\": 20}");
    Scene scene = load(file.string(), sets);
    RenderRun run;
    run.frames = 2;
    auto t = render_frames(*player_, scene, run);
    ASSERT_TRUE(t.ok()) << t.error().to_string();
    const Image aov = player_->renderer->read_aovs();
    const glm::vec3 eye = t->last.camera.position;
    int compared = 0, wrong = 0;
    for (int y = 0; y < aov.height; ++y)
      for (int x = 0; x < aov.width; ++x) {
        if (aov.at(x, y, 13) < 0.5f) continue;  // not the mirror
        const glm::vec3 p(aov.at(x, y, 0), aov.at(x, y, 1), aov.at(x, y, 2));
        const glm::vec3 n = glm::normalize(glm::vec3(aov.at(x, y, 3), aov.at(x, y, 4), aov.at(x, y, 5)));
        const glm::vec3 u = glm::normalize(p - eye);
        const glm::vec3 r = u - 2.0f * glm::dot(n, u) * n;
        // Not at grazing angles: near the silhouette R sweeps so fast that mipmapped lookups
        // blend walls together.
        if (-glm::dot(n, u) < 0.3f) continue;
        // Exit of the ray from the box [-3.9, 3.9]^3: the axis with the smallest exit distance.
        std::array<float, 3> exit{};
        for (int a = 0; a < 3; ++a)
          exit[std::size_t(a)] = r[a] == 0.0f ? 1e30f : ((r[a] > 0 ? 3.9f : -3.9f) - p[a]) / r[a];
        std::array<int, 3> order = {0, 1, 2};
        std::sort(order.begin(), order.end(), [&](int a, int b) { return exit[std::size_t(a)] < exit[std::size_t(b)]; });
        const int axis = order[0];
        const glm::vec3 hit = p + exit[std::size_t(axis)] * r;
        // Away from the room's edges, where walls meet (and the walls' 0.2 m thickness shows).
        bool near_edge = false;
        for (int a = 0; a < 3; ++a)
          if (a != axis && std::abs(hit[a]) > 3.5f) near_edge = true;
        if (near_edge) continue;
        const int face = 2 * axis + (r[axis] > 0 ? 0 : 1);
        const glm::vec3 want(kFaceColours[std::size_t(face)]);
        const glm::vec3 got(aov.at(x, y, 10), aov.at(x, y, 11), aov.at(x, y, 12));
        ++compared;
        wrong += glm::length(got - want) > 0.1f;
      }
    EXPECT_GT(compared, 3000);
    if (box) {
      EXPECT_LT(double(wrong), 0.01 * compared) << wrong << " of " << compared;
    } else {
      EXPECT_GT(double(wrong), 0.05 * compared) << wrong << " of " << compared;
    }
  }
}

// Mirrors that see mirrors on the first frame. In content/scenes/reflections.json the
// mirror ball and the mirror plane both capture on frame 0. With one capture round each sees the
// other before the other has a map: a mirror reflecting nothing, near black (the ball's base
// colour is 0.05, the plane's 0.02, both metallic). With render.probe_bounces = 2 the second
// round reads the first round's maps, so where one probe sees the other reflector it sees that
// reflector's surroundings. What stays dark is a reflection of the first probe itself inside the
// other (ball -> plane -> ball: a third bounce), a small patch that each further round shrinks.
class MirrorsSeeMirrors : public ProbeTest {
 protected:
  // The texels of `cube`, captured from `from`, whose direction meets `hit` well inside the
  // other reflector (not within a texel or two of its silhouette, where filtering mixes in the
  // background), as counts of dark and clear-colour ones.
  struct Seen {
    int texels = 0, dark = 0, clear = 0;
    float dark_fraction() const { return texels ? float(dark) / float(texels) : 1.0f; }
  };
  template <class Hit>
  static Seen seen(const CubeMap& cube, const glm::vec3& from, Hit hit, const glm::vec3& clear) {
    Seen out;
    for (int f = 0; f < 6; ++f)
      for (int y = 0; y < cube.size; ++y)
        for (int x = 0; x < cube.size; ++x) {
          const glm::vec3 d = cube_direction(CubeFace(f), (float(x) + 0.5f) / float(cube.size),
                                             (float(y) + 0.5f) / float(cube.size));
          if (!hit(from, glm::normalize(d))) continue;
          const glm::vec3 c(cube.at(CubeFace(f), x, y));
          ++out.texels;
          out.dark += std::max({c.r, c.g, c.b}) < kDark;
          out.clear += glm::length(c - clear) < 0.02f;
        }
    return out;
  }
  // Linear radiance below this on every channel reads as black: the ball's own shading without
  // a map (ambient 0.08-0.11 times a base colour of 0.05, no diffuse for a metal) stays under it
  // away from the sun's highlight.
  static constexpr float kDark = 0.05f;
};

TEST_F(MirrorsSeeMirrors, OnTheFirstFrameOfTheReflectionsDemo) {
  const fs::path file = content_dir() / "scenes" / "reflections.json";
  struct Result {
    Seen ball_in_plane, plane_in_ball, plane_aov;
    int faces = 0, rounds = 0;
  };
  auto first_frame = [&](int bounces, bool sphere_ball) {
    Result res;
    std::vector<std::string> sets = {"render.probe_bounces=" + std::to_string(bounces)};
    if (sphere_ball) sets.push_back("mirror_sphere.reflector.map=sphere");
    Scene scene = load(file.string(), sets);
    RenderRun run;
    run.frames = 1;
    run.width = 320;
    run.height = 180;
    auto t = render_frames(*player_, scene, run);
    EXPECT_TRUE(t.ok()) << t.error().to_string();
    if (!t.ok()) return res;
    res.faces = t->last.stats.probe_faces;
    res.rounds = t->last.probes.rounds;
    const ecs::Entity ball = named(scene, "mirror_sphere"), plane = named(scene, "mirror_plane");
    const ProbeState& bs = scene.world.get<ProbeState>(ball);
    const ProbeState& ps = scene.world.get<ProbeState>(plane);
    EXPECT_TRUE(bs.has_map && ps.has_map);
    // The ball: a sphere (its world bounds' centre and half extent); the plane: the rectangle
    // of its flat world bounds at z = const. Both shrunk by a margin (2 texels of a 128 face
    // seen from 4.5 m away is about 0.14 m).
    const Aabb bb = scene.world.get<WorldBounds>(ball).box, pb = scene.world.get<WorldBounds>(plane).box;
    const glm::vec3 ball_centre = bb.center();
    const float ball_radius = 0.5f * (bb.max.x - bb.min.x) - 0.15f;
    auto hits_ball = [&](const glm::vec3& o, const glm::vec3& d) {
      const glm::vec3 oc = o - ball_centre;
      const float b = glm::dot(oc, d), c = glm::dot(oc, oc) - ball_radius * ball_radius;
      return b < 0.0f && b * b - c > 0.0f;
    };
    EXPECT_LT(pb.max.z - pb.min.z, 1e-3f);  // the plane stands in z = const
    auto hits_plane = [&](const glm::vec3& o, const glm::vec3& d) {
      if (std::abs(d.z) < 1e-4f) return false;
      const float s = (pb.min.z - o.z) / d.z;
      const glm::vec3 p = o + s * d;
      return s > 0.0f && p.x > pb.min.x + 0.15f && p.x < pb.max.x - 0.15f &&
             p.y > pb.min.y + 0.15f && p.y < pb.max.y - 0.15f;
    };
    const glm::vec3 clear = scene.render.clear_color;
    res.ball_in_plane = seen(player_->renderer->read_probe_cube(ps.handle, ps.front), ps.center,
                             hits_ball, clear);
    res.plane_in_ball = seen(player_->renderer->read_probe_cube(bs.handle, bs.front), bs.center,
                             hits_plane, clear);
    // The main view: plane pixels whose lookup direction R (S3 eq. (1)) shows the ball in the
    // plane's cube, with the reflected colour C_t from the reflection AOV.
    const Image aov = player_->renderer->read_aovs();
    const glm::vec3 eye = t->last.camera.position;
    for (int y = 0; y < aov.height; ++y)
      for (int x = 0; x < aov.width; ++x) {
        if (aov.at(x, y, 13) < 0.5f || std::abs(aov.at(x, y, 2) - pb.min.z) > 0.01f) continue;
        const glm::vec3 p(aov.at(x, y, 0), aov.at(x, y, 1), aov.at(x, y, 2));
        const glm::vec3 n = glm::normalize(glm::vec3(aov.at(x, y, 3), aov.at(x, y, 4), aov.at(x, y, 5)));
        const glm::vec3 u = glm::normalize(p - eye);
        const glm::vec3 r = u - 2.0f * glm::dot(n, u) * n;
        if (!hits_ball(ps.center, r)) continue;
        const glm::vec3 ct(aov.at(x, y, 10), aov.at(x, y, 11), aov.at(x, y, 12));
        ++res.plane_aov.texels;
        res.plane_aov.dark += std::max({ct.r, ct.g, ct.b}) < kDark;
        res.plane_aov.clear += glm::length(ct - clear) < 0.02f;
      }
    return res;
  };
  const Result one = first_frame(1, false), two = first_frame(2, false), three = first_frame(3, false);
  for (const auto& [name, r] : {std::pair<const char*, const Result&>{"1", one}, {"2", two}, {"3", three}})
    std::printf("probe_bounces %s: %d rounds, %d faces; ball in plane's cube %d/%d dark, %d clear; "
                "plane in ball's cube %d/%d dark, %d clear; ball in the main view's plane %d/%d "
                "dark, %d clear\n",
                name, r.rounds, r.faces, r.ball_in_plane.dark, r.ball_in_plane.texels,
                r.ball_in_plane.clear, r.plane_in_ball.dark, r.plane_in_ball.texels,
                r.plane_in_ball.clear, r.plane_aov.dark, r.plane_aov.texels, r.plane_aov.clear);
  // One round per probe, or 2 and 3: 12 faces per round.
  EXPECT_EQ(one.rounds, 1);
  EXPECT_EQ(one.faces, 12);
  EXPECT_EQ(two.rounds, 2);
  EXPECT_EQ(two.faces, 24);
  EXPECT_EQ(three.faces, 36);
  for (const Result* r : {&one, &two, &three}) {
    EXPECT_GT(r->ball_in_plane.texels, 300);
    EXPECT_GT(r->plane_in_ball.texels, 1000);
    EXPECT_GT(r->plane_aov.texels, 500);
    // The other reflector is drawn in each probe (never a hole showing the clear colour).
    EXPECT_EQ(r->ball_in_plane.clear + r->plane_in_ball.clear + r->plane_aov.clear, 0);
  }
  // One round: each mirror is black in the other's map (the sun's highlight aside), and so is
  // the ball in the plane as the camera sees it (measured: docs/design/probes.md, "Bounces").
  EXPECT_GT(one.ball_in_plane.dark_fraction(), 0.8f);
  EXPECT_GT(one.plane_in_ball.dark_fraction(), 0.7f);
  EXPECT_GT(one.plane_aov.dark_fraction(), 0.8f);
  // Two rounds: the ball in the plane's map and in the main view shows its surroundings; the
  // plane in the ball's map still shows the ball black where it reflects it (ball -> plane ->
  // ball, a third bounce; measured: docs/design/probes.md).
  EXPECT_LT(two.ball_in_plane.dark_fraction(), 0.1f);
  EXPECT_LT(two.plane_in_ball.dark_fraction(), 0.3f);
  EXPECT_LT(two.plane_aov.dark_fraction(), 0.1f);
  // Three rounds fill that in too (docs/design/probes.md).
  EXPECT_LT(three.ball_in_plane.dark_fraction(), 0.05f);
  EXPECT_LT(three.plane_in_ball.dark_fraction(), 0.05f);
  EXPECT_LT(three.plane_aov.dark_fraction(), 0.05f);
  // A sphere-mapped ball is read through its sphere map, which each round remakes from its cube.
  const Result sphere_one = first_frame(1, true), sphere_two = first_frame(2, true);
  std::printf("sphere-mapped ball: in the plane's cube %d/%d dark with 1 round, %d/%d with 2\n",
              sphere_one.ball_in_plane.dark, sphere_one.ball_in_plane.texels,
              sphere_two.ball_in_plane.dark, sphere_two.ball_in_plane.texels);
  EXPECT_GT(sphere_one.ball_in_plane.dark_fraction(), 0.8f);
  EXPECT_LT(sphere_two.ball_in_plane.dark_fraction(), 0.1f);
}

}  // namespace
}  // namespace kaskad
