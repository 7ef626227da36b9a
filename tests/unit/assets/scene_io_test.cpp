// Scene files: round trip, overrides, and errors that name the file and the place.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "components/camera.h"
#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/name.h"
#include "components/reflector.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "runtime/assets/scene_io.h"
#include "runtime/assets/material_file.h"
#include "runtime/core/json_reader.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;
const fs::path kContent = KASKAD_CONTENT_DIR;

fs::path temp_dir() {
  const fs::path d = testing_util::test_tmp();
  fs::create_directories(d);
  return d;
}

fs::path write_file(const std::string& name, const std::string& text) {
  const fs::path p = temp_dir() / name;
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

ecs::Entity find(const Scene& s, const std::string& name) {
  ecs::Entity found;
  s.world.view<Name>().each([&](ecs::Entity e, const Name& n) {
    if (n.value == name) found = e;
  });
  return found;
}

TEST(SceneIo, DefaultSceneRoundTripsExactly) {
  auto a = read_scene(kContent / "scenes" / "default.json");
  ASSERT_TRUE(a.ok()) << a.error().to_string();
  const fs::path first = temp_dir() / "first.json", second = temp_dir() / "second.json";
  ASSERT_TRUE(save_scene(first, *a).ok());
  auto b = read_scene(first);
  ASSERT_TRUE(b.ok()) << b.error().to_string();
  ASSERT_TRUE(save_scene(second, *b).ok());
  EXPECT_EQ(read_file(first), read_file(second));
  // Nothing lost: same entities with the same values.
  EXPECT_EQ(a->world.size(), b->world.size());
  const ecs::Entity sun_a = find(*a, "sun"), sun_b = find(*b, "sun");
  ASSERT_TRUE(sun_a.valid() && sun_b.valid());
  EXPECT_EQ(a->world.get<Light>(sun_a).intensity, b->world.get<Light>(sun_b).intensity);
  const glm::quat qa = a->world.get<Transform>(sun_a).rotation;
  const glm::quat qb = b->world.get<Transform>(sun_b).rotation;
  EXPECT_NEAR(std::abs(glm::dot(qa, qb)), 1.0f, 1e-6f);
  EXPECT_EQ(a->shadow_defaults.map_size, b->shadow_defaults.map_size);
}

TEST(SceneIo, ParentsAndModelsRoundTrip) {
  const fs::path p = write_file("parents.json", R"({
    "entities": [
      { "name": "root", "transform": { "translation": [1, 2, 3] } },
      { "name": "child", "transform": { "parent": "root", "euler_deg": [0, 90, 0] },
        "primitive": { "shape": "cone", "segments": 12 }, "renderer": { "cast_shadows": false } },
      { "name": "truck", "model": { "path": ")" + (kContent / "models/Box/glTF-Binary/Box.glb").string() + R"(" } }
    ] })");
  auto s = read_scene(p);
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  const ecs::Entity child = find(*s, "child");
  EXPECT_EQ(s->world.get<Transform>(child).parent, find(*s, "root"));
  EXPECT_FALSE(s->world.get<MeshRenderer>(child).cast_shadows);
  const fs::path out = temp_dir() / "parents_out.json";
  ASSERT_TRUE(save_scene(out, *s).ok());
  auto again = read_scene(out);
  ASSERT_TRUE(again.ok()) << again.error().to_string();
  EXPECT_EQ(again->world.get<Transform>(find(*again, "child")).parent, find(*again, "root"));
  EXPECT_EQ(again->world.get<PrimitiveMesh>(find(*again, "child")).segments, 12);
}

TEST(SceneIo, ModelPathsAreRebasedWhenSavedElsewhere) {
  fs::create_directories(temp_dir() / "a" / "b");
  const fs::path model = fs::absolute(kContent / "models/Box/glTF-Binary/Box.glb");
  fs::copy_file(model, temp_dir() / "a" / "Box.glb", fs::copy_options::overwrite_existing);
  const fs::path p = temp_dir() / "a" / "scene.json";
  std::ofstream(p) << R"({ "entities": [ { "name": "m", "model": { "path": "Box.glb" } } ] })";
  auto s = read_scene(p);
  ASSERT_TRUE(s.ok());
  const fs::path out = temp_dir() / "a" / "b" / "moved.json";
  ASSERT_TRUE(save_scene(out, *s).ok());
  auto moved = read_scene(out);
  ASSERT_TRUE(moved.ok());
  EXPECT_EQ(moved->world.get<ModelRef>(find(*moved, "m")).path, "../Box.glb");
  EXPECT_TRUE(instantiate_scene(*moved).ok());
}

TEST(SceneIo, OverridesChangeSettingsAndComponentFields) {
  auto s = read_scene(kContent / "scenes" / "default.json",
                      {"shadow.map_size=4096", "sun.light.intensity=3.5", "render.width=640",
                       "camera.camera.fov_y_deg=30", "box_floating.transform.translation.1=2.5",
                       "shadow.filter=none"});
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  EXPECT_EQ(s->shadow_defaults.map_size, 4096);
  EXPECT_EQ(s->shadow_defaults.filter, ShadowFilter::none);
  EXPECT_EQ(s->world.get<ShadowSettings>(find(*s, "sun")).map_size, 4096);
  EXPECT_FLOAT_EQ(s->world.get<Light>(find(*s, "sun")).intensity, 3.5f);
  EXPECT_EQ(s->render.width, 640);
  EXPECT_FLOAT_EQ(s->world.get<Camera>(find(*s, "camera")).fov_y_deg, 30.0f);
  EXPECT_FLOAT_EQ(s->world.get<Transform>(find(*s, "box_floating")).translation.y, 2.5f);
}

void expect_error(const Result<Scene>& r, const std::vector<std::string>& parts) {
  ASSERT_FALSE(r.ok());
  const std::string msg = r.error().to_string();
  for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
}

TEST(SceneIo, CascadeFieldsLoadWithRangeChecksAndPerLightOverrides) {
  const fs::path p = temp_dir() / "cascades.json";
  std::ofstream(p) << R"({ "shadow": { "cascade_count": 3, "fit_mode": "crop", "lambda": 0.8,
      "split_scheme": "log", "max_distance": 60, "depth_format": "d32f", "normal_offset_bias": 2,
      "blend_band": 0.2, "selection": "map_bounds", "debug_cascades": true, "beam_radius": 5,
      "point_mode": "dual_paraboloid" },
    "entities": [
      { "name": "sun", "transform": { "direction": [0, -1, 0] },
        "light": { "type": "directional", "cast_shadows": true, "angular_size_deg": 0.53 },
        "shadow": { "cascade_count": 1, "fit_mode": "scene" } } ] })";
  auto s = read_scene(p);
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  const ShadowSettings& d = s->shadow_defaults;
  EXPECT_EQ(d.cascade_count, 3);
  EXPECT_EQ(d.fit_mode, FitMode::crop);
  EXPECT_EQ(d.split_scheme, SplitScheme::log);
  EXPECT_FLOAT_EQ(d.lambda, 0.8f);
  EXPECT_FLOAT_EQ(d.max_distance, 60.0f);
  EXPECT_EQ(d.depth_format, DepthFormat::d32f);
  EXPECT_EQ(d.selection, CascadeSelection::map_bounds);
  EXPECT_TRUE(d.debug_cascades);
  EXPECT_EQ(d.point_mode, PointShadowMode::dual_paraboloid);
  const ShadowSettings& l = s->world.get<ShadowSettings>(find(*s, "sun"));
  EXPECT_EQ(l.cascade_count, 1);
  EXPECT_EQ(l.fit_mode, FitMode::scene);
  EXPECT_FLOAT_EQ(l.lambda, 0.8f);  // the rest from the scene-wide defaults
  // Saved and read again: the same settings (per light only what differs).
  const fs::path out = temp_dir() / "cascades_saved.json";
  ASSERT_TRUE(save_scene(out, *s).ok());
  auto again = read_scene(out);
  ASSERT_TRUE(again.ok()) << again.error().to_string();
  EXPECT_EQ(again->world.get<ShadowSettings>(find(*again, "sun")).fit_mode, FitMode::scene);
  EXPECT_FLOAT_EQ(again->world.get<Light>(find(*again, "sun")).angular_size_deg, 0.53f);
  EXPECT_EQ(again->shadow_defaults.depth_format, DepthFormat::d32f);
  EXPECT_EQ(again->shadow_defaults.point_mode, PointShadowMode::dual_paraboloid);

  const fs::path def = kContent / "scenes" / "default.json";
  expect_error(read_scene(def, {"shadow.cascade_count=9"}), {"/shadow/cascade_count", "9"});
  expect_error(read_scene(def, {"shadow.lambda=1.5"}), {"/shadow/lambda", "1.5"});
  expect_error(read_scene(def, {"shadow.fit_mode=tight"}), {"tight", "stable", "scene"});
  expect_error(read_scene(def, {"shadow.fit_mode=scene"}),
               {"/shadow/fit_mode", "needs cascade_count 1, was 4"});
  expect_error(read_scene(def, {"shadow.blend_band=-0.1"}), {"/shadow/blend_band"});
  expect_error(read_scene(def, {"shadow.normal_offset_bias=17"}), {"/shadow/normal_offset_bias"});
  expect_error(read_scene(def, {"shadow.depth_format=d8"}), {"d8", "d16", "d24", "d32f"});
  expect_error(read_scene(def, {"sun.light.angular_size_deg=50"}), {"/light/angular_size_deg"});
  expect_error(read_scene(def, {"shadow.point_mode=sphere"}),
               {"/shadow/point_mode", "sphere", "cube", "dual_paraboloid"});
}

