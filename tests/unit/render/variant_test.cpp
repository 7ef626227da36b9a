// Variant keys, the feature manifest and material files: no GL needed.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "runtime/assets/material_file.h"
#include "runtime/render/feature_manifest.h"
#include "runtime/render/renderer.h"
#include "runtime/render/variant_key.h"

namespace kaskad::render {
namespace {

namespace fs = std::filesystem;
const fs::path kShaders = fs::path(KASKAD_CONTENT_DIR) / "shaders";

FeatureManifest manifest() {
  auto m = FeatureManifest::load(kShaders / "features.json");
  EXPECT_TRUE(m.ok()) << m.error().to_string();
  return m.ok() ? std::move(m.value()) : FeatureManifest();
}

fs::path temp(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(KASKAD_TEST_TMP) / "variants";
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary) << text;
  return dir / name;
}

// The rules of variant_key.h's header comment, written out independently of kFeatureTable.
bool documented_rules_hold(VariantKey k) {
  using V = VariantKey;
  const std::uint32_t used =
      V::kBaseColorTexture.mask() | V::kNormalMap.mask() | V::kAlphaMask.mask() |
      V::kEmissive.mask() | V::kReflectionCube.mask() | V::kReflectionSphere.mask() |
      V::kReceiveShadows.mask() | V::kReflectionBox.mask() | V::kShadow.mask() |
      V::kShadowFilter.mask() | V::kCascadeCountMinus1.mask() | V::kAovs.mask() |
      V::kDebugCascades.mask() | V::kCascadeSelection.mask() | V::kShadowProjection.mask() |
      V::kShadowLayered.mask() | V::kShadowLightsMinus1.mask();
  if (k.bits() & ~used) return false;
  if (k.get(V::kShadowFilter) > 2) return false;  // none, bilinear, pcf3x3
  if (k.has(V::kReflectionCube) && k.has(V::kReflectionSphere)) return false;
  if (k.has(V::kReflectionBox) && !k.has(V::kReflectionCube)) return false;
  const bool needs_shadow = k.has(V::kShadowFilter) || k.has(V::kCascadeCountMinus1) ||
                            k.has(V::kDebugCascades) || k.has(V::kCascadeSelection) ||
                            k.has(V::kShadowProjection) || k.has(V::kShadowLayered) ||
                            k.has(V::kShadowLightsMinus1);
  if (needs_shadow && !k.has(V::kShadow)) return false;
  if (k.has(V::kShadowProjection) && k.has(V::kCascadeCountMinus1)) return false;
  return true;
}

TEST(VariantKey, EveryKeyFollowsTheDocumentedRules) {
  const FeatureManifest m = manifest();
  std::uint32_t used = 0;
  for (const auto& f : m.features()) used |= f.field.mask();
  // Every key over the used bits (every subset of them: all values of every field, selection,
  // projection and layered included): valid() (kFeatureTable's rules) agrees with the rules
  // written out above, the manifest names a broken rule exactly when valid() is false, and a
  // valid key filters to itself for the forward pass (it reads everything) and to valid keys
  // for the others.
  int valid = 0, disagree = 0;
  for (std::uint32_t bits = 0;; bits = ((bits | ~used) + 1) & used) {
    const VariantKey k(bits);
    if ((k.valid() != documented_rules_hold(k) || k.valid() != m.check(k).empty()) &&
        disagree++ < 5)
      ADD_FAILURE() << "key 0x" << std::hex << bits << ": valid() " << k.valid()
                    << ", documented rules " << documented_rules_hold(k) << ", manifest: '"
                    << m.check(k) << "' (" << m.describe(k) << ")";
    if (k.valid()) {
      ++valid;
      EXPECT_EQ(k.filtered_for(Pass::forward), k);
      EXPECT_TRUE(k.filtered_for(Pass::depth).valid());
      EXPECT_TRUE(k.filtered_for(Pass::shadow_points).valid());
    }
    if (bits == used) break;
  }
  EXPECT_EQ(disagree, 0);
  // Material keys: 2^5 free bits x 4 of the 8 reflection cube/sphere/box combinations = 128.
  // Frame keys: 2 without shadow (aovs), and with shadow 3 filters x 2 aovs x 2 debug x
  // 2 selection x 2 layered x 4 shadowed-light counts x (8 ortho cascade counts + 3 other
  // projections) = 2112.
  EXPECT_EQ(valid, 128 * 2114);
}

// The table is the one source: the manifest's features, their fields and the GLSL bit numbers
// all come from it.
TEST(VariantKey, FeatureTableDrivesTheManifestAndTheGlslBits) {
  const FeatureManifest m = manifest();
  ASSERT_EQ(m.features().size(), std::size(kFeatureTable));
  for (std::size_t i = 0; i < m.features().size(); ++i) {
    EXPECT_EQ(m.features()[i].name, kFeatureTable[i].name);
    EXPECT_EQ(m.features()[i].field.mask(), kFeatureTable[i].field().mask());
  }
  EXPECT_EQ(m.find("cascade_count")->field.mask(), VariantKey::kCascadeCountMinus1.mask());
  EXPECT_EQ(m.check(m.with(m.with(m.with(VariantKey(), *m.find("shadow"), 1),
                                  *m.find("shadow_projection"), 2),
                           *m.find("cascade_count"), 3)),
            "shadow_projection excludes cascade_count");
  int bits = 0;
  for (const auto& [name, value] : m.defines(VariantKey(), ShaderStage::vertex)) {
    if (name.rfind("BIT_", 0) != 0) continue;
    ++bits;
    if (name == "BIT_NORMAL_MAP") {
      EXPECT_EQ(value, std::to_string(VariantKey::kNormalMap.offset));
    }
    if (name == "BIT_REFLECTION_BOX") {
      EXPECT_EQ(value, std::to_string(VariantKey::kReflectionBox.offset));
    }
  }
  EXPECT_EQ(bits, 8);  // every material feature, in every stage
}

TEST(VariantKey, DefinesComeFromOneFunctionForBothKinds) {
  const FeatureManifest m = manifest();
  VariantKey k;
  k = m.with(k, *m.find("normal_map"), 1);
  k = m.with(k, *m.find("shadow"), 1);
  k = m.with(k, *m.find("shadow_filter"), 2);
  k = m.with(k, *m.find("cascade_count"), 4);
  const auto defs = m.defines(k, ShaderStage::fragment);
  auto value = [&](const std::string& name) {
    for (const auto& [n, v] : defs)
      if (n == name) return v;
    return std::string("missing");
  };
  EXPECT_EQ(value("MATERIAL_HAS_NORMAL_MAP"), "1");
  EXPECT_EQ(value("MATERIAL_HAS_EMISSIVE"), "0");
  EXPECT_EQ(value("VARIANT_HAS_SHADOW"), "1");
  EXPECT_EQ(value("VARIANT_SHADOW_FILTER"), "2");
  EXPECT_EQ(value("VARIANT_SHADOW_FILTER_PCF3X3"), "2");
  EXPECT_EQ(value("VARIANT_CASCADE_COUNT"), "4");
  EXPECT_EQ(m.describe(k), "normal_map shadow shadow_filter=pcf3x3 cascade_count=4");
  EXPECT_EQ(value("BIT_NORMAL_MAP"), "1");
  // Stages: normal_map is fragment-only.
  for (const auto& [n, v] : m.defines(k, ShaderStage::vertex)) EXPECT_NE(n, "MATERIAL_HAS_NORMAL_MAP");
}

TEST(VariantKey, InvalidCombinationsAreNamed) {
  const FeatureManifest m = manifest();
  VariantKey k;
  k = m.with(k, *m.find("reflection_cube"), 1);
  k = m.with(k, *m.find("reflection_sphere"), 1);
  EXPECT_NE(m.check(k).find("excludes"), std::string::npos) << m.check(k);
  VariantKey f = m.with(VariantKey(), *m.find("shadow_filter"), 1);
  EXPECT_NE(m.check(f).find("shadow_filter requires shadow"), std::string::npos) << m.check(f);
}

TEST(FeatureManifest, BadManifestsAreRejected) {
  auto bad = [](const std::string& text) { return FeatureManifest::load(temp("features.json", text)); };
  // Features are declared in C++ only.
  auto r1 = bad(R"({"features": [{"name": "sparkles", "kind": "material"}]})");
  ASSERT_FALSE(r1.ok());
  EXPECT_NE(r1.error().to_string().find("kFeatureTable"), std::string::npos) << r1.error().to_string();
  auto r2 = bad(R"({"parameters": [{"name": "glitter", "type": "float", "default": 0, "feature": "sparkles"}]})");
  ASSERT_FALSE(r2.ok());
  EXPECT_NE(r2.error().to_string().find("/parameters/0/feature"), std::string::npos) << r2.error().to_string();
  EXPECT_NE(r2.error().to_string().find("sparkles"), std::string::npos);
  auto r3 = bad("{ not json");
  ASSERT_FALSE(r3.ok());
  EXPECT_NE(r3.error().to_string().find("features.json"), std::string::npos);
  auto r4 = bad(R"({"textures": [{"name": "glow", "feature": "glowing"}]})");
  ASSERT_FALSE(r4.ok());
  EXPECT_NE(r4.error().to_string().find("glowing"), std::string::npos) << r4.error().to_string();
}

// common.glsl sizes the frame block's arrays with its own defines; they must match the
// renderer's FrameBlock limits (written twice: GLSL cannot include a C++ header).
TEST(ShaderConstants, CommonGlslMatchesTheRendererLimits) {
  std::ifstream in(kShaders / "common.glsl");
  ASSERT_TRUE(in) << "cannot open common.glsl";
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto define = [&](const std::string& name) {
    const std::string key = "#define " + name + " ";
    const auto at = text.find(key);
    return at == std::string::npos ? -1 : std::atoi(text.c_str() + at + key.size());
  };
  EXPECT_EQ(define("MAX_CASCADES"), kMaxCascades);
  EXPECT_EQ(define("MAX_EXTRA_SHADOWS"), kMaxShadowedLights - 1);
}

// The number of shadowed lights is a frame feature: a frame compiles the lookups of the lights
// it shades and no others (issue 13: dormant extra-light code cost a quarter of the frame).
TEST(FrameVariant, ShadowLightsCountsTheShadowedLightsTheFrameShades) {
  const FeatureManifest m = manifest();
  const Feature& lights = *m.find("shadow_lights");
  FrameInput frame;
  frame.lights.resize(4);
  EXPECT_EQ(m.value(lights, frame_variant(frame)), 1);  // no shadow: the field is off
  EXPECT_FALSE(frame_variant(frame).has(VariantKey::kShadowLightsMinus1));
  // Extra lights without a first shadowed light are not drawn.
  frame.extra_shadows.resize(1);
  frame.extra_shadows[0].light_index = 1;
  EXPECT_FALSE(frame_variant(frame).has(VariantKey::kShadow));
  EXPECT_FALSE(frame_variant(frame).has(VariantKey::kShadowLightsMinus1));

  frame.shadow.light_index = 0;
  frame.extra_shadows.clear();
  EXPECT_EQ(m.value(lights, frame_variant(frame)), 1);
  // Drawn: a directional light in range. Not drawn: a light index past the shaded lights, a
  // spot projection (extras are directional cascades).
  ShadowPass extra;
  extra.light_index = 1;
  frame.extra_shadows.push_back(extra);
  extra.light_index = 9;
  frame.extra_shadows.push_back(extra);
  extra.light_index = 2;
  extra.projection = ShadowProjection::perspective;
  frame.extra_shadows.push_back(extra);
  VariantKey k = frame_variant(frame);
  EXPECT_EQ(m.value(lights, k), 2);
  EXPECT_TRUE(k.valid());
  EXPECT_EQ(m.check(k), "");
  EXPECT_NE(m.describe(k).find("shadow_lights=2"), std::string::npos) << m.describe(k);
  // At most kMaxShadowedLights in all.
  extra.projection = ShadowProjection::ortho;
  for (int i = 0; i < 5; ++i) frame.extra_shadows.push_back(extra);
  k = frame_variant(frame);
  EXPECT_EQ(m.value(lights, k), kMaxShadowedLights);
  // The forward and points passes read it; the depth pass does not.
  EXPECT_EQ(k.filtered_for(Pass::shadow_points).get(VariantKey::kShadowLightsMinus1), 3u);
  EXPECT_EQ(k.filtered_for(Pass::depth).get(VariantKey::kShadowLightsMinus1), 0u);
  const auto defs = m.defines(k, ShaderStage::fragment);
  EXPECT_NE(std::find(defs.begin(), defs.end(), std::pair<std::string, std::string>(
                                                    "VARIANT_SHADOW_LIGHTS", "4")),
            defs.end());
  // Without a shadow the count is an invalid key, named by the manifest.
  const VariantKey orphan = VariantKey().set(VariantKey::kShadowLightsMinus1, 1);
  EXPECT_FALSE(orphan.valid());
  EXPECT_NE(m.check(orphan).find("shadow_lights requires shadow"), std::string::npos)
      << m.check(orphan);
}

struct BadMaterial {
  const char* name;
  const char* text;
  std::vector<const char*> expect;
};

TEST(MaterialFile, MalformedFilesGiveErrorsNamingFileAndKey) {
  const FeatureManifest m = manifest();
  const BadMaterial cases[] = {
      {"unknown_feature", R"({"features": ["sparkles"]})", {"/features/0", "sparkles", "normal_map"}},
      {"frame_feature", R"({"features": ["shadow"]})", {"/features/0", "not a material feature"}},
      {"contradiction", R"({"features": ["reflection_cube", "reflection_sphere"]})", {"/features/0", "exclude each other"}},
      {"wrong_type", R"({"parameters": {"roughness": "rough"}})", {"/parameters/roughness", "expected a number"}},
      {"out_of_range", R"({"parameters": {"metallic": 1.5}})", {"/parameters/metallic", "[0, 1]", "1.5"}},
      {"unknown_param", R"({"parameters": {"shininess": 3}})", {"/parameters/shininess", "roughness"}},
      {"param_needs_feature", R"({"parameters": {"normal_scale": 2}})", {"/parameters/normal_scale", "normal_map"}},
      {"texture_needs_feature", R"({"textures": {"normal": "n.png"}})", {"/textures/normal", "normal_map"}},
      {"feature_needs_texture", R"({"features": ["base_color_texture"]})", {"/textures", "base_color"}},
      {"missing_texture_file", R"({"features": ["normal_map"], "textures": {"normal": "nope.png"}})", {"/textures/normal", "nope.png"}},
      {"unknown_key", R"({"feature": []})", {"unknown key 'feature'", "features"}},
      {"vec_size", R"({"parameters": {"base_color": [1, 1, 1]}})", {"/parameters/base_color", "4 numbers"}},
      {"malformed", "{\"features\": [", {"line 1", "malformed JSON"}},
  };
  for (const auto& c : cases) {
    AssetStore assets;
    const fs::path file = temp(std::string(c.name) + ".json", c.text);
    auto r = load_material_file(file, m, assets);
    ASSERT_FALSE(r.ok()) << c.name;
    const std::string msg = r.error().to_string();
    EXPECT_NE(msg.find(c.name), std::string::npos) << c.name << ": file not named in " << msg;
    for (const char* e : c.expect) EXPECT_NE(msg.find(e), std::string::npos) << c.name << ": '" << e << "' not in " << msg;
  }
}

TEST(MaterialFile, ShippedMaterialsLoad) {
  const FeatureManifest m = manifest();
  int loaded = 0;
  for (const auto& f : fs::directory_iterator(fs::path(KASKAD_CONTENT_DIR) / "materials")) {
    if (f.path().extension() != ".json") continue;
    AssetStore assets;
    auto r = load_material_file(f.path(), m, assets);
    ASSERT_TRUE(r.ok()) << r.error().to_string();
    EXPECT_TRUE(VariantKey(r->features).valid());
    ++loaded;
  }
  EXPECT_GE(loaded, 4);
}

}  // namespace
}  // namespace kaskad::render
