// glTF materials on import: alpha modes and transmission, occlusion, emission, metallic-roughness
// and texture transforms per slot, the second uv set, and WebP and AVIF textures.
#include "tests/unit/assets/gltf_test_util.h"

namespace kaskad {
namespace {

using namespace gltf_test;

// ---- Material inputs: occlusion, emission, texture transforms --------------------------------



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
