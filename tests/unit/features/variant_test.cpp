// Variant keys, the feature manifest and material files: no GL needed.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <filesystem>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "components/shadow_technique.h"
#include "runtime/assets/material_file.h"
#include "runtime/features/feature_manifest.h"
#include "runtime/render/frame_uniforms.h"
#include "runtime/render/renderer.h"
#include "runtime/features/variant_key.h"
#include "tests/test_tmp.h"

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
  const fs::path dir = testing_util::test_tmp();
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary) << text;
  return dir / name;
}

// The rules of variant_key.h's header comment, written out independently of kFeatureTable.
bool documented_rules_hold(VariantKey k) {
  using V = VariantKey;
  const std::uint64_t used =
      V::kBaseColorTexture.mask() | V::kNormalMap.mask() | V::kAlphaMask.mask() |
      V::kEmissive.mask() | V::kReflectionCube.mask() | V::kReflectionSphere.mask() |
      V::kReceiveShadows.mask() | V::kReflectionBox.mask() | V::kShadow.mask() |
      V::kShadowFilter.mask() | V::kCascadeCountMinus1.mask() | V::kAovs.mask() |
      V::kDebugCascades.mask() | V::kCascadeSelection.mask() | V::kShadowProjection.mask() |
      V::kShadowLayered.mask() | V::kShadowLightsMinus1.mask() | V::kShadowTechnique.mask() |
      V::kShadowKernel.mask() | V::kToneMapping.mask() | V::kOcclusionTexture.mask() |
      V::kEmissiveTexture.mask() | V::kTextureTransform.mask() | V::kShadowPeel.mask() |
      V::kReflectionPbr.mask() | V::kEnvironment.mask() |
      V::kAlphaToCoverage.mask() | V::kMetallicRoughnessTexture.mask() | V::kShadowReuse.mask() |
      V::kAlphaBlend.mask() | V::kSkin.mask() | V::kMorph.mask();
  if (k.bits() & ~used) return false;
  if (k.get(V::kSkin) > 2) return false;             // none, 4 joints, 8 joints
  if (k.get(V::kToneMapping) > 2) return false;      // none, khr_pbr_neutral, aces
  if (k.get(V::kShadowFilter) > 2) return false;     // none, bilinear, pcf3x3
  // one per row of the technique table (components/shadow_technique.h)
  if (k.get(V::kShadowTechnique) >= kShadowTechniqueCount) return false;
  if (k.get(V::kShadowKernel) > 4) return false;     // 3x3, 5x5, 7x7, 9x9, poisson
  if (k.get(V::kShadowReuse) > 3) return false;      // off, store, load, reproject
  if (k.has(V::kReflectionCube) && k.has(V::kReflectionSphere)) return false;
  if (k.has(V::kReflectionBox) && !k.has(V::kReflectionCube)) return false;
  if (k.has(V::kReflectionPbr) && !k.has(V::kReflectionCube)) return false;
  if (k.has(V::kEmissiveTexture) && !k.has(V::kEmissive)) return false;
  if (k.has(V::kAlphaMask) && k.has(V::kAlphaBlend)) return false;
  const bool needs_shadow = k.has(V::kShadowFilter) || k.has(V::kCascadeCountMinus1) ||
                            k.has(V::kDebugCascades) || k.has(V::kCascadeSelection) ||
                            k.has(V::kShadowProjection) || k.has(V::kShadowLayered) ||
                            k.has(V::kShadowLightsMinus1) || k.has(V::kShadowTechnique) ||
                            k.has(V::kShadowKernel) || k.has(V::kShadowPeel) ||
                            k.has(V::kShadowReuse);
  if (needs_shadow && !k.has(V::kShadow)) return false;
  if (k.has(V::kShadowProjection) && k.has(V::kCascadeCountMinus1)) return false;
  return true;
}