// The receiver-culling and far-cascade switches: both on by default, off by override, saved
// only when off, and not numbers; the far-cascade interval within [1, 16].
TEST(SceneIo, ReceiverCullingSwitchesLoadAndSave) {
  const fs::path def = kContent / "scenes" / "default.json";
  auto d = read_scene(def);
  ASSERT_TRUE(d.ok()) << d.error().to_string();
  EXPECT_TRUE(d->shadow_defaults.cull_by_receivers);
  EXPECT_TRUE(d->shadow_defaults.scissor_to_receivers);
  auto off = read_scene(def, {"shadow.cull_by_receivers=false", "shadow.scissor_to_receivers=false"});
  ASSERT_TRUE(off.ok()) << off.error().to_string();
  EXPECT_FALSE(off->shadow_defaults.cull_by_receivers);
  EXPECT_FALSE(off->shadow_defaults.scissor_to_receivers);
  const fs::path out = temp_dir() / "switches_saved.json";
  ASSERT_TRUE(save_scene(out, *off).ok());
  auto again = read_scene(out);
  ASSERT_TRUE(again.ok()) << again.error().to_string();
  EXPECT_FALSE(again->shadow_defaults.cull_by_receivers);
  EXPECT_FALSE(again->shadow_defaults.scissor_to_receivers);
  expect_error(read_scene(def, {"shadow.cull_by_receivers=1"}), {"/shadow/cull_by_receivers"});
  auto cadence = read_scene(def, {"shadow.far_cascade_interval=4"});
  ASSERT_TRUE(cadence.ok()) << cadence.error().to_string();
  EXPECT_EQ(cadence->shadow_defaults.far_cascade_interval, 4);
  expect_error(read_scene(def, {"shadow.far_cascade_interval=0"}), {"/shadow/far_cascade_interval", "0"});
  expect_error(read_scene(def, {"shadow.far_cascade_interval=17"}), {"/shadow/far_cascade_interval", "17"});
}

// The soft-shadow settings: shadow.technique, pcf_kernel, pcf_taps, pcf_radius, lom_layers, vsm_blur,
// vsm_bleed_reduction and the spot/point light radius load, save, override and are rejected out of range with the key and the value.
TEST(SceneIo, SoftShadowSettingsLoadSaveAndRejectBadValues) {
  const fs::path def = kContent / "scenes" / "default.json";
  auto s = read_scene(def, {"shadow.technique=pcss", "shadow.pcf_kernel=7", "shadow.pcf_taps=32",
                            "shadow.pcf_radius=4", "sun.light.angular_size_deg=5"});
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  EXPECT_EQ(s->shadow_defaults.technique, ShadowTechnique::pcss);
  EXPECT_EQ(s->shadow_defaults.pcf_kernel, PcfKernel::k7x7);
  EXPECT_EQ(s->shadow_defaults.pcf_taps, 32);
  EXPECT_FLOAT_EQ(s->shadow_defaults.pcf_radius, 4.0f);
  auto p = read_scene(def, {"shadow.pcf_kernel=\"poisson\""});
  ASSERT_TRUE(p.ok()) << p.error().to_string();
  EXPECT_EQ(p->shadow_defaults.pcf_kernel, PcfKernel::poisson);
  auto unquoted = read_scene(def, {"shadow.pcf_kernel=poisson"});
  ASSERT_TRUE(unquoted.ok()) << unquoted.error().to_string();
  EXPECT_EQ(unquoted->shadow_defaults.pcf_kernel, PcfKernel::poisson);
  // Defaults: today's hard 3x3 PCF.
  auto d = read_scene(def);
  ASSERT_TRUE(d.ok());
  EXPECT_EQ(d->shadow_defaults.technique, ShadowTechnique::pcf);
  EXPECT_EQ(d->shadow_defaults.pcf_kernel, PcfKernel::k3x3);

  // Saved and read again, with a spot light's radius.
  const fs::path file = temp_dir() / "soft.json";
  std::ofstream(file) << R"({ "shadow": { "technique": "pcss", "pcf_kernel": "poisson", "pcf_taps": 24,
                               "lom_layers": 5, "vsm_blur": 9, "vsm_bleed_reduction": 0.35 },
    "entities": [
      { "name": "lamp", "transform": { "translation": [0, 4, 0], "direction": [0, -1, 0] },
        "light": { "type": "spot", "cast_shadows": true, "radius": 0.25 },
        "shadow": { "pcf_kernel": 9 } } ] })";
  auto spot = read_scene(file);
  ASSERT_TRUE(spot.ok()) << spot.error().to_string();
  EXPECT_FLOAT_EQ(spot->world.get<Light>(find(*spot, "lamp")).radius, 0.25f);
  EXPECT_EQ(spot->world.get<ShadowSettings>(find(*spot, "lamp")).pcf_kernel, PcfKernel::k9x9);
  const fs::path out = temp_dir() / "soft_saved.json";
  ASSERT_TRUE(save_scene(out, *spot).ok());
  auto again = read_scene(out);
  ASSERT_TRUE(again.ok()) << again.error().to_string();
  EXPECT_FLOAT_EQ(again->world.get<Light>(find(*again, "lamp")).radius, 0.25f);
  EXPECT_EQ(again->shadow_defaults.technique, ShadowTechnique::pcss);
  EXPECT_EQ(again->shadow_defaults.pcf_kernel, PcfKernel::poisson);
  EXPECT_EQ(again->shadow_defaults.pcf_taps, 24);
  EXPECT_EQ(again->shadow_defaults.lom_layers, 5);
  EXPECT_EQ(again->shadow_defaults.vsm_blur, 9);
  EXPECT_FLOAT_EQ(again->shadow_defaults.vsm_bleed_reduction, 0.35f);
  // vsm and evsm by name, and their defaults.
  for (const auto& [name, technique] : {std::pair("vsm", ShadowTechnique::vsm),
                                        std::pair("evsm", ShadowTechnique::evsm)}) {
    auto v = read_scene(def, {std::string("shadow.technique=") + name});
    ASSERT_TRUE(v.ok()) << v.error().to_string();
    EXPECT_EQ(v->shadow_defaults.technique, technique);
    EXPECT_EQ(v->shadow_defaults.vsm_blur, 5);
    EXPECT_FLOAT_EQ(v->shadow_defaults.vsm_bleed_reduction, 0.2f);
  }
  EXPECT_EQ(again->world.get<ShadowSettings>(find(*again, "lamp")).pcf_kernel, PcfKernel::k9x9);

  // An area light: type, size, its cone; size belongs to area lights only, radius not to them.
  const fs::path panel_file = temp_dir() / "panel.json";
  std::ofstream(panel_file) << R"({ "entities": [
      { "name": "panel", "transform": { "translation": [0, 3, 0], "direction": [0, -1, 0] },
        "light": { "type": "area", "size": [2, 0.5], "outer_cone_deg": 70, "cast_shadows": true } },
      { "name": "lamp", "transform": { "translation": [0, 4, 0] }, "light": { "type": "point" } } ] })";
  auto panel = read_scene(panel_file);
  ASSERT_TRUE(panel.ok()) << panel.error().to_string();
  const Light& area = panel->world.get<Light>(find(*panel, "panel"));
  EXPECT_EQ(area.type, LightType::area);
  EXPECT_EQ(area.size, glm::vec2(2.0f, 0.5f));
  const fs::path panel_out = temp_dir() / "panel_saved.json";
  ASSERT_TRUE(save_scene(panel_out, *panel).ok());
  auto panel_again = read_scene(panel_out);
  ASSERT_TRUE(panel_again.ok()) << panel_again.error().to_string();
  EXPECT_EQ(panel_again->world.get<Light>(find(*panel_again, "panel")).size, glm::vec2(2.0f, 0.5f));
  EXPECT_EQ(panel_again->world.get<Light>(find(*panel_again, "panel")).type, LightType::area);
  expect_error(read_scene(panel_file, {"panel.light.size.0=0"}), {"/light/size", "0"});
  expect_error(read_scene(panel_file, {"panel.light.size.1=101"}), {"/light/size", "101"});
  expect_error(read_scene(panel_file, {"panel.light.radius=0.5"}), {"/light/radius", "area", "size"});
  expect_error(read_scene(panel_file, {"panel.light.outer_cone_deg=85"}),
               {"/light/outer_cone_deg", "80", "85"});
  const fs::path sized_point = temp_dir() / "sized_point.json";
  std::ofstream(sized_point) << R"({ "entities": [
      { "name": "lamp", "light": { "type": "point", "size": [1, 1] } } ] })";
  expect_error(read_scene(sized_point), {"sized_point.json", "/light/size", "area"});
  expect_error(read_scene(def, {"shadow.technique=msm"}),
               {"/shadow/technique", "msm", "pcf", "pcss", "backprojection", "lom", "vsm", "evsm"});
  expect_error(read_scene(def, {"shadow.vsm_blur=4"}), {"/shadow/vsm_blur", "odd", "[1, 15]", "4"});
  expect_error(read_scene(def, {"shadow.vsm_blur=0"}), {"/shadow/vsm_blur", "0"});
  expect_error(read_scene(def, {"shadow.vsm_blur=17"}), {"/shadow/vsm_blur", "17"});
  expect_error(read_scene(def, {"shadow.vsm_bleed_reduction=1"}),
               {"/shadow/vsm_bleed_reduction", "[0, 1)", "1"});
  expect_error(read_scene(def, {"shadow.vsm_bleed_reduction=-0.1"}),
               {"/shadow/vsm_bleed_reduction", "-0.1"});
  expect_error(read_scene(def, {"shadow.pcf_kernel=4"}), {"/shadow/pcf_kernel", "3, 5, 7, 9", "4"});
  expect_error(read_scene(def, {"shadow.pcf_kernel=11"}), {"/shadow/pcf_kernel", "11"});
  expect_error(read_scene(def, {"shadow.pcf_kernel=1"}), {"/shadow/pcf_kernel", "1"});
  expect_error(read_scene(def, {"shadow.pcf_kernel=gauss"}), {"/shadow/pcf_kernel", "gauss", "3, 5, 7, 9", "poisson"});
  expect_error(read_scene(def, {"shadow.pcf_kernel=9x9"}), {"/shadow/pcf_kernel", "9x9", "3, 5, 7, 9"});
  expect_error(read_scene(def, {"shadow.pcf_kernel=true"}), {"/shadow/pcf_kernel", "poisson"});
  expect_error(read_scene(def, {"shadow.pcf_taps=7"}), {"/shadow/pcf_taps", "[8, 64]", "7"});
  expect_error(read_scene(def, {"shadow.pcf_taps=65"}), {"/shadow/pcf_taps", "65"});
  expect_error(read_scene(def, {"shadow.pcf_radius=0.5"}), {"/shadow/pcf_radius", "0.5"});
  expect_error(read_scene(def, {"shadow.pcf_radius=17"}), {"/shadow/pcf_radius", "17"});
  expect_error(read_scene(def, {"shadow.lom_layers=1"}), {"/shadow/lom_layers", "[2, 16]", "1"});
  expect_error(read_scene(def, {"shadow.lom_layers=17"}), {"/shadow/lom_layers", "17"});
  expect_error(read_scene(def, {"shadow.technique=layered"}), {"/shadow/technique", "lom"});
  expect_error(read_scene(file, {"lamp.light.radius=-0.1"}), {"/light/radius", "-0.1"});
  expect_error(read_scene(file, {"lamp.light.radius=101"}), {"/light/radius", "101"});
  expect_error(read_scene(file, {"lamp.light.angular_size_deg=1"}),
               {"/light/angular_size_deg", "directional", "radius"});
  expect_error(read_scene(def, {"sun.light.radius=0.5"}), {"/light/radius", "angular_size_deg"});
  // The component checks name the field too (API misuse, not only files).
  ShadowSettings bad;
  bad.pcf_taps = 100;
  EXPECT_EQ(validate_shadow_settings(bad), "pcf_taps must be in [8, 64], was 100");
  bad = {};
  bad.technique = ShadowTechnique(7);
  EXPECT_EQ(validate_shadow_settings(bad),
            "technique must be pcf, pcss, backprojection, lom, vsm or evsm, was 7");
  bad = {};
  bad.vsm_blur = 6;
  EXPECT_EQ(validate_shadow_settings(bad), "vsm_blur must be an odd integer in [1, 15], was 6");
  bad = {};
  bad.vsm_bleed_reduction = 1.0f;
  EXPECT_EQ(validate_shadow_settings(bad), "vsm_bleed_reduction must be in [0, 1), was 1");
  bad = {};
  bad.lom_layers = 1;
  EXPECT_EQ(validate_shadow_settings(bad), "lom_layers must be in [2, 16], was 1");
}

