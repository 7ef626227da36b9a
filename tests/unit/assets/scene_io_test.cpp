// Scene files (runtime/assets/scene_io.cpp, scene_instantiate.cpp, model_import.cpp): round
// trip, models and their instances, the ground, entities added between frames, and errors that
// name the file and the place.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "components/camera.h"
#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/name.h"
#include "components/transform.h"
#include "runtime/assets/scene_io.h"
#include "runtime/assets/material_file.h"
#include "tests/unit/assets/scene_test_util.h"

namespace kaskad {
namespace {

using namespace scene_test;

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

TEST(SceneIo, AParentCycleIsALoadErrorNamingTheChain) {
  expect_error(read_scene(write_file("cycle.json", R"({"entities": [
    {"name": "a", "transform": {"parent": "c"}},
    {"name": "b", "transform": {"parent": "a"}},
    {"name": "c", "transform": {"parent": "b"}}]})")),
               {"cycle.json", "/entities/0/transform/parent", "parent cycle: a -> c -> b -> a"});
}

// Parent chains as long as the scene load in linear time: a chain of 100,000 loads (the tail
// entities first in the file), and the same chain closed into a cycle is named by its ends.
TEST(SceneIo, AHundredThousandLongParentChainLoadsAndItsCycleIsNamedShortly) {
  constexpr int kLength = 100000;
  auto chain = [&](bool closed) {
    std::string text = R"({"entities": [)";
    for (int i = kLength - 1; i >= 0; --i) {
      text += R"({"name": "e)" + std::to_string(i) + '"';
      if (i > 0 || closed)
        text += R"(, "transform": {"parent": "e)" + std::to_string(i > 0 ? i - 1 : kLength - 1) +
                R"("})";
      text += i > 0 ? "}," : "}";
    }
    return text + "]}";
  };
  auto open = read_scene(write_file("long_chain.json", chain(false)));
  ASSERT_TRUE(open.ok()) << open.error().to_string();
  EXPECT_EQ(open->world.get<Transform>(find(*open, "e1")).parent, find(*open, "e0"));
  auto closed = read_scene(write_file("long_cycle.json", chain(true)));
  ASSERT_FALSE(closed.ok());
  EXPECT_EQ(closed.error().where, "/entities/0/transform/parent");
  EXPECT_EQ(closed.error().message, "parent cycle: e99999 -> e99998 -> e99997 -> e99996 -> ... (" +
                                        std::to_string(kLength - 7) +
                                        " more) -> e2 -> e1 -> e0 -> e99999");
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
