// glTF import of living content: skins, morph targets and animation clips, from real content
// (the Fox) and from small files the tests write, with the errors and warnings bad ones get.
#include "tests/unit/assets/gltf_test_util.h"

namespace kaskad {
namespace {

using namespace gltf_test;

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

}  // namespace
}  // namespace kaskad