TEST(SceneIo, OverrideErrorsListValidKeys) {
  const fs::path def = kContent / "scenes" / "default.json";
  expect_error(read_scene(def, {"shadow.map_sise=4"}), {"map_sise", "map_size", "filter"});
  expect_error(read_scene(def, {"nobody.light.intensity=1"}), {"nobody", "sun", "render"});
  expect_error(read_scene(def, {"sun.light.colour=1"}), {"colour", "color", "intensity"});
  expect_error(read_scene(def, {"shadow.map_size=1000"}), {"map_size", "power of two", "1000"});
  expect_error(read_scene(def, {"shadow.map_size=big"}), {"map_size", "integer", "string"});
  expect_error(read_scene(def, {"render.width"}), {"key=value"});
  expect_error(read_scene(def, {"sun.transform.translation.7=1"}), {"index"});
  expect_error(read_scene(def, {"shadow.filter=pcf5"}), {"pcf5", "pcf3x3"});
}

TEST(SceneIo, MalformedFilesGiveErrorsNamingFileAndPlace) {
  expect_error(read_scene(write_file("bad1.json", "{\n  \"entities\": [\n    { \"name\": }\n")),
               {"bad1.json", "line 3", "malformed JSON"});
  expect_error(read_scene(write_file("bad2.json", R"({"entities": [{"name": "a", "lihgt": {}}]})")),
               {"bad2.json", "/entities/0/lihgt", "unknown key", "light"});
  expect_error(read_scene(write_file("bad3.json", R"({"entities": [{"light": {"intensity": "bright"}}]})")),
               {"bad3.json", "/entities/0/light/intensity", "expected a number"});
  expect_error(read_scene(write_file("bad4.json", R"({"entities": [{"light": {"type": "laser"}}]})")),
               {"/entities/0/light/type", "laser", "directional", "area"});
  expect_error(read_scene(write_file("bad5.json", R"({"entities": [{"camera": {"near": 10, "far": 1}}]})")),
               {"/entities/0/camera/far", "greater than near"});
  expect_error(read_scene(write_file("bad6.json", R"({"entities": [{"transform": {"parent": "ghost"}}]})")),
               {"/entities/0/transform/parent", "ghost"});
  expect_error(read_scene(write_file("bad7.json", R"({"entities": [{"name": "x"}, {"name": "x"}]})")),
               {"/entities/1/name", "duplicate"});
  expect_error(read_scene(write_file("bad8.json", R"({"entities": {}})")), {"/entities", "array"});
  expect_error(read_scene(write_file("bad9.json", R"([1, 2])")), {"bad9.json", "object"});
  expect_error(read_scene(write_file("bad10.json", R"({"entities": [{"transform": {"scale": [1, 2]}}]})")),
               {"/entities/0/transform/scale", "3 numbers"});
  expect_error(read_scene(write_file("bad11.json", R"({"kaskad_scene": 99})")), {"kaskad_scene", "99"});
  expect_error(read_scene(write_file("bad12.json", "")), {"bad12.json", "malformed JSON"});
  expect_error(read_scene(temp_dir() / "does_not_exist.json"), {"does_not_exist.json", "cannot open"});
  expect_error(read_scene(write_file("bad.txt", "{}")), {"bad.txt", ".json"});
  expect_error(read_scene(write_file("bad13.json",
                                     R"({"entities": [{"primitive": {"shape": "box", "tiles": 2}}]})")),
               {"/entities/0/primitive/tiles", "terrain"});
  expect_error(read_scene(write_file("bad14.json",
                                     R"({"entities": [{"primitive": {"shape": "terrain", "segments": 30, "tiles": 4}}]})")),
               {"/entities/0/primitive/tiles", "multiple"});
}

// A model entity's renderer flags, layer included, apply to every mesh imported under it.
TEST(SceneIo, ModelRendererFlagsAndLayerReachImportedMeshes) {
  const fs::path file = write_file("layered_model.json", R"({"entities": [{"name": "m",
      "model": {"path": ")" + (kContent / "models/Box/glTF-Binary/Box.glb").string() + R"("},
      "renderer": {"cast_shadows": false, "layer": 5}}]})");
  auto scene = read_scene(file);
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  ASSERT_TRUE(instantiate_scene(*scene).ok());
  int meshes = 0;
  scene->world.view<MeshRenderer>().each([&](ecs::Entity, const MeshRenderer& mr) {
    if (mr.mesh == kNoMesh) return;
    ++meshes;
    EXPECT_EQ(mr.layer, 5);
    EXPECT_FALSE(mr.cast_shadows);
  });
  EXPECT_GT(meshes, 0);
}

// Several entities naming one glTF file read it once: every instance gets its own entity tree
// (names, parents inside its own tree, its own renderer flags) over the same meshes and
// materials, so the renderer uploads them once and draws them instanced.
TEST(SceneIo, InstancesOfOneModelShareItsMeshes) {
  const std::string model = (kContent / "models/CesiumMilkTruck/glTF/CesiumMilkTruck.gltf").string();
  auto scene_with = [&](int n) {
    std::string entities;
    for (int i = 0; i < n; ++i)
      entities += std::string(i ? "," : "") + R"({"name": "truck)" + std::to_string(i) +
                  R"(", "transform": {"translation": [)" + std::to_string(4 * i) +
                  R"(, 0, 0]}, "model": {"path": ")" + model + R"("}, "renderer": {"layer": )" +
                  std::to_string(i) + "}}";
    auto scene = read_scene(write_file("trucks_" + std::to_string(n) + ".json",
                                       R"({"entities": [)" + entities + "]}"));
    EXPECT_TRUE(scene.ok()) << scene.error().to_string();
    if (scene.ok()) {
      EXPECT_TRUE(instantiate_scene(*scene).ok());
    }
    return scene;
  };
  auto one = scene_with(1), three = scene_with(3);
  ASSERT_TRUE(one.ok() && three.ok());
  EXPECT_EQ(three->assets.meshes.size(), one->assets.meshes.size());
  EXPECT_EQ(three->assets.textures.size(), one->assets.textures.size());
  // Per instance: the same number of imported entities with the same names and meshes, parents
  // in the instance's own tree, the instance's layer.
  std::map<std::uint32_t, std::vector<std::string>> names;   // by instance entity index
  std::map<std::uint32_t, std::multiset<MeshId>> meshes;
  three->world.view<Imported>().each([&](ecs::Entity e, const Imported& imp) {
    names[imp.source.index].push_back(three->world.get<Name>(e).value);
    const ecs::Entity parent = three->world.get<Transform>(e).parent;
    const bool in_own_tree = parent == imp.source ||
                             (three->world.has<Imported>(parent) &&
                              three->world.get<Imported>(parent).source == imp.source);
    EXPECT_TRUE(in_own_tree) << three->world.get<Name>(e).value;
    if (const auto* mr = three->world.try_get<MeshRenderer>(e)) {
      meshes[imp.source.index].insert(mr->mesh);
      EXPECT_EQ(mr->layer, int(imp.source.index));  // truck i is entity i, layer i
    }
  });
  ASSERT_EQ(names.size(), 3u);
  for (auto& [source, list] : names) std::sort(list.begin(), list.end());
  EXPECT_EQ(names[1], names[0]);
  EXPECT_EQ(names[2], names[0]);
  EXPECT_EQ(meshes[1], meshes[0]);
  EXPECT_EQ(meshes[2], meshes[0]);
  EXPECT_FALSE(meshes[0].empty());
}

