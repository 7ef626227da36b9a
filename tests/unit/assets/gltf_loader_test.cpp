#include "runtime/assets/gltf_loader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "components/animation.h"
#include "components/camera.h"
#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/name.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "runtime/assets/image_io.h"
#include "runtime/features/variant_key.h"
#include "tests/unit/assets/asset_test_util.h"

namespace kaskad {
namespace {

using nlohmann::json;
using test::content_path;
using test::base64;
using test::read_bytes;
using test::temp_dir;
using test::write_bytes;
using test::write_text;

constexpr float kPi = std::numbers::pi_v<float>;

/// A world, an asset store and the result of importing one file into them.
struct Imported3d {
  ecs::World world;
  AssetStore assets;
  ecs::Entity root;
  Result<GltfImportReport> report = Error{};
};

std::unique_ptr<Imported3d> import_file(const std::filesystem::path& path,
                                        bool activate_first_camera = false) {
  auto s = std::make_unique<Imported3d>();
  s->root = s->world.create();
  s->report = import_gltf(path, s->world, s->assets, s->root, s->root, activate_first_camera);
  return s;
}

bool mentions(const Error& error, const std::string& text) {
  return error.to_string().find(text) != std::string::npos;
}

bool warns(const GltfImportReport& report, const std::string& text) {
  for (const auto& w : report.warnings)
    if (w.find(text) != std::string::npos) return true;
  return false;
}

/// Every entity with a Name, by name (names are unique in the files used here).
std::map<std::string, ecs::Entity> entities_by_name(ecs::World& world) {
  std::map<std::string, ecs::Entity> out;
  world.view<Name, Transform>().each(
      [&](ecs::Entity e, Name& name, Transform&) { out[name.value] = e; });
  return out;
}

/// Invariants every imported mesh must satisfy, whatever the file.
void expect_valid_meshes(const AssetStore& assets) {
  for (const MeshData& m : assets.meshes) {
    SCOPED_TRACE(m.name);
    ASSERT_FALSE(m.positions.empty());
    ASSERT_EQ(m.normals.size(), m.positions.size());
    ASSERT_TRUE(m.uvs.empty() || m.uvs.size() == m.positions.size());
    ASSERT_TRUE(m.tangents.empty() || m.tangents.size() == m.positions.size());
    ASSERT_EQ(m.indices.size() % 3, 0u);
    for (std::uint32_t i : m.indices) ASSERT_LT(i, m.positions.size());
    ASSERT_FALSE(m.bounds.empty());
    for (const glm::vec3& p : m.positions) {
      ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
      for (int a = 0; a < 3; ++a) {
        ASSERT_GE(p[a], m.bounds.min[a]);
        ASSERT_LE(p[a], m.bounds.max[a]);
      }
    }
    for (const glm::vec3& n : m.normals) {
      const float len = glm::length(n);
      ASSERT_TRUE(len == 0.0f || std::abs(len - 1.0f) < 1e-4f) << len;
    }
  }
}

template <class T>
void append(std::vector<std::uint8_t>& bytes, std::initializer_list<T> values) {
  for (T v : values) {
    std::uint8_t b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    bytes.insert(bytes.end(), b, b + sizeof(T));
  }
}

/// A small valid glTF (JSON with a base64 buffer): one triangle without normals, indexed by
/// u16 indices, under a node with TRS; tests modify the returned document to break it.
/// Buffer: bytes 0-35 positions (3 x vec3 float), 36-41 indices (3 x u16), 42-43 padding.
json triangle_gltf() {
  std::vector<std::uint8_t> buffer;
  append<float>(buffer, {0, 0, 0, 1, 0, 0, 0, 1, 0});
  append<std::uint16_t>(buffer, {0, 1, 2, 0});
  json doc = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes",
       {{{"name", "parent"},
         {"translation", {1, 2, 3}},
         {"rotation", {0, 0.70710678, 0, 0.70710678}},
         {"scale", {2, 2, 2}},
         {"children", {1}}},
        {{"name", "tri"}, {"mesh", 0}}}},
      {"meshes",
       {{{"name", "triangle"},
         {"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "SCALAR"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
        {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 6}}}},
      {"buffers",
       {{{"byteLength", buffer.size()},
         {"uri", "data:application/octet-stream;base64," + base64(buffer)}}}},
  };
  return doc;
}

std::filesystem::path write_gltf(const std::string& name, const json& doc) {
  const auto path = temp_dir() / name;
  write_text(path, doc.dump(2));
  return path;
}

// ---- Real content ---------------------------------------------------------------------------

TEST(GltfLoader, BoxImportsOneMeshUnderItsNodes) {
  auto s = import_file(content_path("models/Box/glTF-Binary/Box.glb"));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  EXPECT_EQ(s->report->mesh_entities, 1);
  EXPECT_EQ(s->report->triangles, 12u);
  ASSERT_EQ(s->assets.meshes.size(), 1u);
  expect_valid_meshes(s->assets);

  // The MeshRenderer entity hangs under a node entity, which hangs (maybe indirectly) under root.
  int renderers = 0;
  s->world.view<MeshRenderer, Transform>().each([&](ecs::Entity e, MeshRenderer& r, Transform& t) {
    ++renderers;
    EXPECT_EQ(r.mesh, MeshId{0});
    ASSERT_TRUE(t.parent.valid());
    EXPECT_TRUE(s->world.has<Name>(t.parent));
    EXPECT_TRUE(s->world.has<Material>(e));
    ASSERT_NE(s->world.try_get<Imported>(e), nullptr);
    EXPECT_EQ(s->world.get<Imported>(e).source, s->root);
  });
  EXPECT_EQ(renderers, 1);
}

TEST(GltfLoader, DracoBoxHasTheSameBoundsAsThePlainBox) {
  auto plain = import_file(content_path("models/Box/glTF-Binary/Box.glb"));
  auto draco = import_file(content_path("models/Box/glTF-Draco-Binary/Box_Draco.glb"));
  ASSERT_TRUE(plain->report.ok()) << plain->report.error().to_string();
  ASSERT_TRUE(draco->report.ok()) << draco->report.error().to_string();
  ASSERT_EQ(plain->assets.meshes.size(), 1u);
  ASSERT_EQ(draco->assets.meshes.size(), 1u);
  expect_valid_meshes(draco->assets);
  const Aabb a = plain->assets.meshes[0].bounds, b = draco->assets.meshes[0].bounds;
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(a.min[axis], b.min[axis], 1e-3f) << "axis " << axis;
    EXPECT_NEAR(a.max[axis], b.max[axis], 1e-3f) << "axis " << axis;
  }
  EXPECT_GT(draco->report->triangles, 0u);
}

TEST(GltfLoader, DracoEngineHasItsTrianglesAndHierarchy) {
  auto s = import_file(content_path("models/2CylinderEngine/glTF-Draco/2CylinderEngine.gltf"),
                       /*activate_first_camera=*/true);
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  const GltfImportReport& r = s->report.value();
  // 65,311 triangles in 34 primitives of 29 meshes; meshes shared by nodes count once.
  EXPECT_NEAR(double(r.triangles), 65311.0, 200.0);
  EXPECT_EQ(s->assets.meshes.size(), 34u);
  EXPECT_EQ(r.nodes, 82);
  EXPECT_GE(r.mesh_entities, 67);  // 67 nodes refer to a mesh
  EXPECT_EQ(r.cameras, 1);
  expect_valid_meshes(s->assets);

  // Parent links: every node entity's parent is the import root or another imported node, and
  // the hierarchy is more than one level deep.
  int max_depth = 0, node_entities = 0;
  s->world.view<Name, Transform>().each([&](ecs::Entity e, Name&, Transform& t) {
    if (e == s->root) return;
    ++node_entities;
    ASSERT_TRUE(t.parent.valid());
    int depth = 0;
    for (ecs::Entity p = e; p != s->root; p = s->world.get<Transform>(p).parent) {
      ASSERT_TRUE(s->world.has<Transform>(p) || p == s->root);
      ASSERT_LT(++depth, 100);
    }
    max_depth = std::max(max_depth, depth);
  });
  EXPECT_EQ(node_entities, r.nodes + r.mesh_entities);
  EXPECT_GE(max_depth, 3);

  int active = 0;
  s->world.view<Camera, Transform>().each([&](ecs::Entity, Camera& c, Transform&) {
    active += c.active;
    EXPECT_GT(c.near, 0.0f);
    EXPECT_GT(c.far, c.near);
  });
  EXPECT_EQ(active, 1);
}

