// The scene file's blocks (runtime/assets/scene_blocks.cpp, reflector_io.cpp): each setting
// loads, saves, overrides and is rejected out of range with the key and the value; what the
// readers record for the editor (json_reader::FieldRecorder).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include "components/light.h"
#include "components/material.h"
#include "components/reflector.h"
#include "components/shadow_settings.h"
#include "runtime/assets/scene_io.h"
#include "runtime/core/json_reader.h"
#include "tests/unit/assets/scene_test_util.h"

namespace kaskad {
namespace {

using namespace scene_test;
using json = nlohmann::json;

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