// A tiled terrain instantiates one entity per tile (the authored one plus imported children with
// its material and renderer flags), and saves back as the one primitive it was.
TEST(SceneIo, TiledTerrainBecomesTileEntitiesAndSavesAsOnePrimitive) {
  const fs::path file = write_file("tiled.json", R"({"entities": [{"name": "ground",
      "primitive": {"shape": "terrain", "segments": 16, "tiles": 4},
      "renderer": {"cast_shadows": false},
      "material": {"base_color": [0.2, 0.4, 0.6, 1]}}]})");
  auto scene = read_scene(file);
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  ASSERT_TRUE(instantiate_scene(*scene).ok());
  int tiles = 0;
  std::size_t triangles = 0;
  scene->world.view<MeshRenderer>().each([&](ecs::Entity e, const MeshRenderer& mr) {
    ++tiles;
    triangles += scene->assets.meshes[index(mr.mesh)].triangle_count();
    EXPECT_FALSE(mr.cast_shadows);
    EXPECT_EQ(scene->world.get<Material>(e).base_color, glm::vec4(0.2f, 0.4f, 0.6f, 1.0f));
  });
  EXPECT_EQ(tiles, 16);
  EXPECT_EQ(triangles, 2u * 16u * 16u);
  const fs::path out = temp_dir() / "tiled_saved.json";
  ASSERT_TRUE(save_scene(out, *scene).ok());
  const std::string saved = read_file(out);
  EXPECT_NE(saved.find("\"tiles\": 4"), std::string::npos);
  auto again = read_scene(out);
  ASSERT_TRUE(again.ok()) << again.error().to_string();
  EXPECT_EQ(again->world.view<PrimitiveMesh>().size_hint(), 1u);
}

TEST(SceneIo, MissingModelIsAnErrorAtInstantiation) {
  auto s = read_scene(write_file("missing_model.json",
                                 R"({"entities": [{"name": "m", "model": {"path": "nowhere.glb"}}]})"));
  ASSERT_TRUE(s.ok());
  Status st = instantiate_scene(*s);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().to_string().find("nowhere.glb"), std::string::npos) << st.error().to_string();
  // The scene file and the entity that names the model come first.
  EXPECT_LT(st.error().to_string().find("missing_model.json: /m/model/path: "),
            st.error().to_string().find("nowhere.glb"))
      << st.error().to_string();
}

TEST(SceneIo, GltfFileIsWrappedWithDefaultCameraAndSun) {
  auto s = read_scene(kContent / "models/Box/glTF-Binary/Box.glb");
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  EXPECT_TRUE(find(*s, "camera").valid());
  EXPECT_TRUE(find(*s, "sun").valid());
  EXPECT_TRUE(s->world.get<Camera>(find(*s, "camera")).auto_frame);
  EXPECT_TRUE(s->world.get<Light>(find(*s, "sun")).cast_shadows);
  EXPECT_EQ(s->render.ground, GroundMode::on);  // saved as such: the saved file renders the same
  auto overridden = read_scene(kContent / "models/Box/glTF-Binary/Box.glb", {"sun.light.intensity=7"});
  ASSERT_TRUE(overridden.ok()) << overridden.error().to_string();
  EXPECT_FLOAT_EQ(overridden->world.get<Light>(find(*overridden, "sun")).intensity, 7.0f);
}

TEST(SceneIo, SaveToUnwritablePlaceFailsCleanly) {
  auto s = read_scene(kContent / "scenes" / "default.json");
  ASSERT_TRUE(s.ok());
  Status st = save_scene(temp_dir() / "no" / "such" / "dir" / "x.json", *s);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().to_string().find("x.json"), std::string::npos);
}

}  // namespace
}  // namespace kaskad

namespace kaskad {
namespace {

TEST(SceneIo, GltfMaterialsMapOntoFeatureBits) {
  auto s = read_scene(kContent / "models/CesiumMilkTruck/glTF/CesiumMilkTruck.gltf");
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  ASSERT_TRUE(instantiate_scene(*s).ok());
  int textured = 0, plain = 0;
  s->world.view<Material>().each([&](ecs::Entity, const Material& m) {
    EXPECT_EQ(m.features, derive_material_features(m));
    if (m.base_color_texture != kNoTexture) {
      EXPECT_TRUE(m.features & 1u);  // VariantKey::kBaseColorTexture
      ++textured;
    } else {
      ++plain;
    }
  });
  EXPECT_GT(textured, 0);
  EXPECT_GT(plain, 0);
}

TEST(SceneIo, ReflectorsRoundTripAndOverride) {
  auto a = read_scene(kContent / "scenes" / "reflections.json",
                      {"mirror_sphere.reflector.faces_per_frame=2", "mirror_plane.reflector.map=sphere"});
  ASSERT_TRUE(a.ok()) << a.error().to_string();
  const ecs::Entity sphere = find(*a, "mirror_sphere"), plane = find(*a, "mirror_plane");
  ASSERT_TRUE(sphere.valid() && plane.valid());
  const Reflector& r = a->world.get<Reflector>(sphere);
  EXPECT_EQ(r.update, ProbeUpdate::every_n);
  EXPECT_EQ(r.every_n, 10);
  EXPECT_EQ(r.faces_per_frame, 2);
  EXPECT_FLOAT_EQ(r.amount, 0.9f);
  EXPECT_EQ(a->world.get<Reflector>(plane).map, ReflectionMap::sphere);
  EXPECT_FLOAT_EQ(a->world.get<Material>(plane).k_s, 0.9f);
  // Explicit centre and excluded layers survive a save and load, byte for byte.
  a->world.get<Reflector>(plane).has_center = true;
  a->world.get<Reflector>(plane).center = {0.5f, 1.5f, -4.25f};
  a->world.get<Reflector>(plane).exclude_layers = (1u << 3) | (1u << 31);
  a->world.get<Reflector>(plane).box_projection = true;
  a->world.get<Reflector>(plane).box_min = {-5, 0, -9};
  a->world.get<Reflector>(plane).box_max = {5, 4.5f, 1};
  const fs::path first = temp_dir() / "refl1.json", second = temp_dir() / "refl2.json";
  ASSERT_TRUE(save_scene(first, *a).ok());
  auto b = read_scene(first);
  ASSERT_TRUE(b.ok()) << b.error().to_string();
  ASSERT_TRUE(save_scene(second, *b).ok());
  EXPECT_EQ(read_file(first), read_file(second));
  const Reflector& rb = b->world.get<Reflector>(find(*b, "mirror_plane"));
  EXPECT_TRUE(rb.has_center);
  EXPECT_EQ(rb.center, glm::vec3(0.5f, 1.5f, -4.25f));
  EXPECT_EQ(rb.exclude_layers, (1u << 3) | (1u << 31));
  EXPECT_TRUE(rb.box_projection);
  EXPECT_EQ(rb.box_max, glm::vec3(5, 4.5f, 1));
  // The optional fields are in the canonical form as "auto" and "none", so that --set and the
  // editor's inspector reach them: set, then set back.
  const nlohmann::json plain = scene_to_json(*a)["entities"];
  const auto sphere_doc = std::find_if(plain.begin(), plain.end(), [](const nlohmann::json& e) {
    return e["name"] == "mirror_sphere";
  });
  ASSERT_NE(sphere_doc, plain.end());
  EXPECT_EQ((*sphere_doc)["reflector"]["center"], "auto");
  EXPECT_EQ((*sphere_doc)["reflector"]["box"], "none");
  ASSERT_TRUE(apply_live_override(*b, "mirror_plane.reflector.center=auto").ok());
  ASSERT_TRUE(apply_live_override(*b, "mirror_plane.reflector.box=none").ok());
  EXPECT_FALSE(b->world.get<Reflector>(find(*b, "mirror_plane")).has_center);
  EXPECT_FALSE(b->world.get<Reflector>(find(*b, "mirror_plane")).box_projection);
  ASSERT_TRUE(apply_live_override(*b, "mirror_plane.reflector.center=[1,2,3]").ok());
  ASSERT_TRUE(apply_live_override(
                  *b, R"(mirror_plane.reflector.box={"min": [-4, 0, -4], "max": [4, 4, 4]})")
                  .ok());
  EXPECT_EQ(b->world.get<Reflector>(find(*b, "mirror_plane")).center, glm::vec3(1, 2, 3));
  EXPECT_TRUE(b->world.get<Reflector>(find(*b, "mirror_plane")).box_projection);
  EXPECT_EQ(b->world.get<Reflector>(find(*b, "mirror_plane")).box_min, glm::vec3(-4, 0, -4));
  auto wrong = apply_live_override(*b, "mirror_plane.reflector.center=middle");
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.error().to_string().find(R"(expected [x, y, z] or "auto")"), std::string::npos)
      << wrong.error().to_string();
  wrong = apply_live_override(*b, "mirror_plane.reflector.box=off");
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.error().to_string().find(R"(or "none")"), std::string::npos)
      << wrong.error().to_string();
}