TEST(GltfLoader, MilkTruckTexturesAreDecodedThroughOiio) {
  const auto dir = content_path("models/CesiumMilkTruck/glTF");
  auto s = import_file(dir / "CesiumMilkTruck.gltf");
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  expect_valid_meshes(s->assets);
  // Two glTF textures share one image with the same colour space: one texture.
  ASSERT_EQ(s->assets.textures.size(), 1u);
  const TextureData& t = s->assets.textures[0];
  EXPECT_TRUE(t.srgb);

  auto reference = load_image(dir / "CesiumMilkTruck.png");
  ASSERT_TRUE(reference.ok()) << reference.error().to_string();
  ASSERT_EQ(t.width, reference->width);
  ASSERT_EQ(t.height, reference->height);
  ASSERT_EQ(t.rgba8.size(), std::size_t(t.width) * t.height * 4);
  for (int y = 0; y < t.height; y += 97) {
    for (int x = 0; x < t.width; x += 89) {
      for (int c = 0; c < 3; ++c) {
        const int expected =
            int(std::lround(reference->at(x, y, std::min(c, reference->channels - 1)) * 255.0f));
        ASSERT_EQ(int(t.rgba8[(std::size_t(y) * t.width + x) * 4 + c]), expected);
      }
    }
  }

  int textured = 0;
  s->world.view<Material, MeshRenderer>().each([&](ecs::Entity, Material& m, MeshRenderer&) {
    textured += m.base_color_texture == TextureId{0};
    EXPECT_EQ(m.normal_texture, kNoTexture);
    EXPECT_EQ(m.metallic, 0.0f);  // the file's metallicFactor
  });
  EXPECT_GE(textured, 1);
  // The truck's wheels turn: its one animation is imported onto the model entity.
  EXPECT_EQ(s->report->animations, 1);
  ASSERT_TRUE(s->world.has<Animator>(s->root));
  const Animator& a = s->world.get<Animator>(s->root);
  ASSERT_EQ(a.clips.size(), 1u);
  EXPECT_TRUE(a.clips[0].playing);
  for (const auto& w : s->report->warnings) EXPECT_EQ(w.find("animation"), std::string::npos) << w;
}

TEST(GltfLoader, FoxImportsItsSkinAndThreeClips) {
  auto s = import_file(content_path("models/Fox/glTF/Fox.gltf"));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  for (const auto& w : s->report->warnings) EXPECT_EQ(w.find("skin"), std::string::npos) << w;
  EXPECT_EQ(s->report->skins, 1);
  EXPECT_EQ(s->report->animations, 3);
  ASSERT_EQ(s->assets.skins.size(), 1u);
  ASSERT_EQ(s->assets.skins[0].inverse_bind.size(), 24u);
  int deformers = 0;
  s->world.view<Deformer, MeshRenderer>().each([&](ecs::Entity, Deformer& d, MeshRenderer& mr) {
    ++deformers;
    EXPECT_EQ(d.skin, 0u);
    ASSERT_EQ(d.joints.size(), 24u);
    for (ecs::Entity j : d.joints) EXPECT_TRUE(s->world.has<Transform>(j));
    const MeshDeform& m = s->assets.meshes[index(mr.mesh)].deform;
    ASSERT_EQ(m.influences, 4);
    const std::size_t n = s->assets.meshes[index(mr.mesh)].positions.size();
    ASSERT_EQ(m.weights.size(), 4 * n);
    for (std::size_t v = 0; v < n; ++v) {
      const float sum = m.weights[4 * v] + m.weights[4 * v + 1] + m.weights[4 * v + 2] + m.weights[4 * v + 3];
      ASSERT_NEAR(sum, 1.0f, 1e-5f) << v;
    }
  });
  EXPECT_EQ(deformers, 1);
  ASSERT_TRUE(s->world.has<Animator>(s->root));
  const Animator& a = s->world.get<Animator>(s->root);
  EXPECT_EQ(a.names, (std::vector<std::string>{"Survey", "Walk", "Run"}));
  EXPECT_TRUE(a.clips[0].playing);
  EXPECT_FALSE(a.clips[1].playing);
  for (std::size_t k = 0; k < 3; ++k) {
    const AnimationClip& clip = s->assets.animations[a.first_clip + k];
    EXPECT_GT(clip.duration, 0.5f) << clip.name;
    EXPECT_GT(clip.channels.size(), 20u) << clip.name;
    for (const auto& ch : clip.channels) EXPECT_TRUE(a.nodes[ch.node].valid());
  }
}

/// triangle_gltf() with one morph target (vertex 1 moves +1 in y), mesh weights [0.25] and a
/// STEP animation of the node's weights (0 at t = 0, 1 from t = 1).
json morphed_triangle_gltf() {
  json doc = triangle_gltf();
  std::vector<std::uint8_t> extra;
  append<float>(extra, {0, 0, 0, 0, 1, 0, 0, 0, 0});  // target POSITION (36 bytes)
  append<float>(extra, {0, 1});                       // times (8 bytes)
  append<float>(extra, {0, 1});                       // weights (8 bytes)
  std::vector<std::uint8_t> buffer;
  append<float>(buffer, {0, 0, 0, 1, 0, 0, 0, 1, 0});
  append<std::uint16_t>(buffer, {0, 1, 2, 0});
  buffer.insert(buffer.end(), extra.begin(), extra.end());
  doc["buffers"][0] = {{"byteLength", buffer.size()},
                       {"uri", "data:application/octet-stream;base64," + base64(buffer)}};
  doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 44}, {"byteLength", 36}});
  doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 80}, {"byteLength", 8}});
  doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 88}, {"byteLength", 8}});
  doc["accessors"].push_back({{"bufferView", 2}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}});
  doc["accessors"].push_back({{"bufferView", 3}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}});
  doc["accessors"].push_back({{"bufferView", 4}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}});
  doc["meshes"][0]["primitives"][0]["targets"] = {{{"POSITION", 2}}};
  doc["meshes"][0]["weights"] = {0.25};
  doc["animations"] = {{{"name", "open"},
                        {"samplers", {{{"input", 3}, {"output", 4}, {"interpolation", "STEP"}}}},
                        {"channels", {{{"sampler", 0}, {"target", {{"node", 1}, {"path", "weights"}}}}}}}};
  return doc;
}