TEST(VariantKey, EveryKeyFollowsTheDocumentedRules) {
  const FeatureManifest m = manifest();
  std::uint64_t material_used = 0, frame_used = 0, deform_used = 0;
  for (const auto& f : m.features())
    (f.kind == FeatureKind::material ? material_used
     : f.kind == FeatureKind::frame  ? frame_used
                                     : deform_used) |= f.field.mask();
  int disagree = 0;
  // valid() (kFeatureTable's rules) agrees with the rules written out above, the manifest names
  // a broken rule exactly when valid() is false, and a valid key filters to itself for the
  // forward pass (it reads everything, but alpha_to_coverage only with alpha_mask and
  // shadow_reuse only with receive_shadows and without alpha_blend) and to valid keys for the
  // others.
  auto check = [&](VariantKey k) {
    if ((k.valid() != documented_rules_hold(k) || k.valid() != m.check(k).empty()) &&
        disagree++ < 5)
      ADD_FAILURE() << "key 0x" << std::hex << k.bits() << ": valid() " << k.valid()
                    << ", documented rules " << documented_rules_hold(k) << ", manifest: '"
                    << m.check(k) << "' (" << m.describe(k) << ")";
    if (!k.valid()) return false;
    std::uint64_t forward = k.bits();
    if (!k.has(VariantKey::kAlphaMask)) forward &= ~VariantKey::kAlphaToCoverage.mask();
    if (!k.has(VariantKey::kReceiveShadows) || k.has(VariantKey::kAlphaBlend))
      forward &= ~VariantKey::kShadowReuse.mask();
    EXPECT_EQ(k.filtered_for(Pass::forward), VariantKey(forward));
    EXPECT_TRUE(k.filtered_for(Pass::depth).valid());
    EXPECT_TRUE(k.filtered_for(Pass::shadow_points).valid());
    EXPECT_TRUE(k.filtered_for(Pass::lom_occlusion).valid());
    EXPECT_TRUE(k.filtered_for(Pass::vsm_moments).valid());
    return true;
  };
  // No rule links a material feature to a frame feature, so every subset of the frame bits is
  // checked with a few material keys, and every subset of the material bits with a few frame
  // keys (every subset of both: 2^27 keys, too many since the soft-shadow features).
  const VariantKey some_materials[] = {
      VariantKey(), VariantKey().set(VariantKey::kReceiveShadows, 1).set(VariantKey::kAlphaMask, 1),
      VariantKey().set(VariantKey::kReflectionCube, 1).set(VariantKey::kReflectionBox, 1)};
  const VariantKey some_frames[] = {
      VariantKey(), VariantKey().set(VariantKey::kShadow, 1).set(VariantKey::kShadowFilter, 2),
      VariantKey()
          .set(VariantKey::kShadow, 1)
          .set(VariantKey::kShadowProjection, 3)
          .set(VariantKey::kShadowTechnique, 1)
          .set(VariantKey::kShadowKernel, 4)};
  // shadow_reuse's two bits are left out of the subsets (they would make four times as many)
  // and tried in each of their values on every valid frame key: its only rule is that it needs
  // shadow.
  const std::uint64_t reuse = VariantKey::kShadowReuse.mask();
  const std::uint64_t enumerated = frame_used & ~reuse;
  int valid_frames = 0, valid_materials = 0, valid_reuse = 0;
  for (std::uint64_t bits = 0;; bits = ((bits | ~enumerated) + 1) & enumerated) {
    int n = 0;
    for (VariantKey mat : some_materials) n += check(VariantKey(bits | mat.bits())) ? 1 : 0;
    EXPECT_TRUE(n == 0 || n == 3) << std::hex << bits;
    valid_frames += n > 0 ? 1 : 0;
    if (n > 0)
      for (std::uint32_t value = 1; value < 4; ++value)
        valid_reuse += check(VariantKey(bits | some_materials[1].bits())
                                 .set(VariantKey::kShadowReuse, value)) ? 1 : 0;
    if (bits == enumerated) break;
  }
  for (std::uint64_t bits = 0;; bits = ((bits | ~material_used) + 1) & material_used) {
    int n = 0;
    for (VariantKey frame : some_frames) n += check(VariantKey(bits | frame.bits())) ? 1 : 0;
    EXPECT_TRUE(n == 0 || n == 3) << std::hex << bits;
    valid_materials += n > 0 ? 1 : 0;
    if (bits == material_used) break;
  }
  // Deform keys (the deform pass's alone: no rule links them to the others): 3 skins x morph.
  int valid_deforms = 0;
  for (std::uint64_t bits = 0;; bits = ((bits | ~deform_used) + 1) & deform_used) {
    const VariantKey k(bits);
    if (check(k)) {
      ++valid_deforms;
      EXPECT_EQ(k.filtered_for(Pass::deform), k);
      EXPECT_EQ((k | some_frames[1]).filtered_for(Pass::deform), k);
    }
    if (bits == deform_used) break;
  }
  EXPECT_EQ(valid_deforms, 6);
  EXPECT_EQ(disagree, 0);
  // Material keys: 2^6 free bits x 3 of the 4 alpha_mask/alpha_blend combinations x 3 of the 4
  // emissive/emissive_texture combinations x 6 of the 16 reflection cube/sphere/box/pbr
  // combinations (none, sphere, cube with or without box and pbr) = 3456.
  // Frame keys: 2 without shadow (aovs), and with shadow 3 filters x 2 aovs x 2 debug x
  // 2 selection x 2 layered x 4 shadowed-light counts x (8 ortho cascade counts + 3 other
  // projections) x the techniques (6 today: pcf, pcss, backprojection, lom, vsm, evsm) x
  // 5 kernels x 2 peel = 126720; all of them x 3 tone mappings x 2 environments x
  // 2 alpha_to_coverage.
  const int shadowed = 3 * 2 * 2 * 2 * 2 * 4 * (8 + 3) * int(kShadowTechniqueCount) * 5 * 2;
  EXPECT_EQ(valid_materials, 3456);
  EXPECT_EQ(valid_frames, 2 * 2 * 3 * (2 + shadowed));
  // shadow_reuse store, load and reproject on every frame key with shadow.
  EXPECT_EQ(valid_reuse, 2 * 2 * 3 * 3 * shadowed);
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
  EXPECT_EQ(bits, 14);  // every material feature, in every stage
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
  // The technique's traits the lookup files switch on, from the technique table.
  EXPECT_EQ(value("TECHNIQUE_NEEDS_LIGHT_SIZE"), "0");
  EXPECT_EQ(value("TECHNIQUE_MOMENT_CHANNELS"), "0");
  const auto evsm = m.defines(m.with(k, *m.find("shadow_technique"), 5), ShaderStage::fragment);
  const auto pcss = m.defines(m.with(k, *m.find("shadow_technique"), 1), ShaderStage::fragment);
  EXPECT_NE(std::find(evsm.begin(), evsm.end(), std::pair<std::string, std::string>(
                                                    "TECHNIQUE_MOMENT_CHANNELS", "4")),
            evsm.end());
  EXPECT_NE(std::find(pcss.begin(), pcss.end(), std::pair<std::string, std::string>(
                                                    "TECHNIQUE_NEEDS_LIGHT_SIZE", "1")),
            pcss.end());
  // Stages: emissive is fragment-only; normal_map reaches the vertex stage too (its tangents).
  bool normal_map_in_vertex = false;
  for (const auto& [n, v] : m.defines(k, ShaderStage::vertex)) {
    EXPECT_NE(n, "MATERIAL_HAS_EMISSIVE");
    normal_map_in_vertex |= n == "MATERIAL_HAS_NORMAL_MAP" && v == "1";
  }
  EXPECT_TRUE(normal_map_in_vertex);
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

// The frame block's array sizes reach the shaders as defines made from components/limits.h;
// no shader defines them itself (one source).
TEST(ShaderConstants, LimitsAreDefinedFromTheOneCppDefinition) {
  const FeatureManifest m = manifest();
  for (const ShaderStage stage : {ShaderStage::vertex, ShaderStage::fragment}) {
    const auto defs = m.defines(VariantKey(), stage);
    auto value = [&](const std::string& name) {
      for (const auto& [key, v] : defs)
        if (key == name) return std::atoi(v.c_str());
      return -1;
    };
    EXPECT_EQ(value("MAX_LIGHTS"), kMaxLights);
    EXPECT_EQ(value("MAX_CASCADES"), kMaxCascades);
    EXPECT_EQ(value("MAX_SHADOW_VIEWS"), kMaxShadowedLights);
  }
  for (const auto& entry : std::filesystem::directory_iterator(kShaders)) {
    std::ifstream in(entry.path());
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(text.find("#define MAX_"), std::string::npos) << entry.path();
  }
}

// The number of shadow views is a frame feature: a frame compiles the lookups of the views it
// shades and no others (dormant extra-light code is not free: docs/design/shadow_cost.md).
TEST(FrameVariant, ShadowLightsCountsTheShadowViews) {
  const FeatureManifest m = manifest();
  const Feature& lights = *m.find("shadow_lights");
  FrameInput frame;
  frame.lights.resize(4);
  EXPECT_EQ(m.value(lights, frame_variant(frame)), 1);  // no shadow: the field is off
  EXPECT_FALSE(frame_variant(frame).has(VariantKey::kShadow));
  EXPECT_FALSE(frame_variant(frame).has(VariantKey::kShadowLightsMinus1));
  auto add_view = [&](int light) {
    ShadowView v;
    v.light_index = light;
    v.layer_count = 2;
    v.first_layer = frame.shadow_views.empty()
                        ? 0
                        : frame.shadow_views.back().first_layer + frame.shadow_views.back().layer_count;
    frame.shadow_views.push_back(v);
  };
  add_view(0);
  EXPECT_EQ(m.value(lights, frame_variant(frame)), 1);
  EXPECT_TRUE(frame_variant(frame).has(VariantKey::kShadow));
  add_view(2);
  VariantKey k = frame_variant(frame);
  EXPECT_EQ(m.value(lights, k), 2);
  EXPECT_TRUE(k.valid());
  EXPECT_EQ(m.check(k), "");
  EXPECT_NE(m.describe(k).find("shadow_lights=2"), std::string::npos) << m.describe(k);
  add_view(1);
  add_view(3);
  EXPECT_EQ(shadow_views_error(frame), "");
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

// Shadow views the renderer cannot draw as given are named, not drawn wrongly.
TEST(FrameInput, ShadowViewsErrorNamesTheBadView) {
  FrameInput frame;
  frame.lights.resize(3);
  ShadowView v;
  v.light_index = 0;
  v.layer_count = 4;
  frame.shadow_views = {v};
  EXPECT_EQ(shadow_views_error(frame), "");
  auto error_with = [&](auto&& change) {
    FrameInput f = frame;
    f.shadow_views.push_back(v);
    f.shadow_views[1].light_index = 1;
    f.shadow_views[1].first_layer = 4;
    change(f);
    return shadow_views_error(f);
  };
  EXPECT_EQ(error_with([](FrameInput&) {}), "");
  EXPECT_NE(error_with([](FrameInput& f) { f.shadow_views[1].light_index = 3; })
                .find("shadow view 1: light index 3 is not one of the 3 shaded lights"),
            std::string::npos);
  EXPECT_NE(error_with([](FrameInput& f) { f.shadow_views[1].first_layer = 5; })
                .find("shadow view 1: first layer 5, expected 4"),
            std::string::npos);
  EXPECT_NE(error_with([](FrameInput& f) { f.shadow_views[1].layer_count = 0; })
                .find("shadow view 1: 0 layers"),
            std::string::npos);
  EXPECT_NE(error_with([](FrameInput& f) {
              f.shadow_views[1].projection = ShadowProjection::perspective;
            }).find("only the first view may be a spot or point light's"),
            std::string::npos);
  EXPECT_NE(error_with([](FrameInput& f) { f.aov_shadow_view = 2; })
                .find("aov_shadow_view 2 is not one of the 2 shadow views"),
            std::string::npos);
  EXPECT_NE(error_with([](FrameInput& f) {
              for (int i = 0; i < 3; ++i) f.shadow_views.push_back(f.shadow_views[1]);
            }).find("5 shadow views; at most 4"),
            std::string::npos);
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

namespace kaskad::render {
namespace {

// pack_frame_block: each view's data in its slot, splits and texel sizes four per vec4, each
// light pointing at its view, exposure in its own field (a probe face's is 1).
TEST(FrameUniforms, PackPutsEveryViewAndLightInItsPlace) {
  FrameInput frame;
  frame.lights.resize(3);
  frame.lights[2].type = LightType::spot;
  frame.exposure = 2.5f;
  frame.shadow_settings.vsm_bleed_reduction = 0.3f;
  frame.shadow_settings.vsm_blur = 7;
  frame.height = 200;
  frame.camera.proj = glm::perspective(glm::radians(90.0f), 2.0f, 0.1f, 100.0f);
  ShadowView a;
  a.light_index = 2;
  a.layer_count = 1;
  a.projection = ShadowProjection::perspective;
  a.paraboloid_margin = 0.25f;
  ShadowView b;
  b.light_index = 0;
  b.first_layer = 1;
  b.layer_count = 8;
  b.normal_offset = 1.5f;
  b.blend_band = 0.2f;
  for (int i = 0; i <= 8; ++i) b.splits[std::size_t(i)] = float(i + 1);
  for (int i = 0; i < 8; ++i) {
    b.texel_size[std::size_t(i)] = 0.01f * float(i + 1);
    b.view_proj[std::size_t(i)] = glm::mat4(float(i + 1));
  }
  frame.shadow_views = {a, b};
  frame.aov_shadow_view = 1;
  ASSERT_EQ(shadow_views_error(frame), "");
  const FrameBlock fb = pack_frame_block(frame);
  EXPECT_EQ(fb.counts, glm::ivec4(3, 2, 1, 7));  // w: vsm_blur
  EXPECT_EQ(fb.frame_params.x, 2.5f);
  EXPECT_EQ(fb.frame_params.w, 0.3f);
  // Metres per pixel at 1 m of view depth: 2 tan(45 deg) / 200.
  EXPECT_FLOAT_EQ(fb.camera_pos.w, 0.01f);
  EXPECT_EQ(fb.light_info[0], glm::ivec4(int(LightType::directional), 1, 0, 0));
  EXPECT_EQ(fb.light_info[1].y, -1);
  EXPECT_EQ(fb.light_info[2], glm::ivec4(int(LightType::spot), 0, 0, 0));
  EXPECT_EQ(fb.shadow_views[0].info, glm::ivec4(2, 0, 1, 0));
  EXPECT_EQ(fb.shadow_views[0].params.z, 0.25f);
  EXPECT_EQ(fb.shadow_views[1].info, glm::ivec4(0, 1, 8, 0));
  EXPECT_EQ(fb.shadow_views[1].params, glm::vec4(1.5f, 0.2f, 0.0f, 0.0f));
  EXPECT_EQ(fb.shadow_views[1].splits[0], glm::vec4(1, 2, 3, 4));
  EXPECT_EQ(fb.shadow_views[1].splits[2].x, 9.0f);
  EXPECT_EQ(fb.shadow_views[1].texel[1].w, 0.08f);
  EXPECT_EQ(fb.shadow_views[1].view_proj[7], glm::mat4(8.0f));
  ProbeJob job;
  job.center = {1, 2, 3};
  job.resolution = 64;
  job.view_proj[4] = glm::mat4(3.0f);
  const FrameBlock face = probe_face_block(fb, job, 4);
  EXPECT_EQ(face.view_proj, glm::mat4(3.0f));
  // A 90-degree face of 64 texels: 2 / 64 metres per pixel per metre of distance, negated.
  EXPECT_EQ(face.camera_pos, glm::vec4(1, 2, 3, -2.0f / 64.0f));
  EXPECT_EQ(face.frame_params.x, 1.0f);
  EXPECT_EQ(face.view, fb.view);  // sphere maps are made for the main view
}

}  // namespace
}  // namespace kaskad::render