TEST(SceneIo, BadReflectorsNameTheKey) {
  auto bad = [](const std::string& reflector) {
    const std::string text = R"({"kaskad_scene": 1, "entities": [{"primitive": {"shape": "sphere"}, "reflector": )" +
                             reflector + "}]}";
    auto s = read_scene(write_file("bad_reflector.json", text));
    EXPECT_FALSE(s.ok()) << reflector;
    return s.ok() ? std::string() : s.error().to_string();
  };
  EXPECT_NE(bad(R"({"faces_per_frame": 7})").find("/entities/0/reflector/faces_per_frame"), std::string::npos);
  EXPECT_NE(bad(R"({"resolution": 100})").find("resolution must be a power of two"), std::string::npos);
  EXPECT_NE(bad(R"({"near": 5, "far": 2})").find("/entities/0/reflector/far"), std::string::npos);
  EXPECT_NE(bad(R"({"update": "sometimes"})").find("unknown value 'sometimes'"), std::string::npos);
  EXPECT_NE(bad(R"({"update": "static_file"})").find("/entities/0/reflector/file"), std::string::npos);
  EXPECT_NE(bad(R"({"exclude_layers": [40]})").find("/entities/0/reflector/exclude_layers/0"), std::string::npos);
  EXPECT_NE(bad(R"({"amount": 1.5})").find("/entities/0/reflector/amount"), std::string::npos);
  EXPECT_NE(bad(R"({"mirror": true})").find("unknown key 'mirror'"), std::string::npos);
  EXPECT_NE(bad(R"({"box": {"min": [0, 0, 0], "max": [1, -1, 1]}})").find("/entities/0/reflector/box"), std::string::npos);
  EXPECT_NE(bad(R"({"box": {"min": [0, 0, 0]}})").find("a box needs min and max"), std::string::npos);
  EXPECT_NE(bad(R"({"center": [5, 0, 0], "box": {"min": [-1, -1, -1], "max": [1, 1, 1]}})")
                .find("box must contain the capture centre"), std::string::npos);
  auto s = read_scene(write_file("reflector_no_mesh.json",
                                 R"({"kaskad_scene": 1, "entities": [{"reflector": {}}]})"));
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().to_string().find("needs a primitive or model"), std::string::npos);
}

}  // namespace
}  // namespace kaskad

namespace kaskad {
namespace {

TEST(SceneIo, FirstDirectionalLightCastsShadowsUnlessTheFileSaysFalse) {
  const char* two_suns = R"({"entities": [
    {"name": "a", "light": {"type": "point"}},
    {"name": "b", "light": {"type": "directional"}},
    {"name": "c", "light": {"type": "directional"}}]})";
  auto s = read_scene(write_file("two_suns_default.json", two_suns));
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  EXPECT_FALSE(s->world.get<Light>(find(*s, "a")).cast_shadows);  // not directional
  EXPECT_TRUE(s->world.get<Light>(find(*s, "b")).cast_shadows);   // the first directional
  EXPECT_FALSE(s->world.get<Light>(find(*s, "c")).cast_shadows);
  auto off = read_scene(write_file("sun_off.json", R"({"entities": [
    {"name": "b", "light": {"type": "directional", "cast_shadows": false}}]})"));
  ASSERT_TRUE(off.ok()) << off.error().to_string();
  EXPECT_FALSE(off->world.get<Light>(find(*off, "b")).cast_shadows);
  // A saved scene says it explicitly, so it loads the same.
  const fs::path out = temp_dir() / "two_suns_saved.json";
  ASSERT_TRUE(save_scene(out, *s).ok());
  auto again = read_scene(out);
  ASSERT_TRUE(again.ok()) << again.error().to_string();
  EXPECT_TRUE(again->world.get<Light>(find(*again, "b")).cast_shadows);
}

TEST(SceneIo, OverridesTakeDirectionLookAtAndEulerForRotation) {
  auto s = read_scene(kContent / "scenes" / "default.json",
                      {"sun.transform.direction=[0,-1,0.0001]", "camera.transform.look_at=[0,0,0]",
                       "box_resting.transform.euler_deg=[0,90,0]"});
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  const glm::vec3 sun_dir = s->world.get<Transform>(find(*s, "sun")).rotation * glm::vec3(0, 0, -1);
  EXPECT_NEAR(sun_dir.y, -1.0f, 1e-4f);
  const Transform& cam = s->world.get<Transform>(find(*s, "camera"));
  const glm::vec3 to_origin = glm::normalize(-cam.translation);
  const glm::vec3 cam_dir = cam.rotation * glm::vec3(0, 0, -1);
  EXPECT_NEAR(glm::dot(cam_dir, to_origin), 1.0f, 1e-5f);
  const glm::vec3 box_x = s->world.get<Transform>(find(*s, "box_resting")).rotation * glm::vec3(1, 0, 0);
  EXPECT_NEAR(box_x.z, -1.0f, 1e-5f);
  // A field that no form has is still an error that lists the forms.
  expect_error(read_scene(kContent / "scenes" / "default.json", {"sun.transform.aim=[0,-1,0]"}),
               {"aim", "direction", "look_at"});
}

// A glTF with a directional light on a node whose name has a dot, and no meshes.
const char* kLitGltf = R"({"asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 3}]}},
  "nodes": [{"name": "Sun.001", "extensions": {"KHR_lights_punctual": {"light": 0}}}],
  "scenes": [{"nodes": [0]}], "scene": 0})";

TEST(SceneIo, ImportedLightsTakeTheSceneShadowSettingsAndAnswerToSetByNodeName) {
  write_file("lit.gltf", kLitGltf);
  const fs::path file = write_file(
      "lit_scene.json",
      R"({"shadow": {"map_size": 1024}, "entities": [{"name": "m", "model": {"path": "lit.gltf"}}]})");
  std::vector<std::string> later;
  auto s = read_scene(file,
                      {"shadow.cascade_count=3", "Sun.001.light.intensity=2",
                       "Sun.001.shadow.filter=none", "Sun.001.transform.direction=[1,-1,0]"},
                      &later);
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  ASSERT_EQ(later.size(), 3u);  // the node does not exist before instantiation
  ASSERT_TRUE(instantiate_scene(*s).ok());
  const ecs::Entity sun = find(*s, "Sun.001");
  ASSERT_TRUE(sun.valid());
  // Scene-wide settings, --set shadow.* included, reach the imported light.
  EXPECT_EQ(s->world.get<ShadowSettings>(sun).map_size, 1024);
  EXPECT_EQ(s->world.get<ShadowSettings>(sun).cascade_count, 3);
  EXPECT_TRUE(s->world.get<Light>(sun).cast_shadows);
  for (const std::string& o : later) ASSERT_TRUE(apply_entity_override(*s, o).ok()) << o;
  EXPECT_FLOAT_EQ(s->world.get<Light>(sun).intensity, 2.0f);
  EXPECT_EQ(s->world.get<ShadowSettings>(sun).filter, ShadowFilter::none);
  EXPECT_EQ(s->world.get<ShadowSettings>(sun).map_size, 1024);  // the rest is kept
  const glm::vec3 d = s->world.get<Transform>(sun).rotation * glm::vec3(0, 0, -1);
  EXPECT_NEAR(d.x, std::sqrt(0.5f), 1e-5f);
  // Bad values and unknown names are errors naming the key and listing what exists.
  auto bad = apply_entity_override(*s, "Sun.001.light.intensity=-1");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().to_string().find("intensity"), std::string::npos) << bad.error().to_string();
  auto unknown = apply_entity_override(*s, "Moon.light.intensity=1");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().to_string().find("Sun.001"), std::string::npos)
      << unknown.error().to_string();
  auto section = apply_entity_override(*s, "Sun.001.reflector.amount=1");
  ASSERT_FALSE(section.ok());
  EXPECT_NE(section.error().to_string().find("valid keys here: light, shadow, transform"),
            std::string::npos)
      << section.error().to_string();
}