// Skins the reader cannot trust are errors naming the skin (a joint listed twice, a skeleton
// out of range); a singular inverse bind matrix and a skin on a mesh without joint weights are
// warnings. The Fox, its skin changed, next to copies of its buffer and texture.
TEST(GltfLoader, BadSkinsAreErrorsOrWarningsNamingTheSkin) {
  const auto dir = content_path("models/Fox/glTF");
  for (const char* f : {"Fox.bin", "Texture.png"}) write_bytes(temp_dir() / f, read_bytes(dir / f));
  const json fox = json::parse(read_bytes(dir / "Fox.gltf"));
  {
    json doc = fox;
    doc["skins"][0]["joints"][1] = doc["skins"][0]["joints"][0];
    auto s = import_file(write_gltf("fox_dup_joint.gltf", doc));
    ASSERT_FALSE(s->report.ok());
    EXPECT_TRUE(mentions(s->report.error(), "skins[0]")) << s->report.error().to_string();
    EXPECT_TRUE(mentions(s->report.error(), "listed twice"));
  }
  {
    json doc = fox;
    doc["skins"][0]["skeleton"] = 999;
    auto s = import_file(write_gltf("fox_bad_skeleton.gltf", doc));
    ASSERT_FALSE(s->report.ok());
    EXPECT_TRUE(mentions(s->report.error(), "skeleton 999 out of range")) << s->report.error().to_string();
  }
  {
    json doc = fox;
    for (auto& p : doc["meshes"][0]["primitives"]) {
      p["attributes"].erase("JOINTS_0");
      p["attributes"].erase("WEIGHTS_0");
    }
    auto s = import_file(write_gltf("fox_no_weights.gltf", doc));
    ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
    EXPECT_TRUE(warns(*s->report, "skin ignored: its mesh has no JOINTS_0 and WEIGHTS_0"));
  }
}

