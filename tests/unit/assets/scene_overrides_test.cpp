// `--set` overrides (runtime/assets/scene_overrides.cpp): on the document before a load, on a
// loaded scene, on imported glTF nodes, and a model's `nodes` block.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "components/animation.h"
#include "components/camera.h"
#include "components/light.h"
#include "components/name.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "runtime/assets/scene_io.h"
#include "tests/unit/assets/scene_test_util.h"

namespace kaskad {
namespace {

using namespace scene_test;

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

// A model's clips: a save writes a playing clip's time as it was last set (its clock is not
// authored, so save -> load -> save is the same file) and a stopped clip's where it stopped;
// --set of one field acts on the live state and keeps the clock; the document takes
// ENTITY.animation.CLIP.FIELD before the import knows the clips (which then checks the name);
// a scene read but not loaded saves the block as given.
TEST(SceneIo, AnimationBlocksSaveTheTimeAsSetAndTakeOverrides) {
  const fs::path fox = kContent / "scenes" / "fox_walk.json";
  auto s = read_scene(fox);
  ASSERT_TRUE(s.ok()) << s.error().to_string();
  EXPECT_TRUE(scene_to_json(*s)["entities"].dump().find("\"Survey\"") != std::string::npos)
      << "read but not loaded: the block as the file gave it";
  ASSERT_TRUE(instantiate_scene(*s).ok());
  Animator& a = s->world.get<Animator>(find(*s, "walker"));
  const auto clip = [&](const std::string& name) {
    return std::size_t(std::find(a.names.begin(), a.names.end(), name) - a.names.begin());
  };
  const std::size_t walk = clip("Walk"), survey = clip("Survey");
  ASSERT_LT(walk, a.clips.size());
  ASSERT_LT(survey, a.clips.size());
  ASSERT_TRUE(a.clips[walk].playing);
  a.clips[walk].time = 0.7f;    // the clock moved on
  a.clips[survey].time = 1.25f;  // a stopped clip, put there
  auto saved_clip = [&](const char* name) {
    const nlohmann::json doc = scene_to_json(*s);
    for (const auto& e : doc["entities"])
      if (e.value("name", "") == "walker") return e["animation"][name];
    return nlohmann::json();
  };
  EXPECT_FLOAT_EQ(saved_clip("Walk")["time"].get<float>(), 0.0f);
  EXPECT_FLOAT_EQ(saved_clip("Survey")["time"].get<float>(), 1.25f);
  EXPECT_FLOAT_EQ(live_entity_sections(*s, find(*s, "walker"))["animation"]["Walk"]["time"].get<float>(), 0.7f);
  // One field set live: the others stay where the clock has them.
  ASSERT_TRUE(apply_live_override(*s, "walker.animation.Walk.speed=2").ok());
  EXPECT_FLOAT_EQ(a.clips[walk].speed, 2.0f);
  EXPECT_NEAR(a.clips[walk].time, 0.7f, 1e-6f);
  ASSERT_TRUE(apply_live_override(*s, "walker.animation.Walk.time=0.3").ok());
  a.clips[walk].time = 0.9f;
  EXPECT_FLOAT_EQ(saved_clip("Walk")["time"].get<float>(), 0.3f);
  EXPECT_FLOAT_EQ(saved_clip("Walk")["speed"].get<float>(), 2.0f);

  // The document: a glTF file wrapped into a scene has no animation block until --set makes one.
  const fs::path truck = kContent / "models" / "CesiumMilkTruck" / "glTF" / "CesiumMilkTruck.gltf";
  auto stopped = read_scene(truck, {"model.animation.animation_0.playing=false"});
  ASSERT_TRUE(stopped.ok()) << stopped.error().to_string();
  ASSERT_TRUE(instantiate_scene(*stopped).ok());
  EXPECT_FALSE(stopped->world.get<Animator>(find(*stopped, "model")).clips[0].playing);
  auto wrong = read_scene(truck, {"model.animation.wheels.playing=false"});
  ASSERT_TRUE(wrong.ok()) << wrong.error().to_string();
  auto st = instantiate_scene(*wrong);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().to_string().find("no clip named 'wheels'"), std::string::npos) << st.error().to_string();
  EXPECT_NE(st.error().to_string().find("animation_0"), std::string::npos);
}

}  // namespace
}  // namespace kaskad