// A model's nodes block: the scene's own settings of a glTF file's nodes, applied over what the
// file gives, kept by scene_to_json (so an editor save keeps edits of imported nodes), per model
// entity (two instances of a file take their own), and errors that name the place.
TEST(SceneIo, ModelNodeSettingsApplyOverTheFileAndSaveWithTheModel) {
  write_file("lit.gltf", kLitGltf);
  const fs::path file = write_file("nodes_scene.json", R"({"entities": [
      {"name": "m", "model": {"path": "lit.gltf", "nodes": {
          "Sun.001": {"light": {"intensity": 5}, "transform": {"direction": [0, -1, 0]}},
          "Moon": {"light": {"intensity": 2}}}}},
      {"name": "m2", "model": {"path": "lit.gltf", "nodes": {
          "Sun.001": {"renderer": {}, "light": {"color": [0, 1, 0]}}}}}]})");
  auto loaded = read_scene(file);
  ASSERT_TRUE(loaded.ok()) << loaded.error().to_string();
  // Sun.001 has no renderer: m2's block names a section the node lacks.
  auto lacking = instantiate_scene(*loaded);
  ASSERT_FALSE(lacking.ok());
  EXPECT_NE(lacking.error().to_string().find("/entities/1/model/nodes/Sun.001/renderer"),
            std::string::npos)
      << lacking.error().to_string();
  std::string text = read_file(file);
  text.replace(text.find(R"("renderer": {}, )"), std::string(R"("renderer": {}, )").size(), "");
  write_file("nodes_scene.json", text);

  auto s = read_scene(file);
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  ASSERT_TRUE(instantiate_scene(*s).ok());
  std::vector<ecs::Entity> suns;
  s->world.view<Light>().each([&](ecs::Entity e, const Light&) { suns.push_back(e); });
  ASSERT_EQ(suns.size(), 2u);
  std::sort(suns.begin(), suns.end(),
            [](ecs::Entity a, ecs::Entity b) { return a.index < b.index; });
  const Light& first = s->world.get<Light>(suns[0]);
  const Light& second = s->world.get<Light>(suns[1]);
  EXPECT_FLOAT_EQ(first.intensity, 5.0f);
  EXPECT_EQ(first.color, glm::vec3(1.0f));  // what the file gives, where the block is silent
  EXPECT_FLOAT_EQ(second.intensity, 3.0f);  // the other instance: only its own block
  EXPECT_EQ(second.color, glm::vec3(0.0f, 1.0f, 0.0f));
  const glm::vec3 down = s->world.get<Transform>(suns[0]).rotation * glm::vec3(0, 0, -1);
  EXPECT_NEAR(down.y, -1.0f, 1e-6f);

  // Written back with each set field's value as the node has it (the rotation in its saved
  // form); a node the file does not have keeps its block as it was read.
  nlohmann::json doc = scene_to_json(*s);
  const nlohmann::json& nodes = doc["entities"][0]["model"]["nodes"];
  EXPECT_EQ(nodes["Sun.001"]["light"], nlohmann::json::parse(R"({"intensity": 5.0})"));
  ASSERT_TRUE(nodes["Sun.001"]["transform"].contains("rotation"));
  EXPECT_EQ(nodes["Sun.001"]["transform"].size(), 1u);
  EXPECT_EQ(nodes["Moon"], nlohmann::json::parse(R"({"light": {"intensity": 2}})"));
  EXPECT_EQ(doc["entities"][1]["model"]["nodes"]["Sun.001"],
            nlohmann::json::parse(R"({"light": {"color": [0.0, 1.0, 0.0]}})"));

  // A --set (or editor) edit of a node is kept too, with the fields set before it. Both instances
  // name their sun "Sun.001", so only a unique name can be set: rename one model away first.
  ASSERT_TRUE(remove_entity(*s, "m2").ok());
  ASSERT_TRUE(apply_entity_override(*s, "Sun.001.light.color=[1,0,0]").ok());
  ASSERT_TRUE(apply_entity_override(*s, "Sun.001.shadow.filter=none").ok());
  ASSERT_TRUE(apply_entity_override(*s, "Sun.001.transform.translation.1=7").ok());
  doc = scene_to_json(*s);
  const nlohmann::json& edited = doc["entities"][0]["model"]["nodes"]["Sun.001"];
  EXPECT_EQ(edited["light"],
            nlohmann::json::parse(R"({"intensity": 5.0, "color": [1.0, 0.0, 0.0]})"));
  EXPECT_EQ(edited["shadow"], nlohmann::json::parse(R"({"filter": "none"})"));
  EXPECT_EQ(edited["transform"]["translation"], nlohmann::json::parse("[0.0, 7.0, 0.0]"));
  EXPECT_TRUE(edited["transform"].contains("rotation"));

  // save -> load -> save: the same bytes, the same values.
  const fs::path saved = temp_dir() / "nodes_saved.json";
  ASSERT_TRUE(save_scene(saved, *s).ok());
  auto again = read_scene(saved);
  ASSERT_TRUE(again.ok()) << again.error().to_string();
  ASSERT_TRUE(instantiate_scene(*again).ok());
  const ecs::Entity sun = find(*again, "Sun.001");
  ASSERT_TRUE(sun.valid());
  EXPECT_EQ(again->world.get<Light>(sun).color, glm::vec3(1.0f, 0.0f, 0.0f));
  EXPECT_EQ(again->world.get<ShadowSettings>(sun).filter, ShadowFilter::none);
  EXPECT_FLOAT_EQ(again->world.get<Transform>(sun).translation.y, 7.0f);
  const fs::path resaved = temp_dir() / "nodes_resaved.json";
  ASSERT_TRUE(save_scene(resaved, *again).ok());
  EXPECT_EQ(read_file(saved), read_file(resaved));

  // entity_for_key() resolves a key as the overrides do: the longest name, unique.
  auto sun_key = entity_for_key(*s, "Sun.001.light.color");
  ASSERT_TRUE(sun_key.ok()) << sun_key.error().to_string();
  EXPECT_EQ(sun_key.value(), find(*s, "Sun.001"));
  EXPECT_FALSE(entity_for_key(*s, "Sun.light.color").ok());

  // Two nodes of one name in one model: a note of either is not kept (it could not be read back
  // to one of them), and nothing empty is written.
  write_file("twins.gltf", R"({"asset": {"version": "2.0"},
    "nodes": [{"name": "twin"}, {"name": "twin"}], "scenes": [{"nodes": [0, 1]}], "scene": 0})");
  auto twins = read_scene(write_file(
      "twins_scene.json", R"({"entities": [{"name": "t", "model": {"path": "twins.gltf"}}]})"));
  ASSERT_TRUE(twins.ok());
  ASSERT_TRUE(instantiate_scene(*twins).ok());
  std::vector<ecs::Entity> twin_nodes;
  twins->world.view<Name>().each([&](ecs::Entity e, const Name& n) {
    if (n.value == "twin") twin_nodes.push_back(e);
  });
  ASSERT_EQ(twin_nodes.size(), 2u);
  note_node_override(*twins, twin_nodes[0], "transform", {"translation"});
  EXPECT_FALSE(scene_to_json(*twins)["entities"][0]["model"].contains("nodes"));

  // Bad blocks are errors naming the file and the place.
  auto error_of = [&](const std::string& nodes_block) {
    const fs::path bad = write_file("nodes_bad.json", R"({"entities": [{"name": "m", "model":
        {"path": "lit.gltf", "nodes": )" + nodes_block + "}}]}");
    auto r = read_scene(bad);
    if (r.ok()) {
      Status st = instantiate_scene(*r);
      return st.ok() ? std::string() : st.error().to_string();
    }
    return r.error().to_string();
  };
  std::string e = error_of(R"({"Sun.001": {"material": {}}})");
  EXPECT_NE(e.find("/entities/0/model/nodes/Sun.001/material"), std::string::npos) << e;
  EXPECT_NE(e.find("transform, light, shadow, camera and renderer"), std::string::npos) << e;
  e = error_of(R"({"Sun.001": {"light": {"intensity": -1}}})");
  EXPECT_NE(e.find("nodes_bad.json"), std::string::npos) << e;
  EXPECT_NE(e.find("/entities/0/model/nodes/Sun.001/light/intensity"), std::string::npos) << e;
  e = error_of(R"({"Sun.001": {"transform": {"parent": "m"}}})");
  EXPECT_NE(e.find("keeps its parent"), std::string::npos) << e;
  e = error_of(R"([1])");
  EXPECT_NE(e.find("/entities/0/model/nodes"), std::string::npos) << e;
}

TEST(SceneIo, AParentCycleIsALoadErrorNamingTheChain) {
  expect_error(read_scene(write_file("cycle.json", R"({"entities": [
    {"name": "a", "transform": {"parent": "c"}},
    {"name": "b", "transform": {"parent": "a"}},
    {"name": "c", "transform": {"parent": "b"}}]})")),
               {"cycle.json", "/entities/0/transform/parent", "parent cycle: a -> c -> b -> a"});
}

TEST(SceneIo, GroundCoversTheFootprintAndTheShadowOfTheBounds) {
  const Aabb model = Aabb::from_corners({-1, 2, -1}, {1, 4, 1});  // 2 m tall, floating at 2
  // Straight down: the footprint plus a quarter of the size (|extent| = sqrt(12)) around.
  const Aabb down = ground_extent(model, {0, -1, 0});
  const float margin = 0.25f * std::sqrt(12.0f);
  EXPECT_NEAR(down.min.x, -1.0f - margin, 1e-5f);
  EXPECT_NEAR(down.max.z, 1.0f + margin, 1e-5f);
  EXPECT_NEAR(down.min.y, 2.0f, 1e-3f);
  EXPECT_LT(down.min.y, 2.0f);  // just under the lowest point
  // 45 degrees towards +x: the top's shadow lands 2 m further along +x.
  const Aabb slanted = ground_extent(model, glm::normalize(glm::vec3(1, -1, 0)));
  EXPECT_NEAR(slanted.max.x, 1.0f + 2.0f + margin, 1e-4f);
  EXPECT_NEAR(slanted.min.x, -1.0f - margin, 1e-4f);
  // A grazing light is taken at about 14 degrees: a shadow 4x the height long, not infinite.
  const Aabb grazing = ground_extent(model, glm::normalize(glm::vec3(1, -0.01f, 0)));
  EXPECT_LT(grazing.max.x, 1.0f + 4.0f * 2.0f + margin + 1e-3f);
  EXPECT_GT(grazing.max.x, 1.0f + 3.8f * 2.0f);
}

}  // namespace
}  // namespace kaskad

namespace kaskad {
namespace {

TEST(SceneIo, LiveOverridesChangeALoadedSceneAsAFileWould) {
  // Two suns: "a" takes the scene-wide filter, "b" overrides it in its own block.
  auto s = read_scene(write_file("live.json", R"({"shadow": {"filter": "pcf3x3"}, "entities": [
    {"name": "a", "light": {"type": "directional", "cast_shadows": true}},
    {"name": "b", "light": {"type": "directional", "cast_shadows": true}, "shadow": {"filter": "none"}},
    {"name": "box", "primitive": {"shape": "box"}}]})"));
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  { auto st = apply_live_override(*s, "shadow.filter=bilinear"); ASSERT_TRUE(st.ok()) << st.error().to_string(); }
  ASSERT_TRUE(apply_live_override(*s, "shadow.cascade_count=2").ok());
  EXPECT_EQ(s->shadow_defaults.filter, ShadowFilter::bilinear);
  EXPECT_EQ(s->world.get<ShadowSettings>(find(*s, "a")).filter, ShadowFilter::bilinear);
  EXPECT_EQ(s->world.get<ShadowSettings>(find(*s, "b")).filter, ShadowFilter::none);  // its own
  EXPECT_EQ(s->world.get<ShadowSettings>(find(*s, "b")).cascade_count, 2);
  ASSERT_TRUE(apply_live_override(*s, "render.exposure=0.5").ok());
  EXPECT_FLOAT_EQ(s->render.exposure, 0.5f);
  ASSERT_TRUE(apply_live_override(*s, "box.transform.translation.1=3").ok());
  EXPECT_FLOAT_EQ(s->world.get<Transform>(find(*s, "box")).translation.y, 3.0f);
  // A bad value is an error and changes nothing.
  auto bad = apply_live_override(*s, "shadow.cascade_count=12");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().to_string().find("cascade_count"), std::string::npos);
  EXPECT_EQ(s->shadow_defaults.cascade_count, 2);
  EXPECT_EQ(s->world.get<ShadowSettings>(find(*s, "a")).cascade_count, 2);
}