// Joint and weight types glTF does not allow are read as they come, with a warning naming them:
// float joints, integer weights that are not normalized.
TEST(GltfLoader, OffTypeJointsAndWeightsAreWarnings) {
  json doc = triangle_gltf();
  std::vector<std::uint8_t> extra;
  append<float>(extra, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0});  // JOINTS_0 as floats (48 bytes)
  for (int v = 0; v < 3; ++v) extra.insert(extra.end(), {1, 0, 0, 0});  // WEIGHTS_0 bytes (12)
  doc["buffers"].push_back({{"byteLength", extra.size()},
                            {"uri", "data:application/octet-stream;base64," + base64(extra)}});
  doc["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", 48}});
  doc["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 48}, {"byteLength", 12}});
  doc["accessors"].push_back({{"bufferView", 2}, {"componentType", 5126}, {"count", 3}, {"type", "VEC4"}});
  doc["accessors"].push_back({{"bufferView", 3}, {"componentType", 5121}, {"count", 3}, {"type", "VEC4"}});
  doc["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = 2;
  doc["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"] = 3;
  auto s = import_file(write_gltf("off_type_skin.gltf", doc));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  EXPECT_TRUE(warns(*s->report, "JOINTS_0 are floats"));
  EXPECT_TRUE(warns(*s->report, "WEIGHTS_0 are integers without normalized"));
}

TEST(GltfLoader, MorphTargetsAndTheirWeightsAnimation) {
  auto s = import_file(write_gltf("morph.gltf", morphed_triangle_gltf()));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  EXPECT_EQ(s->report->morphed, 1);
  EXPECT_EQ(s->report->animations, 1);
  const auto by_name = entities_by_name(s->world);
  ASSERT_TRUE(by_name.count("tri"));
  const ecs::Entity tri = by_name.at("tri");
  ASSERT_TRUE(s->world.has<MorphWeights>(tri));
  EXPECT_EQ(s->world.get<MorphWeights>(tri).weights, std::vector<float>{0.25f});
  int deformers = 0;
  s->world.view<Deformer, MeshRenderer>().each([&](ecs::Entity, Deformer& d, MeshRenderer& mr) {
    ++deformers;
    EXPECT_EQ(d.skin, Deformer::kNoSkin);
    const MeshDeform& m = s->assets.meshes[index(mr.mesh)].deform;
    ASSERT_EQ(m.targets.size(), 1u);
    EXPECT_EQ(m.targets[0].positions[1], glm::vec3(0, 1, 0));
    EXPECT_EQ(m.default_weights, std::vector<float>{0.25f});
    // Flat normals were generated (the file has none): the target still follows its vertices.
    EXPECT_EQ(m.targets[0].positions.size(), s->assets.meshes[index(mr.mesh)].positions.size());
  });
  EXPECT_EQ(deformers, 1);
  const AnimationClip& clip = s->assets.animations.at(0);
  ASSERT_EQ(clip.channels.size(), 1u);
  EXPECT_EQ(clip.channels[0].path, AnimatedPath::weights);
  EXPECT_EQ(clip.channels[0].tracks[0].interpolation, KeyInterpolation::step);
  EXPECT_FLOAT_EQ(clip.duration, 1.0f);
}

TEST(GltfLoader, BadAnimationsAndMorphTargetsAreErrorsNamingThePlace) {
  {
    json doc = morphed_triangle_gltf();
    doc["animations"][0]["samplers"][0]["interpolation"] = "SMOOTH";
    auto s = import_file(write_gltf("bad_interp.gltf", doc));
    ASSERT_FALSE(s->report.ok());
    EXPECT_TRUE(mentions(s->report.error(), "animations[0] \"open\" samplers[0]")) << s->report.error().to_string();
    EXPECT_TRUE(mentions(s->report.error(), "unknown interpolation 'SMOOTH'"));
  }
  {
    json doc = morphed_triangle_gltf();
    doc["animations"][0]["samplers"][0]["output"] = 2;  // the target's VEC3 accessor
    auto s = import_file(write_gltf("bad_output.gltf", doc));
    ASSERT_FALSE(s->report.ok());
    EXPECT_TRUE(mentions(s->report.error(), "expected 1 components")) << s->report.error().to_string();
  }
  {
    json doc = morphed_triangle_gltf();
    doc["meshes"][0]["weights"] = {0.25, 0.5};
    auto s = import_file(write_gltf("bad_weights.gltf", doc));
    ASSERT_FALSE(s->report.ok());
    EXPECT_TRUE(mentions(s->report.error(), "2 values for 1 morph targets")) << s->report.error().to_string();
  }
  {
    json doc = morphed_triangle_gltf();
    doc["animations"][0]["channels"][0]["target"]["node"] = 7;
    auto s = import_file(write_gltf("bad_target.gltf", doc));
    ASSERT_FALSE(s->report.ok());
    EXPECT_TRUE(mentions(s->report.error(), "target node 7 out of range")) << s->report.error().to_string();
  }
  {
    // Keyframe times start at 0 or later (glTF 3.11).
    json doc = morphed_triangle_gltf();
    std::vector<std::uint8_t> buffer;
    append<float>(buffer, {0, 0, 0, 1, 0, 0, 0, 1, 0});
    append<std::uint16_t>(buffer, {0, 1, 2, 0});
    append<float>(buffer, {0, 0, 0, 0, 1, 0, 0, 0, 0});
    append<float>(buffer, {-1, 1});  // times
    append<float>(buffer, {0, 1});
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(buffer);
    auto s = import_file(write_gltf("negative_time.gltf", doc));
    ASSERT_FALSE(s->report.ok());
    EXPECT_TRUE(mentions(s->report.error(), "time is negative")) << s->report.error().to_string();
  }
  {
    json doc = morphed_triangle_gltf();
    doc["animations"][0]["channels"][0]["target"]["path"] = "pointer";
    auto s = import_file(write_gltf("unknown_path.gltf", doc));
    ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
    bool warned = false;
    for (const auto& w : s->report->warnings) warned |= w.find("path 'pointer'") != std::string::npos;
    EXPECT_TRUE(warned);
  }
}

// ---- A file written by the test: lights, cameras, transforms, generated normals -------------

TEST(GltfLoader, LightsCamerasAndTransformsBecomeComponents) {
  json doc = triangle_gltf();
  doc["extensionsUsed"] = {"KHR_lights_punctual"};
  doc["extensions"]["KHR_lights_punctual"]["lights"] = {
      {{"name", "sun"}, {"type", "directional"}, {"color", {1.0, 0.9, 0.8}}, {"intensity", 3.0}},
      {{"name", "spot"},
       {"type", "spot"},
       {"intensity", 50.0},
       {"range", 20.0},
       {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.6}}}},
      {{"name", "bulb"},
       {"type", "point"},
       {"color", {0.5, 0.5, 1.0}},
       {"intensity", 100.0},
       {"range", 5.0}}};
  doc["cameras"] = {
      {{"type", "perspective"},
       {"perspective", {{"yfov", 0.8}, {"znear", 0.05}, {"zfar", 500.0}, {"aspectRatio", 1.5}}}},
      {{"type", "perspective"}, {"perspective", {{"yfov", 1.0}, {"znear", 0.1}}}},
      {{"type", "orthographic"},
       {"orthographic", {{"xmag", 10.0}, {"ymag", 5.0}, {"znear", 0.0}, {"zfar", 100.0}}}}};
  auto& nodes = doc["nodes"];
  nodes.push_back(
      {{"name", "sun_node"}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
  nodes.push_back(
      {{"name", "spot_node"}, {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
  nodes.push_back(
      {{"name", "bulb_node"}, {"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}});
  nodes.push_back({{"name", "cam"}, {"camera", 0}, {"translation", {0, 1, 5}}});
  nodes.push_back({{"name", "cam_infinite"}, {"camera", 1}});
  nodes.push_back({{"name", "cam_ortho"}, {"camera", 2}});
  doc["scenes"][0]["nodes"] = {0, 2, 3, 4, 5, 6, 7};

  auto s = import_file(write_gltf("lights.gltf", doc), /*activate_first_camera=*/true);
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  EXPECT_EQ(s->report->lights, 3);
  EXPECT_EQ(s->report->cameras, 3);
  EXPECT_EQ(s->report->nodes, 8);
  EXPECT_EQ(s->report->mesh_entities, 1);
  auto by_name = entities_by_name(s->world);
  ecs::World& w = s->world;

  const Light* sun = w.try_get<Light>(by_name.at("sun_node"));
  ASSERT_NE(sun, nullptr);
  EXPECT_EQ(sun->type, LightType::directional);
  EXPECT_NEAR(sun->color.y, 0.9f, 1e-6f);
  EXPECT_EQ(sun->intensity, 3.0f);
  EXPECT_TRUE(sun->cast_shadows);
  EXPECT_TRUE(w.has<ShadowSettings>(by_name.at("sun_node")));
  EXPECT_TRUE(validate_shadow_settings(w.get<ShadowSettings>(by_name.at("sun_node"))).empty());

  const Light* spot = w.try_get<Light>(by_name.at("spot_node"));
  ASSERT_NE(spot, nullptr);
  EXPECT_EQ(spot->type, LightType::spot);
  EXPECT_EQ(spot->color, glm::vec3(1.0f));  // default colour
  EXPECT_EQ(spot->range, 20.0f);
  EXPECT_NEAR(spot->inner_cone_deg, 0.2f * 180.0f / kPi, 1e-4f);
  EXPECT_NEAR(spot->outer_cone_deg, 0.6f * 180.0f / kPi, 1e-4f);
  EXPECT_FALSE(spot->cast_shadows);
  EXPECT_FALSE(w.has<ShadowSettings>(by_name.at("spot_node")));

  const Light* bulb = w.try_get<Light>(by_name.at("bulb_node"));
  ASSERT_NE(bulb, nullptr);
  EXPECT_EQ(bulb->type, LightType::point);
  EXPECT_EQ(bulb->intensity, 100.0f);
  EXPECT_EQ(bulb->range, 5.0f);

  const Camera* cam = w.try_get<Camera>(by_name.at("cam"));
  ASSERT_NE(cam, nullptr);
  EXPECT_EQ(cam->projection, Projection::perspective);
  EXPECT_NEAR(cam->fov_y_deg, 0.8f * 180.0f / kPi, 1e-4f);
  EXPECT_NEAR(cam->near, 0.05f, 1e-7f);
  EXPECT_EQ(cam->far, 500.0f);
  EXPECT_EQ(cam->aspect, 1.5f);
  EXPECT_TRUE(cam->active);
  EXPECT_EQ(w.get<Transform>(by_name.at("cam")).translation, glm::vec3(0, 1, 5));

  const Camera* infinite = w.try_get<Camera>(by_name.at("cam_infinite"));
  ASSERT_NE(infinite, nullptr);
  EXPECT_NEAR(infinite->far, 100.0f, 1e-3f);  // 1000 * znear
  EXPECT_EQ(infinite->aspect, 0.0f);          // from the output image
  EXPECT_FALSE(infinite->active);

  const Camera* ortho = w.try_get<Camera>(by_name.at("cam_ortho"));
  ASSERT_NE(ortho, nullptr);
  EXPECT_EQ(ortho->projection, Projection::orthographic);
  EXPECT_EQ(ortho->ortho_height, 10.0f);
  EXPECT_EQ(ortho->aspect, 2.0f);
  EXPECT_GT(ortho->near, 0.0f);
  EXPECT_EQ(ortho->far, 100.0f);

  // TRS and parent links.
  const Transform& parent = w.get<Transform>(by_name.at("parent"));
  EXPECT_EQ(parent.parent, s->root);
  EXPECT_EQ(parent.translation, glm::vec3(1, 2, 3));
  EXPECT_EQ(parent.scale, glm::vec3(2));
  EXPECT_NEAR(parent.rotation.w, 0.70710678f, 1e-6f);
  EXPECT_NEAR(parent.rotation.y, 0.70710678f, 1e-6f);
  EXPECT_EQ(w.get<Transform>(by_name.at("tri")).parent, by_name.at("parent"));
  EXPECT_EQ(w.get<Transform>(by_name.at("sun_node")).parent, s->root);

  // The triangle had no normals: flat ones are generated (+Z for this counter-clockwise face).
  ASSERT_EQ(s->assets.meshes.size(), 1u);
  expect_valid_meshes(s->assets);
  for (const glm::vec3& n : s->assets.meshes[0].normals) EXPECT_EQ(n, glm::vec3(0, 0, 1));
}

TEST(GltfLoader, MatrixNodesAreDecomposed) {
  json doc = triangle_gltf();
  doc["nodes"][0].erase("translation");
  doc["nodes"][0].erase("rotation");
  doc["nodes"][0].erase("scale");
  // Column-major: rotate 90 degrees about Z, scale (2, 3, -1) (a mirror), translate (4, 5, 6).
  doc["nodes"][0]["matrix"] = {0, 2, 0, 0, -3, 0, 0, 0, 0, 0, -1, 0, 4, 5, 6, 1};
  auto s = import_file(write_gltf("matrix.gltf", doc));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  const Transform& t = s->world.get<Transform>(entities_by_name(s->world).at("parent"));
  EXPECT_EQ(t.translation, glm::vec3(4, 5, 6));
  // Recompose and compare with the original matrix.
  const glm::mat4 m = glm::translate(glm::mat4(1), t.translation) * glm::mat4_cast(t.rotation) *
                      glm::scale(glm::mat4(1), t.scale);
  const float expected[16] = {0, 2, 0, 0, -3, 0, 0, 0, 0, 0, -1, 0, 4, 5, 6, 1};
  for (int i = 0; i < 16; ++i) EXPECT_NEAR(m[i / 4][i % 4], expected[i], 1e-5f) << i;
}

TEST(GltfLoader, NormalizedAndSparseAccessorsAreDecoded) {
  // Positions stored as normalized signed bytes, with a sparse override of vertex 2.
  std::vector<std::uint8_t> buffer;
  append<std::int8_t>(buffer,
                      {0, 0, 0, 0, 127, 0, 0, 0, -128, 0, 0, 0, 0, 0, 0, 0});  // 3 x (xyz+pad)
  append<std::uint8_t>(buffer, {2, 0, 0, 0});                                  // sparse index
  append<std::int8_t>(buffer, {0, 127, 0, 0});                                 // sparse value
  json doc = triangle_gltf();
  doc["buffers"][0] = {{"byteLength", buffer.size()},
                       {"uri", "data:application/octet-stream;base64," + base64(buffer)}};
  doc["bufferViews"] = {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 12}, {"byteStride", 4}},
                        {{"buffer", 0}, {"byteOffset", 16}, {"byteLength", 1}},
                        {{"buffer", 0}, {"byteOffset", 20}, {"byteLength", 3}}};
  doc["accessors"] = {{{"bufferView", 0},
                       {"componentType", 5120},
                       {"normalized", true},
                       {"count", 3},
                       {"type", "VEC3"},
                       {"sparse",
                        {{"count", 1},
                         {"indices", {{"bufferView", 1}, {"componentType", 5121}}},
                         {"values", {{"bufferView", 2}}}}}}};
  doc["meshes"][0]["primitives"][0].erase("indices");  // non-indexed
  doc["extensionsUsed"] = {"KHR_mesh_quantization"};
  doc["extensionsRequired"] = {"KHR_mesh_quantization"};
  auto s = import_file(write_gltf("quantized.gltf", doc));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  ASSERT_EQ(s->assets.meshes.size(), 1u);
  const MeshData& m = s->assets.meshes[0];
  ASSERT_EQ(m.triangle_count(), 1u);
  // Flat normals un-index the mesh, but the vertex order is kept.
  EXPECT_EQ(m.positions[0], glm::vec3(0, 0, 0));
  EXPECT_EQ(m.positions[1], glm::vec3(1, 0, 0));
  EXPECT_EQ(m.positions[2], glm::vec3(0, 1, 0));  // sparse value, not the stored (-1, 0, 0)
}

// ---- Errors: named, and never a crash -------------------------------------------------------

void expect_import_error(const std::filesystem::path& path, const std::string& also_mentions = {}) {
  auto s = import_file(path);
  ASSERT_FALSE(s->report.ok()) << path;
  const std::string text = s->report.error().to_string();
  EXPECT_TRUE(mentions(s->report.error(), path.string())) << text;
  if (!also_mentions.empty()) {
    EXPECT_TRUE(mentions(s->report.error(), also_mentions)) << text;
  }
}

TEST(GltfLoaderErrors, MissingFile) {
  expect_import_error(temp_dir() / "nope.glb", "not found");
}

TEST(GltfLoaderErrors, InvalidJson) {
  const auto path = temp_dir() / "invalid.gltf";
  write_text(path, "{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [ {, ] }");
  expect_import_error(path);
}

TEST(GltfLoaderErrors, DeeplyNestedJson) {
  const auto path = temp_dir() / "nested.gltf";
  write_text(path, "{\"asset\":{\"version\":\"2.0\"},\"extras\":" + std::string(100000, '[') +
                       std::string(100000, ']') + "}");
  expect_import_error(path, "nested");
}

// A data: URI's media type must be one its place takes: tinygltf alone decodes a text/plain
// buffer and reads an image of another type as a file name. The error names the URI's place.
TEST(GltfLoaderErrors, DataUrisOfTheWrongMediaType) {
  json doc = triangle_gltf();
  const std::string uri = doc["buffers"][0]["uri"];
  ASSERT_EQ(uri.rfind("data:application/octet-stream;base64,", 0), 0u) << uri.substr(0, 40);
  const std::string payload = uri.substr(uri.find(',') + 1);
  doc["buffers"][0]["uri"] = "data:application/gltf-buffer;base64," + payload;
  EXPECT_TRUE(import_file(write_gltf("gltf_buffer_uri.gltf", doc))->report.ok());
  doc["buffers"][0]["uri"] = "data:text/plain;base64," + payload;
  expect_import_error(write_gltf("text_buffer_uri.gltf", doc), "/buffers/0/uri");
  expect_import_error(write_gltf("text_buffer_uri.gltf", doc), "'text/plain'");
  doc = triangle_gltf();
  doc["images"] = {{{"uri", "data:text/html;base64,PGh0bWw+"}}};
  expect_import_error(write_gltf("html_image_uri.gltf", doc), "/images/0/uri");
}

// A file of another major version is refused; odd material values load clamped, with a warning
// each (glTF 2.0: baseColorFactor and alphaCutoff in [0, 1], alphaMode one of three names).
TEST(GltfLoaderErrors, AnotherMajorVersionAndOddMaterialValues) {
  json doc = triangle_gltf();
  doc["asset"]["version"] = "3.0";
  expect_import_error(write_gltf("version_3.gltf", doc), "only 2.x files are read");
  doc = triangle_gltf();
  doc["materials"] = {{{"alphaMode", "WEIRD"},
                       {"pbrMetallicRoughness", {{"baseColorFactor", {2, -1, 0.5, 1}}}}}};
  doc["meshes"][0]["primitives"][0]["material"] = 0;
  auto s = import_file(write_gltf("odd_material.gltf", doc));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  std::string warnings;
  for (const std::string& w : s->report->warnings) warnings += w + "\n";
  EXPECT_NE(warnings.find("baseColorFactor outside [0, 1], clamped"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find("unknown alphaMode 'WEIRD'"), std::string::npos) << warnings;
}

TEST(GltfLoaderErrors, MissingBufferFile) {
  json doc = triangle_gltf();
  doc["buffers"][0]["uri"] = "missing.bin";
  expect_import_error(write_gltf("missing_buffer.gltf", doc), "missing.bin");
}

TEST(GltfLoaderErrors, AccessorIndexOutOfRange) {
  json doc = triangle_gltf();
  doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 7;
  expect_import_error(write_gltf("bad_accessor.gltf", doc), "accessor");
}

TEST(GltfLoaderErrors, AccessorPastTheEndOfItsBufferView) {
  json doc = triangle_gltf();
  doc["accessors"][0]["count"] = 4;
  expect_import_error(write_gltf("long_accessor.gltf", doc), "bufferViews[0]");
  doc = triangle_gltf();
  doc["bufferViews"][0]["byteLength"] = 1000;  // view outside its buffer
  expect_import_error(write_gltf("long_view.gltf", doc), "exceeds buffer");
}

TEST(GltfLoaderErrors, IndexValueOutOfRange) {
  std::vector<std::uint8_t> buffer;
  append<float>(buffer, {0, 0, 0, 1, 0, 0, 0, 1, 0});
  append<std::uint16_t>(buffer, {0, 1, 5, 0});
  json doc = triangle_gltf();
  doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(buffer);
  expect_import_error(write_gltf("bad_index.gltf", doc), "index 5");
}

TEST(GltfLoaderErrors, IndexCountNotAMultipleOfThree) {
  json doc = triangle_gltf();
  doc["accessors"][1]["count"] = 2;
  expect_import_error(write_gltf("two_indices.gltf", doc), "multiple of 3");
}

TEST(GltfLoaderErrors, NonFinitePositionsNameTheMesh) {
  std::vector<std::uint8_t> buffer;
  append<float>(buffer, {0, 0, 0, NAN, 0, 0, 0, 1, 0});
  append<std::uint16_t>(buffer, {0, 1, 2, 0});
  json doc = triangle_gltf();
  doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(buffer);
  expect_import_error(write_gltf("nan.gltf", doc), "\"triangle\"");
  const float infinity = std::numeric_limits<float>::infinity();  // replaces the NaN
  std::memcpy(buffer.data() + 12, &infinity, 4);
  doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(buffer);
  expect_import_error(write_gltf("inf.gltf", doc), "POSITION");
}

TEST(GltfLoaderErrors, BadHierarchy) {
  json doc = triangle_gltf();
  doc["nodes"][0]["children"] = {1, 9};
  expect_import_error(write_gltf("bad_child.gltf", doc), "child 9");
  doc = triangle_gltf();
  doc["nodes"][1]["children"] = {0};  // a cycle: 0 -> 1 -> 0
  expect_import_error(write_gltf("cycle.gltf", doc), "root");
}

TEST(GltfLoaderErrors, UnsupportedRequiredExtension) {
  json doc = triangle_gltf();
  doc["extensionsRequired"] = {"KHR_texture_basisu"};
  expect_import_error(write_gltf("basisu.gltf", doc), "KHR_texture_basisu");
}

TEST(GltfLoaderErrors, InvalidLightAndCamera) {
  json doc = triangle_gltf();
  doc["extensions"]["KHR_lights_punctual"]["lights"] = {
      {{"type", "spot"}, {"spot", {{"innerConeAngle", 0.9}, {"outerConeAngle", 0.5}}}}};
  doc["nodes"][0]["extensions"]["KHR_lights_punctual"]["light"] = 0;
  expect_import_error(write_gltf("bad_spot.gltf", doc), "cone");
  doc = triangle_gltf();
  doc["nodes"][0]["extensions"]["KHR_lights_punctual"]["light"] = 3;
  expect_import_error(write_gltf("bad_light_index.gltf", doc), "light");
  doc = triangle_gltf();
  doc["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", -1.0}}}}};
  doc["nodes"][0]["camera"] = 0;
  expect_import_error(write_gltf("bad_camera.gltf", doc), "znear");
}

/// Byte range of the first Draco buffer view of a .glb, in file offsets.
std::pair<std::size_t, std::size_t> draco_range(const std::vector<std::uint8_t>& glb) {
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, glb.data() + 12, 4);
  const json doc = json::parse(glb.begin() + 20, glb.begin() + 20 + json_length);
  const int view =
      doc["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["bufferView"];
  const std::size_t bin_start = 20 + json_length + 8;
  const auto& v = doc["bufferViews"][view];
  return {bin_start + v.value("byteOffset", std::size_t(0)), v["byteLength"].get<std::size_t>()};
}

TEST(GltfLoaderErrors, CorruptDracoStreamIsAnError) {
  const auto original = read_bytes(content_path("models/Box/glTF-Draco-Binary/Box_Draco.glb"));
  const auto [start, length] = draco_range(original);
  ASSERT_LE(start + length, original.size());
  ASSERT_GT(length, 16u);

  // Garbage over the stream's header: the decoder must reject it.
  auto bytes = original;
  for (std::size_t i = 0; i < length / 2; ++i) bytes[start + i] = std::uint8_t(0xA5 ^ (i * 29));
  const auto path = temp_dir() / "corrupt_draco.glb";
  write_bytes(path, bytes);
  expect_import_error(path, "Draco");

  // Garbage further in may or may not decode; it must never crash, and whatever is imported must
  // be valid.
  for (std::size_t from = 8; from < length; from += 7) {
    bytes = original;
    for (std::size_t i = from; i < std::min(length, from + 12); ++i)
      bytes[start + i] = std::uint8_t(i * 131 + from);
    write_bytes(path, bytes);
    auto s = import_file(path);
    if (s->report.ok()) {
      expect_valid_meshes(s->assets);
    } else {
      EXPECT_TRUE(mentions(s->report.error(), path.string())) << s->report.error().to_string();
    }
  }
}

TEST(GltfLoaderErrors, EveryTruncationOfABinaryFileIsHandled) {
  const auto original = read_bytes(content_path("models/Box/glTF-Draco-Binary/Box_Draco.glb"));
  const auto path = temp_dir() / "truncated.glb";
  for (std::size_t keep = 0; keep < original.size(); keep += 13) {
    write_bytes(path, original.data(), keep);
    auto s = import_file(path);
    // A cut inside the BIN chunk is an error; the header says how long the file must be.
    ASSERT_FALSE(s->report.ok()) << "kept " << keep << " bytes";
    EXPECT_TRUE(mentions(s->report.error(), path.string()));
  }
}

TEST(GltfLoaderErrors, MissingTextureIsAWarning) {
  json doc = triangle_gltf();
  doc["images"] = {{{"uri", "no_such_texture.png"}}};
  doc["textures"] = {{{"source", 0}}};
  doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
  doc["meshes"][0]["primitives"][0]["material"] = 0;
  auto s = import_file(write_gltf("missing_texture.gltf", doc));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  EXPECT_TRUE(s->assets.textures.empty());
  bool warned = false;
  for (const auto& w : s->report->warnings)
    warned |= w.find("no_such_texture.png") != std::string::npos;
  EXPECT_TRUE(warned);
}

// ---- Material inputs: occlusion, emission, texture transforms --------------------------------

/// triangle_gltf() with two 2x2 PNG images (written next to the file), one texture each, and
/// material 0 on the triangle set to `material`.
json textured_triangle(const json& material) {
  for (const char* name : {"tex_a.png", "tex_b.png"}) {
    Image image;
    image.width = image.height = 2;
    image.channels = 4;
    image.pixels.assign(16, 0.5f);
    EXPECT_TRUE(save_image(temp_dir() / name, image).ok());
  }
  json doc = triangle_gltf();
  doc["images"] = {{{"uri", "tex_a.png"}}, {{"uri", "tex_b.png"}}};
  doc["textures"] = {{{"source", 0}}, {{"source", 1}}};
  doc["materials"] = {material};
  doc["meshes"][0]["primitives"][0]["material"] = 0;
  return doc;
}

/// The one Material of an import (the triangle's).
Material only_material(Imported3d& s) {
  Material out;
  int n = 0;
  s.world.view<Material>().each([&](ecs::Entity, Material& m) { out = m, ++n; });
  EXPECT_EQ(n, 1);
  return out;
}


// alphaMode BLEND is a blended material (its alphaCutoff ignored: 0.5, the shadow threshold),
// MASK a cut-out, and KHR_materials_transmission blends with transmission_opacity() of the
// base alpha (components/material.h); each maps onto its material feature.
TEST(GltfLoader, AlphaModesAndTransmissionBecomeAlphaModes) {
  using render::VariantKey;
  auto material_of = [](const json& material, const std::string& name) {
    json doc = triangle_gltf();
    doc["materials"] = {material};
    doc["meshes"][0]["primitives"][0]["material"] = 0;
    doc["extensionsUsed"] = {"KHR_materials_transmission"};
    auto s = import_file(write_gltf(name, doc));
    EXPECT_TRUE(s->report.ok()) << s->report.error().to_string();
    EXPECT_FALSE(warns(*s->report, "BLEND")) << "no longer drawn opaque";
    EXPECT_FALSE(warns(*s->report, "KHR_materials_transmission"));  // supported
    return only_material(*s);
  };
  const Material blend = material_of(
      {{"alphaMode", "BLEND"}, {"alphaCutoff", 0.2},
       {"pbrMetallicRoughness", {{"baseColorFactor", {1, 0, 0, 0.4}}}}},
      "blend.gltf");
  EXPECT_EQ(blend.alpha_mode, AlphaMode::blend);
  EXPECT_FLOAT_EQ(blend.alpha_cutoff, 0.5f);
  EXPECT_FLOAT_EQ(blend.base_color.a, 0.4f);
  EXPECT_EQ(blend.features, VariantKey::kAlphaBlend.mask());
  const Material mask = material_of({{"alphaMode", "MASK"}, {"alphaCutoff", 0.3}}, "mask.gltf");
  EXPECT_EQ(mask.alpha_mode, AlphaMode::mask);
  EXPECT_FLOAT_EQ(mask.alpha_cutoff, 0.3f);
  EXPECT_EQ(mask.features, VariantKey::kAlphaMask.mask());
  const Material glass = material_of(
      {{"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 0.5}}}},
       {"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 0.5}}}}}},
      "transmission.gltf");
  EXPECT_EQ(glass.alpha_mode, AlphaMode::blend);
  EXPECT_FLOAT_EQ(glass.base_color.a, 0.5f * (1.0f - 0.5f * (1.0f - kTransmissionOpacityFloor)));
  EXPECT_EQ(glass.features, VariantKey::kAlphaBlend.mask());
  EXPECT_FLOAT_EQ(transmission_opacity(1.0f, 1.0f), kTransmissionOpacityFloor);
  EXPECT_FLOAT_EQ(transmission_opacity(0.8f, 0.0f), 0.8f);
  // No transmission: opaque stays opaque.
  const Material none = material_of(
      {{"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 0.0}}}}}},
      "no_transmission.gltf");
  EXPECT_EQ(none.alpha_mode, AlphaMode::opaque);
  EXPECT_EQ(none.features, 0u);
  json doc = triangle_gltf();
  doc["materials"] = {
      {{"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 2.0}}}}}}};
  doc["meshes"][0]["primitives"][0]["material"] = 0;
  expect_import_error(write_gltf("bad_transmission.gltf", doc), "transmissionFactor");
}

TEST(GltfLoader, OcclusionTextureIsReadWithItsStrength) {
  json doc = textured_triangle({{"occlusionTexture", {{"index", 1}, {"strength", 0.25}}}});
  auto s = import_file(write_gltf("occlusion.gltf", doc));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  const Material m = only_material(*s);
  ASSERT_NE(m.occlusion_texture, kNoTexture);
  EXPECT_FALSE(s->assets.textures[index(m.occlusion_texture)].srgb);  // data, not colour
  EXPECT_FLOAT_EQ(m.occlusion_strength, 0.25f);
  EXPECT_EQ(m.features, render::VariantKey::kOcclusionTexture.mask());
  EXPECT_FALSE(warns(*s->report, "occlusionTexture"));  // no longer "not imported"
  // Strength defaults to 1; outside [0, 1] it is an error naming the material and the field.
  doc["materials"][0]["occlusionTexture"].erase("strength");
  auto d = import_file(write_gltf("occlusion_default.gltf", doc));
  ASSERT_TRUE(d->report.ok()) << d->report.error().to_string();
  EXPECT_FLOAT_EQ(only_material(*d).occlusion_strength, 1.0f);
  doc["materials"][0]["occlusionTexture"]["strength"] = 1.5;
  expect_import_error(write_gltf("occlusion_bad.gltf", doc), "occlusionTexture");
}

TEST(GltfLoader, MetallicRoughnessTextureIsReadAsLinearDataWithItsTransform) {
  json mr = {{"index", 1},
             {"extensions", {{"KHR_texture_transform", {{"offset", {0.25, 0.0}}}}}}};
  json doc = textured_triangle({{"pbrMetallicRoughness",
                                 {{"metallicFactor", 0.5},
                                  {"roughnessFactor", 0.75},
                                  {"metallicRoughnessTexture", mr}}}});
  doc["extensionsUsed"] = {"KHR_texture_transform"};
  auto s = import_file(write_gltf("metallic_roughness.gltf", doc));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  const Material m = only_material(*s);
  ASSERT_NE(m.metallic_roughness_texture, kNoTexture);
  EXPECT_FALSE(s->assets.textures[index(m.metallic_roughness_texture)].srgb);  // data, not colour
  EXPECT_FLOAT_EQ(m.metallic, 0.5f);  // the factors stay; the texture multiplies them
  EXPECT_FLOAT_EQ(m.roughness, 0.75f);
  EXPECT_EQ(m.metallic_roughness_transform.offset, glm::vec2(0.25f, 0.0f));
  EXPECT_EQ(m.features, render::VariantKey::kMetallicRoughnessTexture.mask() |
                            render::VariantKey::kTextureTransform.mask());
  EXPECT_FALSE(warns(*s->report, "metallicRoughnessTexture"));  // no longer "not imported"
  // A bad transform is an error naming this slot.
  doc["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"]["extensions"]
     ["KHR_texture_transform"] = {{"scale", {1.0}}};
  expect_import_error(write_gltf("metallic_roughness_bad.gltf", doc),
                      "metallicRoughnessTexture KHR_texture_transform");
}

TEST(GltfLoader, EmissiveTextureAndStrength) {
  json doc = textured_triangle(
      {{"emissiveFactor", {1.0, 0.5, 0.25}},
       {"emissiveTexture", {{"index", 0}}},
       {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4.0}}}}}});
  doc["extensionsUsed"] = {"KHR_materials_emissive_strength"};
  auto s = import_file(write_gltf("emissive.gltf", doc));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  const Material m = only_material(*s);
  EXPECT_EQ(m.emissive, glm::vec3(4.0f, 2.0f, 1.0f));
  ASSERT_NE(m.emissive_texture, kNoTexture);
  EXPECT_TRUE(s->assets.textures[index(m.emissive_texture)].srgb);
  EXPECT_EQ(m.features,
            render::VariantKey::kEmissive.mask() | render::VariantKey::kEmissiveTexture.mask());
  EXPECT_FALSE(warns(*s->report, "emissiveTexture"));
  // Without emission the texture multiplies zero: no feature (emissive_texture needs emissive).
  doc["materials"][0].erase("emissiveFactor");
  auto dark = import_file(write_gltf("emissive_dark.gltf", doc));
  ASSERT_TRUE(dark->report.ok()) << dark->report.error().to_string();
  EXPECT_EQ(only_material(*dark).features, 0u);
  // A strength that is not a number is an error naming the extension.
  doc["materials"][0]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] = "4";
  expect_import_error(write_gltf("emissive_bad.gltf", doc), "KHR_materials_emissive_strength");
}

TEST(GltfLoader, TextureTransformsArePerSlotWithTexCoordOverride) {
  json base = {{"index", 0},
               {"extensions",
                {{"KHR_texture_transform",
                  {{"offset", {0.5, -0.25}}, {"rotation", 1.5707963}, {"scale", {2.0, 3.0}}}}}}};
  // texCoord 1 overridden by the extension's texCoord 0: imported without a TEXCOORD warning.
  json normal = {{"index", 1},
                 {"texCoord", 1},
                 {"extensions", {{"KHR_texture_transform", {{"texCoord", 0}}}}}};
  json doc = textured_triangle({{"pbrMetallicRoughness", {{"baseColorTexture", base}}},
                                {"normalTexture", normal}});
  doc["extensionsUsed"] = {"KHR_texture_transform"};
  doc["extensionsRequired"] = {"KHR_texture_transform"};
  auto s = import_file(write_gltf("transform.gltf", doc));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  const Material m = only_material(*s);
  EXPECT_EQ(m.base_color_transform.offset, glm::vec2(0.5f, -0.25f));
  EXPECT_FLOAT_EQ(m.base_color_transform.rotation, 1.5707963f);
  EXPECT_EQ(m.base_color_transform.scale, glm::vec2(2.0f, 3.0f));
  EXPECT_EQ(m.normal_transform, TextureTransform{});
  EXPECT_NE(m.normal_texture, kNoTexture);
  EXPECT_FALSE(warns(*s->report, "TEXCOORD"));
  EXPECT_TRUE(m.features & render::VariantKey::kTextureTransform.mask());
  // The rows the shader applies: KHR_texture_transform's T * R * S. The point (1, 0) scales to
  // (2, 0), rotates by +90 degrees in the extension's convention to (0, -2), moves to
  // (0.5, -2.25).
  const auto rows = uv_transform_rows(m.base_color_transform);
  EXPECT_NEAR(glm::dot(rows[0], glm::vec3(1, 0, 1)), 0.5f, 1e-6f);
  EXPECT_NEAR(glm::dot(rows[1], glm::vec3(1, 0, 1)), -2.25f, 1e-6f);
  // An override to the second set is that set; to a set that is not imported, a warning.
  doc["materials"][0]["normalTexture"]["extensions"]["KHR_texture_transform"]["texCoord"] = 1;
  auto t1 = import_file(write_gltf("transform_uv1.gltf", doc));
  ASSERT_TRUE(t1->report.ok()) << t1->report.error().to_string();
  EXPECT_FALSE(warns(*t1->report, "TEXCOORD"));
  EXPECT_EQ(only_material(*t1).normal_transform.tex_coord, 1);
  doc["materials"][0]["normalTexture"]["extensions"]["KHR_texture_transform"]["texCoord"] = 2;
  auto t2 = import_file(write_gltf("transform_uv2.gltf", doc));
  ASSERT_TRUE(t2->report.ok()) << t2->report.error().to_string();
  EXPECT_TRUE(warns(*t2->report, "TEXCOORD_2"));
  EXPECT_EQ(only_material(*t2).normal_transform.tex_coord, 0);
  // An identity transform is no feature.
  doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]
     ["KHR_texture_transform"] = json::object();
  auto identity = import_file(write_gltf("transform_identity.gltf", doc));
  ASSERT_TRUE(identity->report.ok()) << identity->report.error().to_string();
  EXPECT_FALSE(only_material(*identity).features & render::VariantKey::kTextureTransform.mask());
  // Bad values are errors naming the slot, the extension and the field.
  doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]
     ["KHR_texture_transform"] = {{"scale", {1.0}}};
  auto bad = import_file(write_gltf("transform_bad.gltf", doc));
  ASSERT_FALSE(bad->report.ok());
  const std::string text = bad->report.error().to_string();
  EXPECT_NE(text.find("baseColorTexture KHR_texture_transform"), std::string::npos) << text;
  EXPECT_NE(text.find("scale must be 2 finite numbers"), std::string::npos) << text;
  doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]
     ["KHR_texture_transform"] = {{"rotation", "fast"}};
  expect_import_error(write_gltf("transform_bad_rotation.gltf", doc), "rotation");
}

// ---- Second uv set, WebP and AVIF textures --------------------------------------------------

/// textured_triangle(material) whose triangle has TEXCOORD_0 `uv0` and TEXCOORD_1 `uv1` (3 each).
json two_uv_triangle(const json& material, std::initializer_list<float> uv0,
                     std::initializer_list<float> uv1) {
  json doc = textured_triangle(material);
  std::vector<float> floats(uv0);
  floats.insert(floats.end(), uv1);
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(floats.data());
  const std::vector<std::uint8_t> uvs(bytes, bytes + floats.size() * sizeof(float));
  doc["buffers"].push_back({{"byteLength", uvs.size()},
                            {"uri", "data:application/octet-stream;base64," + base64(uvs)}});
  doc["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", 24}});
  doc["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 24}, {"byteLength", 24}});
  doc["accessors"].push_back({{"bufferView", 2}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}});
  doc["accessors"].push_back({{"bufferView", 3}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}});
  doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 2;
  doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = 3;
  return doc;
}

