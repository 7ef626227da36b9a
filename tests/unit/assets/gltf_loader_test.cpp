// glTF import of real content, nodes (lights, cameras, transforms) and accessors, and the errors
// malformed files get.
#include "tests/unit/assets/gltf_test_util.h"

namespace kaskad {
namespace {

using namespace gltf_test;

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

}  // namespace
}  // namespace kaskad