TEST(SceneIo, ExposureInEv) {
  // exposure_ev is 2^EV; the saved form is the scale; `exposure` alone keeps working.
  auto s =
      read_scene(write_file("ev.json", R"({"render": {"exposure_ev": -1.5}, "entities": []})"));
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  EXPECT_FLOAT_EQ(s->render.exposure, std::exp2(-1.5f));
  EXPECT_FLOAT_EQ(scene_to_json(*s)["render"]["exposure"].get<float>(), std::exp2(-1.5f));
  EXPECT_FALSE(scene_to_json(*s)["render"].contains("exposure_ev"));
  auto plain =
      read_scene(write_file("ev_plain.json", R"({"render": {"exposure": 0.25}, "entities": []})"));
  ASSERT_TRUE(plain.ok()) << plain.error().to_string();
  EXPECT_FLOAT_EQ(plain->render.exposure, 0.25f);
  // Live: an EV replaces the scale, and back.
  ASSERT_TRUE(apply_live_override(*s, "render.exposure_ev=2").ok());
  EXPECT_FLOAT_EQ(s->render.exposure, 4.0f);
  ASSERT_TRUE(apply_live_override(*s, "render.exposure=0.5").ok());
  EXPECT_FLOAT_EQ(s->render.exposure, 0.5f);
  // Errors name the file and the field: out of range, not a number, both forms at once.
  const std::pair<const char*, const char*> bad[] = {
      {R"({"render": {"exposure_ev": 14}})", "must be in [-20, 13], was 14"},
      {R"({"render": {"exposure_ev": "bright"}})", "expected a number"},
      {R"({"render": {"exposure": 2, "exposure_ev": 1}})", "not both"}};
  for (const auto& [text, message] : bad) {
    const auto file = write_file("ev_bad.json", text);
    auto e = read_scene(file);
    ASSERT_FALSE(e.ok()) << text;
    const std::string got = e.error().to_string();
    EXPECT_NE(got.find("/render/exposure_ev"), std::string::npos) << got;
    EXPECT_NE(got.find(message), std::string::npos) << got;
    EXPECT_NE(got.find("ev_bad.json"), std::string::npos) << got;
  }
  auto live = apply_live_override(*s, "render.exposure_ev=-30");
  ASSERT_FALSE(live.ok());
  EXPECT_NE(live.error().to_string().find("exposure_ev"), std::string::npos);
  EXPECT_FLOAT_EQ(s->render.exposure, 0.5f);  // unchanged
}

// render.msaa: 1 by default, 2, 4 or 8 from a file, --set and live; saved and read back;
// anything else is an error naming the key and the value, and changes nothing when live.
TEST(SceneIo, MsaaLoadsSavesAndRejectsOtherCounts) {
  const fs::path def = kContent / "scenes" / "default.json";
  auto d = read_scene(def);
  ASSERT_TRUE(d.ok()) << d.error().to_string();
  EXPECT_EQ(d->render.msaa, 1);
  EXPECT_EQ(scene_to_json(*d)["render"]["msaa"].get<int>(), 1);
  for (int samples : {1, 2, 4, 8}) {
    auto s = read_scene(def, {"render.msaa=" + std::to_string(samples)});
    ASSERT_TRUE(s.ok()) << s.error().to_string();
    EXPECT_EQ(s->render.msaa, samples);
    const fs::path out = temp_dir() / "msaa_saved.json";
    ASSERT_TRUE(save_scene(out, *s).ok());
    auto again = read_scene(out);
    ASSERT_TRUE(again.ok()) << again.error().to_string();
    EXPECT_EQ(again->render.msaa, samples);
  }
  auto file = read_scene(write_file("msaa.json", R"({"render": {"msaa": 8}, "entities": []})"));
  ASSERT_TRUE(file.ok()) << file.error().to_string();
  EXPECT_EQ(file->render.msaa, 8);
  for (const char* bad : {"0", "16", "-4"})
    expect_error(read_scene(def, {std::string("render.msaa=") + bad}),
                 {"/render/msaa", "must be in [1, 8]", std::string("was ") + bad});
  expect_error(read_scene(def, {"render.msaa=3"}),
               {"/render/msaa", "must be a power of two in [1, 8]", "was 3"});
  expect_error(read_scene(def, {"render.msaa=4.5"}), {"/render/msaa", "expected an integer"});
  ASSERT_TRUE(apply_live_override(*file, "render.msaa=2").ok());
  EXPECT_EQ(file->render.msaa, 2);
  auto live = apply_live_override(*file, "render.msaa=6");
  ASSERT_FALSE(live.ok());
  EXPECT_NE(live.error().to_string().find("msaa"), std::string::npos);
  EXPECT_EQ(file->render.msaa, 2);  // unchanged
}

TEST(SceneIo, ProbeBouncesLoadSaveOverrideAndRejectBadValues) {
  // Absent: the default; given: kept through a save and a reload; --set and live overrides.
  auto d = read_scene(kContent / "scenes" / "reflections.json");
  ASSERT_TRUE(d.ok()) << d.error().to_string();
  EXPECT_EQ(d->render.probe_bounces, kDefaultProbeBounces);
  auto s = read_scene(write_file("bounces.json", R"({"render": {"probe_bounces": 3}, "entities": []})"));
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  EXPECT_EQ(s->render.probe_bounces, 3);
  EXPECT_EQ(scene_to_json(*s)["render"]["probe_bounces"].get<int>(), 3);
  const fs::path saved = temp_dir() / "bounces_saved.json";
  ASSERT_TRUE(save_scene(saved, *s).ok());
  auto again = read_scene(saved);
  ASSERT_TRUE(again.ok()) << again.error().to_string();
  EXPECT_EQ(again->render.probe_bounces, 3);
  auto set = read_scene(saved, {"render.probe_bounces=1"});
  ASSERT_TRUE(set.ok()) << set.error().to_string();
  EXPECT_EQ(set->render.probe_bounces, 1);
  ASSERT_TRUE(apply_live_override(*s, "render.probe_bounces=4").ok());
  EXPECT_EQ(s->render.probe_bounces, 4);
  // Errors name the file, the field and the range.
  const std::pair<const char*, const char*> bad[] = {
      {R"({"render": {"probe_bounces": 0}})", "must be in [1, 4], was 0"},
      {R"({"render": {"probe_bounces": 5}})", "must be in [1, 4], was 5"},
      {R"({"render": {"probe_bounces": 1.5}})", "expected an integer"},
      {R"({"render": {"probe_bounces": "two"}})", "expected an integer"}};
  for (const auto& [text, message] : bad) {
    const auto file = write_file("bounces_bad.json", text);
    auto e = read_scene(file);
    ASSERT_FALSE(e.ok()) << text;
    const std::string got = e.error().to_string();
    EXPECT_NE(got.find("/render/probe_bounces"), std::string::npos) << got;
    EXPECT_NE(got.find(message), std::string::npos) << got;
    EXPECT_NE(got.find("bounces_bad.json"), std::string::npos) << got;
  }
  expect_error(read_scene(saved, {"render.probe_bounces=9"}), {"probe_bounces", "must be in [1, 4], was 9"});
  auto live = apply_live_override(*s, "render.probe_bounces=0");
  ASSERT_FALSE(live.ok());
  EXPECT_NE(live.error().to_string().find("probe_bounces"), std::string::npos);
  EXPECT_EQ(s->render.probe_bounces, 4);  // unchanged
}

TEST(SceneIo, EntitiesAreAddedAndRemovedBetweenFrames) {
  auto s = read_scene(kContent / "scenes" / "default.json");
  ASSERT_TRUE(s.ok());
  ASSERT_TRUE(instantiate_scene(*s).ok());
  const std::size_t meshes = s->assets.meshes.size();
  auto added = add_entity(*s, nlohmann::json::parse(R"({"name": "crate", "primitive": {"shape": "box"},
      "transform": {"parent": "box_floating"}})"), "/timeline/0/add");
  ASSERT_TRUE(added.ok()) << added.error().to_string();
  EXPECT_EQ(s->assets.meshes.size(), meshes + 1);
  EXPECT_EQ(s->world.get<Transform>(*added).parent, find(*s, "box_floating"));
  // A duplicate name or a bad field changes nothing.
  const std::size_t alive = s->world.size();
  auto dup = add_entity(*s, nlohmann::json::parse(R"({"name": "crate"})"), "/x");
  ASSERT_FALSE(dup.ok());
  EXPECT_NE(dup.error().to_string().find("duplicate"), std::string::npos) << dup.error().to_string();
  auto bad = add_entity(*s, nlohmann::json::parse(R"({"name": "c2", "primitive": {"shape": "blob"}})"), "/x");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().to_string().find("/x/primitive/shape"), std::string::npos) << bad.error().to_string();
  EXPECT_EQ(s->world.size(), alive);
  // Removing the parent takes the child along.
  ASSERT_TRUE(remove_entity(*s, "box_floating").ok());
  EXPECT_FALSE(find(*s, "box_floating").valid());
  EXPECT_FALSE(s->world.alive(*added));
  EXPECT_FALSE(remove_entity(*s, "box_floating").ok());
}

}  // namespace
}  // namespace kaskad