// A slot that names texCoord 1 reads TEXCOORD_1 (occlusion maps usually do): the mesh keeps the
// set, the slot's transform records it, and the material takes the texture_transform feature
// (whose programs pass the second set on). A mesh without TEXCOORD_1 gives such slots its first.
TEST(GltfLoader, SecondUvSetIsImportedForTheSlotsThatNameIt) {
  json doc = two_uv_triangle({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}},
                              {"occlusionTexture", {{"index", 1}, {"texCoord", 1}}}},
                             {0, 0, 1, 0, 0, 1}, {0.5f, 0.5f, 0.75f, 0.5f, 0.5f, 0.75f});
  auto s = import_file(write_gltf("uv1.gltf", doc));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  EXPECT_FALSE(warns(*s->report, "TEXCOORD"));
  ASSERT_EQ(s->assets.meshes.size(), 1u);
  const MeshData& mesh = s->assets.meshes[0];
  ASSERT_EQ(mesh.uvs1.size(), 3u);
  EXPECT_EQ(mesh.uvs1[1], glm::vec2(0.75f, 0.5f));
  EXPECT_EQ(mesh.uvs[1], glm::vec2(1.0f, 0.0f));
  EXPECT_EQ(&mesh.uv_set(1), &mesh.uvs1);
  EXPECT_EQ(&mesh.uv_set(0), &mesh.uvs);
  const Material m = only_material(*s);
  EXPECT_EQ(m.occlusion_transform.tex_coord, 1);
  EXPECT_EQ(m.base_color_transform.tex_coord, 0);
  EXPECT_TRUE(m.features & render::VariantKey::kTextureTransform.mask());
  // Without TEXCOORD_1 the slot reads TEXCOORD_0.
  MeshData no_uv1 = mesh;
  no_uv1.uvs1.clear();
  EXPECT_EQ(&no_uv1.uv_set(1), &no_uv1.uvs);
  // A TEXCOORD_1 of the wrong length is an error naming it.
  doc["accessors"][3]["count"] = 2;
  expect_import_error(write_gltf("uv1_short.gltf", doc), "TEXCOORD_1");
}

// EXT_texture_webp: the texture shows its WebP image (OpenImageIO decodes it), not the fallback
// source; a file that requires the extension loads. EXT_texture_avif is not decoded: its
// fallback source is shown, a texture with no fallback is drawn without it (a warning naming
// it), and a file that requires the extension is refused with the reason.
TEST(GltfLoader, WebpTexturesAreDecodedAndAvifFallsBack) {
  Image webp;
  webp.width = webp.height = 2;
  webp.channels = 4;
  webp.pixels.assign(16, 1.0f);  // white; the PNG fallback is grey
  for (std::size_t i = 0; i < 16; i += 4) webp.pixels[i + 1] = 0.0f;  // magenta
  const Status saved = save_image(temp_dir() / "tex_c.webp", webp);
  ASSERT_TRUE(saved.ok()) << saved.error().to_string();
  json doc = textured_triangle({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
  doc["images"].push_back({{"uri", "tex_c.webp"}});
  doc["textures"][0]["extensions"]["EXT_texture_webp"] = {{"source", 2}};
  doc["extensionsUsed"] = {"EXT_texture_webp"};
  doc["extensionsRequired"] = {"EXT_texture_webp"};
  auto s = import_file(write_gltf("webp.gltf", doc));
  ASSERT_TRUE(s->report.ok()) << s->report.error().to_string();
  const Material m = only_material(*s);
  ASSERT_NE(m.base_color_texture, kNoTexture);
  const TextureData& t = s->assets.textures[index(m.base_color_texture)];
  ASSERT_EQ(t.rgba8.size(), 16u);
  EXPECT_GT(t.rgba8[0], 239);  // the WebP's magenta (WebP is lossy: near it)
  EXPECT_LT(t.rgba8[1], 16);
  EXPECT_GT(t.rgba8[2], 239);
  doc["textures"][0]["extensions"]["EXT_texture_webp"] = {{"source", -1}};
  expect_import_error(write_gltf("webp_bad.gltf", doc), "EXT_texture_webp");

  json avif = textured_triangle({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
  avif["images"].push_back({{"uri", "tex_c.avif"}});  // never read
  avif["textures"][0]["extensions"]["EXT_texture_avif"] = {{"source", 2}};
  avif["extensionsUsed"] = {"EXT_texture_avif"};
  auto fallback = import_file(write_gltf("avif_fallback.gltf", avif));
  ASSERT_TRUE(fallback->report.ok()) << fallback->report.error().to_string();
  const Material fm = only_material(*fallback);
  ASSERT_NE(fm.base_color_texture, kNoTexture);
  EXPECT_GT(fallback->assets.textures[index(fm.base_color_texture)].rgba8[1], 100);  // grey PNG
  avif["textures"][0].erase("source");
  auto none = import_file(write_gltf("avif_only.gltf", avif));
  ASSERT_TRUE(none->report.ok()) << none->report.error().to_string();
  EXPECT_EQ(only_material(*none).base_color_texture, kNoTexture);
  EXPECT_TRUE(warns(*none->report, "only an EXT_texture_avif image"));
  avif["extensionsRequired"] = {"EXT_texture_avif"};
  expect_import_error(write_gltf("avif_required.gltf", avif), "AVIF images are not decoded");
}

}  // namespace
}  // namespace kaskad