namespace kaskad {
namespace {

using json = nlohmann::json;

// The editor finds what the readers recorded for a field by its object and field
// (FieldRecorder::object_and_field()): every path of one pair must hold the same record.
template <class T>
void expect_one_per_object_and_field(const std::map<std::string, T>& recorded) {
  std::map<std::string, std::pair<std::string, T>> by_pair;
  for (const auto& [path, value] : recorded) {
    const auto [it, added] =
        by_pair.try_emplace(json_reader::FieldRecorder::object_and_field(path, '/'), path, value);
    if (!added) {
      EXPECT_EQ(value, it->second.second) << path << " and " << it->second.first << " differ";
    }
  }
}

// The editor's combo boxes list what json_reader::FieldRecorder saw the readers ask for.
// Every string field of the canonical document that the reader checks against a table must be
// recorded, with exactly the names that table accepts.
TEST(SceneIo, FieldRecorderSeesEveryEnumeratedField) {
  const json doc = json::parse(R"({
    "kaskad_scene": 1, "render": {}, "shadow": {},
    "entities": [
      { "name": "mirror", "primitive": { "shape": "sphere" }, "material": { "roughness": 0.1 },
        "reflector": { "map": "sphere" } },
      { "name": "sun", "light": { "type": "directional" }, "shadow": { "filter": "bilinear" } },
      { "name": "camera", "camera": {} } ] })");
  json_reader::FieldRecorder recorder;
  auto scene = parse_scene(doc, temp_dir() / "enums.json");
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  const json canonical = scene_to_json(*scene);
  const auto& fields = recorder.enumerations();
  for (const char* path : {"/render/tone_mapping", "/shadow/filter", "/shadow/split_scheme",
                           "/shadow/fit_mode", "/entities/0/primitive/shape",
                           "/entities/0/material/reflection_model", "/entities/0/reflector/map",
                           "/entities/0/reflector/update", "/entities/1/light/type",
                           "/entities/1/shadow/filter", "/entities/2/camera/projection"})
    EXPECT_TRUE(fields.count(path)) << path << " not recorded";

  // Through the reader again (a scoped recorder of its own, so these reads leave `fields` as is).
  // A name may still be refused for another field's sake (update static_file needs a file): only
  // "unknown value" at this field counts as not accepted.
  auto unknown = [&](const std::string& pointer, const std::string& value) {
    json_reader::FieldRecorder scratch;
    json d = canonical;
    d[json::json_pointer(pointer)] = value;
    auto r = parse_scene(d, temp_dir() / "enums.json");
    return !r.ok() && r.error().where == pointer &&
           r.error().message.rfind("unknown value", 0) == 0;
  };
  int enumerated = 0;
  const json leaves = canonical.flatten();
  for (const auto& [pointer, value] : leaves.items()) {
    if (!value.is_string() || pointer.ends_with("/name") || pointer.ends_with("/parent")) continue;
    const auto it = fields.find(pointer);
    if (it == fields.end()) {
      // Not recorded: a free string (a path), which the reader takes as it is.
      EXPECT_FALSE(unknown(pointer, "not_a_name"))
          << pointer << " rejects a word but was not recorded";
      continue;
    }
    ++enumerated;
    ASSERT_FALSE(it->second.empty()) << pointer;
    for (const std::string& name : it->second)
      EXPECT_FALSE(unknown(pointer, name)) << pointer << " = " << name;
    EXPECT_TRUE(unknown(pointer, "not_a_name")) << pointer;
    // Exactly the table: the reader's own message lists the names it accepts.
    json bad = canonical;
    bad[json::json_pointer(pointer)] = "not_a_name";
    auto r = parse_scene(bad, temp_dir() / "enums.json");
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().message,
              "unknown value 'not_a_name'; expected one of " + json_reader::join(it->second));
    EXPECT_NE(std::find(it->second.begin(), it->second.end(), value.get<std::string>()),
              it->second.end())
        << pointer << ": the canonical value " << value << " is not among the recorded names";
  }
  EXPECT_GE(enumerated, 11);
  // The editor finds a combo's names by the field's object and name ("light.type", whichever
  // entity): that pair must name one table wherever it is read.
  expect_one_per_object_and_field(fields);
  // The shadow filter's names are the table's, in its order, each once.
  const auto& filters = fields.at("/shadow/filter");
  EXPECT_EQ(std::set<std::string>(filters.begin(), filters.end()).size(), filters.size());
  EXPECT_EQ(fields.at("/entities/1/shadow/filter"), filters);
}

// The editor's drag fields stop at what json_reader::FieldRecorder saw the readers check. Every
// number of the canonical document must be recorded, with exactly the reader's bounds: a value
// just outside either bound is refused at that field with "must be in [lo, hi]", the bounds
// themselves are not refused for their range (another field's rule may still refuse them).
TEST(SceneIo, FieldRecorderRecordsEveryNumbersBounds) {
  const json doc = json::parse(R"({
    "kaskad_scene": 1, "render": {}, "shadow": {},
    "entities": [
      { "name": "mirror", "primitive": { "shape": "sphere" }, "material": { "roughness": 0.1 },
        "reflector": { "map": "sphere", "center": [0, 1, 0], "box": { "min": [-1, -1, -1], "max": [1, 1, 1] } } },
      { "name": "sun", "light": { "type": "directional" }, "shadow": { "filter": "bilinear" } },
      { "name": "lamp", "light": { "type": "area" } },
      { "name": "camera", "camera": {} } ] })");
  auto scene = parse_scene(doc, temp_dir() / "ranges.json");
  ASSERT_TRUE(scene.ok()) << scene.error().to_string();
  const json canonical = scene_to_json(*scene);
  // As the editor records: its canonical document read once, every section present.
  json_reader::FieldRecorder recorder;
  ASSERT_TRUE(parse_scene(canonical, temp_dir() / "ranges.json").ok());
  const auto& ranges = recorder.ranges();
  // What the reader says of `value` at `pointer`: "" when it takes it (or refuses another field).
  auto verdict = [&](const std::string& pointer, const json& value) {
    json_reader::FieldRecorder scratch;
    json d = canonical;
    d[json::json_pointer(pointer)] = value;
    auto r = parse_scene(d, temp_dir() / "ranges.json");
    return !r.ok() && r.error().where == pointer ? r.error().message : std::string();
  };
  int checked = 0, powers = 0;
  const json leaves = canonical.flatten();
  for (const auto& [pointer, value] : leaves.items()) {
    if (!value.is_number() || pointer == "/kaskad_scene") continue;
    // A name written as a JSON integer (pcf_kernel's box sides 3, 5, 7, 9) is a choice, not a range.
    if (recorder.enumerations().count(pointer)) continue;
    // An array's numbers share the array's bounds.
    const std::string parent = pointer.substr(0, pointer.rfind('/'));
    const bool element = !parent.empty() && canonical[json::json_pointer(parent)].is_array();
    const auto it = ranges.find(element ? parent : pointer);
    ASSERT_NE(it, ranges.end()) << pointer << " is a number whose bounds were not recorded";
    ++checked;
    const auto [lo, hi, power_of_two] = it->second;
    if (power_of_two) {
      // A map size: offered as the powers of two in its bounds; a number between them refused.
      ++powers;
      std::int64_t between = std::int64_t(lo) + 1;
      while ((between & (between - 1)) == 0) ++between;
      EXPECT_NE(verdict(pointer, between).find("must be a power of two"),
                std::string::npos)
          << pointer;
    }
    const bool integer = value.is_number_integer();
    const json below =
        integer ? json(std::int64_t(lo) - 1) : json(lo - std::max(std::abs(lo), 1.0) * 1e-6);
    const json above =
        integer ? json(std::int64_t(hi) + 1) : json(hi + std::max(std::abs(hi), 1.0) * 1e-6);
    EXPECT_EQ(verdict(pointer, below).rfind("must be in [", 0), 0u) << pointer << " = " << below;
    EXPECT_EQ(verdict(pointer, above).rfind("must be in [", 0), 0u) << pointer << " = " << above;
    for (const double bound : {lo, hi}) {
      const json at = integer ? json(std::int64_t(bound)) : json(bound);
      EXPECT_EQ(verdict(pointer, at).rfind("must be in [", 0), std::string::npos)
          << pointer << " = " << at << ": " << verdict(pointer, at);
    }
  }
  EXPECT_GE(checked, 60);
  EXPECT_GE(powers, 2);  // the scene's map_size, the mirror's resolution
  // The editor finds a field's bounds by its object and name ("light.intensity", whichever
  // entity): that pair must have one range wherever it is read.
  expect_one_per_object_and_field(ranges);
  // Just under 1, where the bound prints as 1: the message says the bound is open.
  EXPECT_NE(verdict("/shadow/vsm_bleed_reduction", 0.99999997).find("[0, 1)"), std::string::npos)
      << verdict("/shadow/vsm_bleed_reduction", 0.99999997);
}

TEST(SceneIo, FieldRecorderIsScoped) {
  EXPECT_EQ(json_reader::FieldRecorder::current(), nullptr);
  {
    json_reader::FieldRecorder outer;
    {
      json_reader::FieldRecorder inner;
      EXPECT_EQ(json_reader::FieldRecorder::current(), &inner);
    }
    EXPECT_EQ(json_reader::FieldRecorder::current(), &outer);
  }
  EXPECT_EQ(json_reader::FieldRecorder::current(), nullptr);
}

}  // namespace
}  // namespace kaskad
