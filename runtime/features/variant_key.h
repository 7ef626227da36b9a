// The variant key: which compile-time features a program has. A 64-bit value with named bits
// and small integer fields (Filament's Variant, Bevy's MeshPipelineKey), split into
//   material features  (bits 0-15)  what a material uses      -> MATERIAL_* defines
//   frame features     (bits 16-47) what the frame needs      -> VARIANT_* defines
//   deform features    (bits 48-55) what the deform pass does  -> DEFORM_* defines
// (bits 56-63 stay free: the shader library keeps the pass there). 32 bits ran out when the
// soft-shadow techniques and PCF kernels arrived.
//
// kFeatureTable below is the one place a feature is declared: its name, define, stages, bit
// offset, value range or value names, and what it requires or excludes. Everything else is
// derived from it: VariantKey's field constants, valid(), FeatureManifest (defines, rule
// messages, `kaskad variants`), the GLSL BIT_* numbers of the material features (defines from
// FeatureManifest::defines(), read by features.glsl's ENABLED()) and material files' checks.
// Adding a feature: one row here, its `#if` block in the shaders, and where its value comes from.
//
// Valid combinations (valid(), from the table's requires/excludes and ranges; a feature is "on"
// when its stored field is non-zero):
//   reflection_cube and reflection_sphere exclude each other
//   reflection_box needs reflection_cube
//   shadow_filter != none and cascade_count != 1 need shadow
//   debug_cascades, cascade_selection and shadow_projection need shadow
//   shadow_projection != ortho has cascade_count 1 (cascades are directional only)
//   shadow_layered needs shadow; the depth pass keeps it (its vertex shader picks the layer)
//   shadow_lights != 1 needs shadow (the lookups of lights that do not exist are not compiled)
//   shadow_technique != pcf, shadow_kernel != k3x3 and shadow_peel need shadow
//   emissive_texture needs emissive
//   reflection_pbr needs reflection_cube
//   alpha_mask and alpha_blend exclude each other
//   alpha_to_coverage is kept by the forward pass only with alpha_mask (filtered_for())
//   shadow_reuse needs shadow; the forward pass keeps it only with receive_shadows and without
//   alpha_blend (a blended pixel shows two surfaces, the cache holds one value per pixel)
// filtered_for(Pass::depth) keeps only what the depth pass uses (alpha_mask with its
// texture_transform, peeling, and the projection when it is dual_paraboloid: its vertex shader
// differs), so every material shares one or two shadow programs; alpha_blend becomes alpha_mask
// there (the shadow rule of blended casters, docs/guide/materials.md "Transparency").
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <string>
#include <string_view>

#include "components/shadow_settings.h"
#include "components/tone_mapping.h"

namespace kaskad::render {

/// forward: colour + AOVs; depth: shadow maps (and LOM's depth peels); shadow_points: the shadow
/// lookup evaluated at given world points (Renderer::shadow_at_points(), the stability metrics);
/// lom_occlusion: the occlusion factors of S1's layered occlusion map (LomPass); vsm_moments:
/// the moments of variance shadow maps and their blur (MomentsPass).
enum class Pass : std::uint8_t {
  forward = 0,
  depth = 1,
  shadow_points = 2,
  lom_occlusion = 3,
  vsm_moments = 4,
  deform = 5
};

constexpr const char* pass_name(Pass pass) {
  switch (pass) {
    case Pass::depth: return "depth";
    case Pass::shadow_points: return "points";
    case Pass::lom_occlusion: return "lom";
    case Pass::vsm_moments: return "moments";
    case Pass::deform: return "deform";
    case Pass::forward: break;
  }
  return "forward";
}

/// material: from the material (MATERIAL_* defines); frame: from frame settings (VARIANT_*);
/// deform: from a deformed mesh (DEFORM_*; the deform pass's compute programs only).
enum class FeatureKind : std::uint8_t { material, frame, deform };
enum class ShaderStage : std::uint8_t { vertex = 1, fragment = 2, compute = 4 };

/// Where a feature's value lives in the key: bit offset and width.
struct KeyField {
  std::uint8_t offset;
  std::uint8_t width;
  constexpr std::uint64_t mask() const { return ((std::uint64_t(1) << width) - 1u) << offset; }
  constexpr std::uint32_t max() const { return (1u << width) - 1u; }
};

/// The value names of an enumerated feature that stores enum E: the enum's own names
/// (enum_names(), the ones files use), so that the two cannot disagree.
template <class E>
consteval std::array<std::string_view, 8> values_of() {
  constexpr auto names = enum_names(E{});
  static_assert(names.size() <= 8, "an enumerated feature has at most 8 values");
  std::array<std::string_view, 8> out{};
  for (std::size_t i = 0; i < names.size(); ++i) out[i] = names[i];
  return out;
}

/// One shader feature (a row of kFeatureTable).
struct FeatureSpec {
  std::string_view name;
  FeatureKind kind = FeatureKind::material;
  std::string_view define;  ///< MATERIAL_* for material features, VARIANT_* for frame ones
  std::uint8_t stages = 0;  ///< ShaderStage bits: the stages that get the define
  std::uint8_t offset = 0;  ///< first bit in the key; the width follows from the value range
  /// Integer features: the value range (a switch: 0..1). Enumerated features: `values` names
  /// the values 0..n-1 and `max` is ignored. The key stores value - min.
  int min = 0, max = 1;
  std::array<std::string_view, 8> values{};
  std::array<std::string_view, 2> requires_{};  ///< features that must be on when this one is
  std::array<std::string_view, 2> excludes{};   ///< features that must be off when this one is

  constexpr int value_count() const {
    int n = 0;
    while (n < int(values.size()) && !values[std::size_t(n)].empty()) ++n;
    return n;
  }
  constexpr int value_max() const { return value_count() > 0 ? value_count() - 1 : max; }
  constexpr KeyField field() const {
    return {offset, std::uint8_t(std::bit_width(unsigned(value_max() - min)))};
  }
};

inline constexpr std::uint8_t kVertexStage = std::uint8_t(ShaderStage::vertex);
inline constexpr std::uint8_t kFragmentStage = std::uint8_t(ShaderStage::fragment);
inline constexpr std::uint8_t kComputeStage = std::uint8_t(ShaderStage::compute);

/// Every shader feature, in the order defines and descriptions list them.
inline constexpr FeatureSpec kFeatureTable[] = {
    // Material features (bits 0-15).
    {.name = "base_color_texture", .define = "MATERIAL_HAS_BASE_COLOR_TEXTURE",
     .stages = kFragmentStage, .offset = 0},
    // The vertex stage passes the tangent frame on (ATTR_TANGENT).
    {.name = "normal_map", .define = "MATERIAL_HAS_NORMAL_MAP",
     .stages = kVertexStage | kFragmentStage, .offset = 1},
    {.name = "alpha_mask", .define = "MATERIAL_HAS_ALPHA_MASK",
     .stages = kVertexStage | kFragmentStage, .offset = 2, .excludes = {"alpha_blend"}},
    {.name = "emissive", .define = "MATERIAL_HAS_EMISSIVE", .stages = kFragmentStage, .offset = 3},
    {.name = "reflection_cube", .define = "MATERIAL_HAS_REFLECTION_CUBE", .stages = kFragmentStage,
     .offset = 4, .excludes = {"reflection_sphere"}},
    {.name = "reflection_sphere", .define = "MATERIAL_HAS_REFLECTION_SPHERE",
     .stages = kFragmentStage, .offset = 5, .excludes = {"reflection_cube"}},
    {.name = "reflection_box", .define = "MATERIAL_HAS_REFLECTION_BOX", .stages = kFragmentStage,
     .offset = 7, .requires_ = {"reflection_cube"}},
    {.name = "receive_shadows", .define = "MATERIAL_RECEIVES_SHADOWS", .stages = kFragmentStage,
     .offset = 6},
    // glTF occlusionTexture (R channel, strength): scales the ambient (indirect) light only.
    {.name = "occlusion_texture", .define = "MATERIAL_HAS_OCCLUSION_TEXTURE",
     .stages = kFragmentStage, .offset = 8},
    // glTF emissiveTexture: multiplies the emissive factor, so it needs `emissive`.
    {.name = "emissive_texture", .define = "MATERIAL_HAS_EMISSIVE_TEXTURE",
     .stages = kFragmentStage, .offset = 9, .requires_ = {"emissive"}},
    // KHR_texture_transform and TEXCOORD_1: each texture slot's uvs are its own uv set through
    // its own offset, rotation and scale (Material::*_transform); the vertex stage passes the
    // second set on. The depth pass keeps it with alpha_mask (cut-outs).
    {.name = "texture_transform", .define = "MATERIAL_HAS_TEXTURE_TRANSFORM",
     .stages = kVertexStage | kFragmentStage, .offset = 10},
    // glTF metallicRoughnessTexture (linear; B metallic, G roughness): multiplies the factors.
    {.name = "metallic_roughness_texture", .define = "MATERIAL_HAS_METALLIC_ROUGHNESS_TEXTURE",
     .stages = kFragmentStage, .offset = 11},
    // Material::reflection_model pbr: the reflector's probe lights the glTF BRDF (its SH and
    // prefiltered cube, components/ibl.h) instead of S3's I + k_s p_r C_t. Set with the cube.
    {.name = "reflection_pbr", .define = "MATERIAL_HAS_REFLECTION_PBR", .stages = kFragmentStage,
     .offset = 12, .requires_ = {"reflection_cube"}},
    // glTF alphaMode BLEND (Material::alpha_mode): the draw is drawn in the forward pass's
    // transparent phase, after the opaque draws, back to front, blended over what is behind.
    // The colour output is premultiplied: (tone-mapped colour x alpha, alpha), blended with
    // (GL_ONE, GL_ONE_MINUS_SRC_ALPHA), i.e. the over operator glTF asks for. The depth pass sees
    // it as alpha_mask (filtered_for()): a blended caster casts where alpha >= alpha_cutoff.
    {.name = "alpha_blend", .define = "MATERIAL_HAS_ALPHA_BLEND",
     .stages = kFragmentStage, .offset = 13, .excludes = {"alpha_mask"}},
    // Frame features (bits 16-31).
    {.name = "shadow", .kind = FeatureKind::frame, .define = "VARIANT_HAS_SHADOW",
     .stages = kFragmentStage, .offset = 16},
    {.name = "shadow_filter", .kind = FeatureKind::frame, .define = "VARIANT_SHADOW_FILTER",
     .stages = kFragmentStage, .offset = 17, .values = values_of<ShadowFilter>(),
     .requires_ = {"shadow"}},
    {.name = "cascade_count", .kind = FeatureKind::frame, .define = "VARIANT_CASCADE_COUNT",
     .stages = kVertexStage | kFragmentStage, .offset = 19, .min = 1, .max = 8,
     .requires_ = {"shadow"}},
    {.name = "aovs", .kind = FeatureKind::frame, .define = "VARIANT_HAS_AOVS",
     .stages = kFragmentStage, .offset = 22},
    {.name = "cascade_selection", .kind = FeatureKind::frame, .define = "VARIANT_CASCADE_SELECTION",
     .stages = kFragmentStage, .offset = 24, .values = values_of<CascadeSelection>(),
     .requires_ = {"shadow"}},
    {.name = "shadow_projection", .kind = FeatureKind::frame, .define = "VARIANT_SHADOW_PROJECTION",
     .stages = kVertexStage | kFragmentStage, .offset = 25,
     .values = values_of<ShadowProjection>(), .requires_ = {"shadow"},
     .excludes = {"cascade_count"}},
    {.name = "shadow_layered", .kind = FeatureKind::frame, .define = "VARIANT_SHADOW_LAYERED",
     .stages = kVertexStage, .offset = 27, .requires_ = {"shadow"}},
    {.name = "debug_cascades", .kind = FeatureKind::frame, .define = "VARIANT_DEBUG_CASCADES",
     .stages = kFragmentStage, .offset = 23, .requires_ = {"shadow"}},
    // The count of shadowed lights the frame shades (the first plus further directional ones):
    // loops over them get a compile-time bound, so lights that do not exist cost nothing.
    {.name = "shadow_lights", .kind = FeatureKind::frame, .define = "VARIANT_SHADOW_LIGHTS",
     .stages = kFragmentStage, .offset = 28, .min = 1, .max = 4, .requires_ = {"shadow"}},
    // Soft shadows, per frame like shadow_filter (the first shadowed light's
    // ShadowSettings::technique). Bits 32-35: room for up to 16 techniques.
    {.name = "shadow_technique", .kind = FeatureKind::frame, .define = "VARIANT_SHADOW_TECHNIQUE",
     .stages = kFragmentStage, .offset = 32,
     .values = values_of<ShadowTechnique>(), .requires_ = {"shadow"}},
    // The depth pass peeling layer j > 0 of S1's layered depth map (LomPass): fragments at or in
    // front of layer j - 1 are discarded, and each writes its depth, signed by whether its draw
    // casts shadows.
    {.name = "shadow_peel", .kind = FeatureKind::frame, .define = "VARIANT_SHADOW_PEEL",
     .stages = kVertexStage | kFragmentStage, .offset = 30, .requires_ = {"shadow"}},
    // The PCF footprint of shadow_filter pcf3x3 (ShadowSettings::pcf_kernel): N x N boxes of
    // nearest compares, or a rotated Poisson-like disc of ShadowSettings::pcf_taps taps. Its
    // value names (the defines' suffixes) are the shader's, "3x3" where files say 3; the count is
    // tied to the enum below.
    {.name = "shadow_kernel", .kind = FeatureKind::frame, .define = "VARIANT_SHADOW_KERNEL",
     .stages = kFragmentStage, .offset = 36,
     .values = {"3x3", "5x5", "7x7", "9x9", "poisson"}, .requires_ = {"shadow"}},
    // render.tone_mapping (components/tone_mapping.h): the curve the colour output goes through.
    {.name = "tone_mapping", .kind = FeatureKind::frame, .define = "VARIANT_TONE_MAPPING",
     .stages = kFragmentStage, .offset = 40, .values = values_of<ToneMapping>()},
    // render.msaa > 1: the multisampled colour pass. An alpha-masked draw writes its coverage
    // (alpha sharpened around the cutoff) instead of discarding, and GL_SAMPLE_ALPHA_TO_COVERAGE
    // turns it into samples. Only alpha-masked programs keep it (filtered_for()), so the others
    // are shared with the single-sample pass.
    {.name = "alpha_to_coverage", .kind = FeatureKind::frame, .define = "VARIANT_ALPHA_TO_COVERAGE",
     .stages = kFragmentStage, .offset = 42},
    // Where light from the surroundings comes from (components/ibl.h): the uniform ambient
    // radiance, or render.environment's SH and prefiltered cube.
    {.name = "environment", .kind = FeatureKind::frame, .define = "VARIANT_ENVIRONMENT",
     .stages = kFragmentStage, .offset = 43, .values = {"uniform", "map"}},
    // render.visibility_cache: the main view's single-sample colour pass stores each pixel's
    // shadow visibility (one float per shadow view, and its distance from the camera); a frame
    // whose visibility inputs are those of the frame before loads it instead of looking the
    // shadow maps up, and a frame whose camera alone moved reprojects it, looking up only the
    // pixels it cannot reuse (Renderer). Only shadow-receiving programs keep it (filtered_for()).
    {.name = "shadow_reuse", .kind = FeatureKind::frame, .define = "VARIANT_SHADOW_REUSE",
     .stages = kFragmentStage, .offset = 44, .values = {"off", "store", "load", "reproject"},
     .requires_ = {"shadow"}},
    // Deform features (bits 48-55): how the deform pass poses a mesh (runtime/assets/
    // mesh_pose.h): skinned by 4 or 8 joints a vertex (glTF JOINTS_0, JOINTS_1), and morphed.
    {.name = "skin", .kind = FeatureKind::deform, .define = "DEFORM_SKIN",
     .stages = kComputeStage, .offset = 48, .values = {"none", "joints4", "joints8"}},
    {.name = "morph", .kind = FeatureKind::deform, .define = "DEFORM_MORPH",
     .stages = kComputeStage, .offset = 50},
};
inline constexpr int kFeatureCount = int(std::size(kFeatureTable));

/// Index of a feature in kFeatureTable; -1 when there is none.
constexpr int feature_index(std::string_view name) {
  for (int i = 0; i < kFeatureCount; ++i)
    if (kFeatureTable[i].name == name) return i;
  return -1;
}

// The kernel's value names are the shader's own; their count must still be the enum's.
static_assert(kFeatureTable[feature_index("shadow_kernel")].value_count() ==
              int(enum_names(PcfKernel{}).size()));

/// A feature's key field by name; a name not in the table does not compile.
consteval KeyField feature_field(std::string_view name) {
  const int i = feature_index(name);
  if (i < 0) throw "feature_field: no such feature in kFeatureTable";
  return kFeatureTable[i].field();
}

/// The first rule a key breaks (valid() and FeatureManifest::check() both read this).
struct BrokenRule {
  enum Kind : std::uint8_t { none, unused_bits, range, requires_, excludes } kind = none;
  int feature = -1;  ///< index into kFeatureTable
  int other = -1;    ///< requires_/excludes: the other feature's index
};

namespace feature_detail {
// The table compiled into masks once, so valid() costs a few dozen bit operations.
struct Rule {
  std::uint64_t mask = 0;
  std::uint8_t offset = 0;
  std::uint32_t max_stored = 0;  ///< value_max - min
  std::array<int, 2> requires_{-1, -1};
  std::array<int, 2> excludes{-1, -1};
};
consteval std::array<Rule, kFeatureCount> make_rules() {
  std::array<Rule, kFeatureCount> rules{};
  std::uint64_t taken = 0;
  for (int i = 0; i < kFeatureCount; ++i) {
    const FeatureSpec& f = kFeatureTable[i];
    Rule& r = rules[std::size_t(i)];
    const KeyField field = f.field();
    // Checks on the table itself: a bad row is a compile error here.
    if (f.name.empty() || f.define.empty() || f.stages == 0) throw "feature without name, define or stage";
    if (feature_index(f.name) != i) throw "duplicate feature name";
    if (f.value_max() < f.min || field.width == 0) throw "empty value range";
    if (unsigned(field.offset) + field.width > 56u) throw "field past bit 55";
    if (taken & field.mask()) throw "features overlap in the key";
    const std::uint64_t home = f.kind == FeatureKind::material ? 0x000000000000ffffu
                               : f.kind == FeatureKind::frame  ? 0x0000ffffffff0000u
                                                               : 0x00ff000000000000u;
    if (field.mask() & ~home)
      throw "material features live in bits 0-15, frame features in 16-47, deform ones in 48-55";
    const std::string_view prefix = f.kind == FeatureKind::material ? "MATERIAL_"
                                    : f.kind == FeatureKind::frame  ? "VARIANT_"
                                                                    : "DEFORM_";
    if (!f.define.starts_with(prefix))
      throw "defines start with MATERIAL_, VARIANT_ or DEFORM_ as their feature's kind";
    taken |= field.mask();
    r.mask = field.mask();
    r.offset = field.offset;
    r.max_stored = std::uint32_t(f.value_max() - f.min);
    for (std::size_t k = 0; k < 2; ++k) {
      if (!f.requires_[k].empty()) {
        r.requires_[k] = feature_index(f.requires_[k]);
        if (r.requires_[k] < 0) throw "requires an unknown feature";
      }
      if (!f.excludes[k].empty()) {
        r.excludes[k] = feature_index(f.excludes[k]);
        if (r.excludes[k] < 0) throw "excludes an unknown feature";
      }
    }
  }
  return rules;
}
inline constexpr std::array<Rule, kFeatureCount> kRules = make_rules();
consteval std::uint64_t used_bits() {
  std::uint64_t used = 0;
  for (const Rule& r : kRules) used |= r.mask;
  return used;
}
}  // namespace feature_detail

class VariantKey {
 public:
  using Field = KeyField;
  // Named fields, looked up in kFeatureTable at compile time.
  // Material features.
  static constexpr Field kBaseColorTexture = feature_field("base_color_texture");
  static constexpr Field kNormalMap = feature_field("normal_map");
  static constexpr Field kAlphaMask = feature_field("alpha_mask");
  static constexpr Field kEmissive = feature_field("emissive");
  static constexpr Field kReflectionCube = feature_field("reflection_cube");
  static constexpr Field kReflectionSphere = feature_field("reflection_sphere");
  static constexpr Field kReceiveShadows = feature_field("receive_shadows");
  static constexpr Field kReflectionBox = feature_field("reflection_box");
  static constexpr Field kOcclusionTexture = feature_field("occlusion_texture");
  static constexpr Field kEmissiveTexture = feature_field("emissive_texture");
  static constexpr Field kTextureTransform = feature_field("texture_transform");
  static constexpr Field kMetallicRoughnessTexture = feature_field("metallic_roughness_texture");
  static constexpr Field kReflectionPbr = feature_field("reflection_pbr");
  static constexpr Field kAlphaBlend = feature_field("alpha_blend");
  static constexpr std::uint64_t kMaterialMask = 0x0000ffffu;
  // Frame features.
  static constexpr Field kShadow = feature_field("shadow");
  static constexpr Field kShadowFilter = feature_field("shadow_filter");  ///< 0 none, 1 bilinear, 2 pcf3x3
  /// cascade count - 1 (1..8 cascades)
  static constexpr Field kCascadeCountMinus1 = feature_field("cascade_count");
  static constexpr Field kAovs = feature_field("aovs");
  static constexpr Field kDebugCascades = feature_field("debug_cascades");
  static constexpr Field kCascadeSelection = feature_field("cascade_selection");  ///< 0 depth (S0's D), 1 map bounds
  /// ShadowProjection: 0 ortho, 1 perspective, 2 cube, 3 dual_paraboloid.
  static constexpr Field kShadowProjection = feature_field("shadow_projection");
  static constexpr std::uint32_t kProjectionDualParaboloid = 3;
  static constexpr Field kShadowLayered = feature_field("shadow_layered");  ///< depth pass: all layers in one pass
  /// Shadowed lights - 1 (1..4): the first plus the further directional ones the frame has.
  /// A count, not a switch, so loops over shadowed lights have a compile-time bound and a light
  /// that does not exist costs nothing (llvmpipe runs a zero-trip loop's body once, masked).
  static constexpr Field kShadowLightsMinus1 = feature_field("shadow_lights");
  /// ShadowTechnique: 0 pcf, 1 pcss, 2 backprojection, 3 lom, 4 vsm, 5 evsm.
  static constexpr Field kShadowTechnique = feature_field("shadow_technique");
  /// Depth pass: peel a layer of S1's layered depth map.
  static constexpr Field kShadowPeel = feature_field("shadow_peel");
  /// PcfKernel: 0 3x3, 1 5x5, 2 7x7, 3 9x9, 4 poisson.
  static constexpr Field kShadowKernel = feature_field("shadow_kernel");
  /// ToneMapping: 0 none, 1 khr_pbr_neutral, 2 aces.
  static constexpr Field kToneMapping = feature_field("tone_mapping");
  /// 0 uniform (the ambient radiance), 1 map (render.environment).
  static constexpr Field kEnvironment = feature_field("environment");
  /// The multisampled colour pass's alpha-masked draws: coverage from alpha (render.msaa > 1).
  static constexpr Field kAlphaToCoverage = feature_field("alpha_to_coverage");
  /// The main view's cached shadow visibility: 0 off, 1 store (look up and store), 2 load.
  static constexpr Field kShadowReuse = feature_field("shadow_reuse");
  static constexpr std::uint32_t kReuseStore = 1, kReuseLoad = 2, kReuseReproject = 3;
  static constexpr std::uint64_t kFrameMask = 0x0000ffffffff0000u;
  // Deform features.
  /// 0 none, 1 four joints a vertex, 2 eight.
  static constexpr Field kSkin = feature_field("skin");
  static constexpr Field kMorph = feature_field("morph");
  static constexpr std::uint64_t kDeformMask = 0x00ff000000000000u;

  constexpr VariantKey() = default;
  constexpr explicit VariantKey(std::uint64_t bits) : bits_(bits) {}

  constexpr std::uint64_t bits() const { return bits_; }
  constexpr std::uint32_t get(Field f) const { return std::uint32_t((bits_ & f.mask()) >> f.offset); }
  constexpr VariantKey& set(Field f, std::uint32_t value) {
    bits_ = (bits_ & ~f.mask()) | ((std::uint64_t(value) << f.offset) & f.mask());
    return *this;
  }
  constexpr bool has(Field f) const { return get(f) != 0; }

  constexpr VariantKey material() const { return VariantKey(bits_ & kMaterialMask); }
  constexpr VariantKey frame() const { return VariantKey(bits_ & kFrameMask); }
  constexpr VariantKey operator|(VariantKey o) const { return VariantKey(bits_ | o.bits_); }
  constexpr bool operator==(const VariantKey&) const = default;
  constexpr auto operator<=>(const VariantKey&) const = default;

  /// The first rule of kFeatureTable this key breaks (unused bits set, a value out of its
  /// range, a requires or excludes rule), or kind none.
  constexpr BrokenRule broken_rule() const {
    using feature_detail::kRules;
    if (bits_ & ~feature_detail::used_bits()) return {BrokenRule::unused_bits};
    for (int i = 0; i < kFeatureCount; ++i) {
      const feature_detail::Rule& r = kRules[std::size_t(i)];
      const std::uint64_t stored = (bits_ & r.mask) >> r.offset;
      if (stored > r.max_stored) return {BrokenRule::range, i};
      if (stored == 0) continue;
      for (int j : r.requires_)
        if (j >= 0 && !(bits_ & kRules[std::size_t(j)].mask)) return {BrokenRule::requires_, i, j};
      for (int j : r.excludes)
        if (j >= 0 && (bits_ & kRules[std::size_t(j)].mask)) return {BrokenRule::excludes, i, j};
    }
    return {};
  }
  /// The combination rules in the header comment. Unused bits must be zero.
  constexpr bool valid() const { return broken_rule().kind == BrokenRule::none; }

  /// The part of the key a pass's shaders read. The depth pass only needs alpha masking (and
  /// peeling; a blended draw is alpha-masked there); the shadow-points, LOM occlusion and VSM moments passes only the shadow lookup's
  /// frame features (a receiver, without AOVs or the debug tint); the forward pass needs
  /// everything but alpha_to_coverage on draws without alpha_mask (it changes nothing there).
  constexpr VariantKey filtered_for(Pass pass) const {
    if (pass == Pass::deform) return VariantKey(bits_ & kDeformMask);
    if (pass == Pass::depth) {
      const std::uint64_t projection = get(kShadowProjection) == kProjectionDualParaboloid
                                           ? kShadowProjection.mask() | kShadow.mask()
                                           : 0u;
      const std::uint64_t layered =
          has(kShadowLayered) ? kShadowLayered.mask() | kShadow.mask() : 0u;
      const std::uint64_t peel = has(kShadowPeel) ? kShadowPeel.mask() | kShadow.mask() : 0u;
      // Blended casters cast as cut-outs at alpha_cutoff (the rule the reference follows too).
      const bool cutout = has(kAlphaMask) || has(kAlphaBlend);
      // A cut-out reads the base colour texture through its transform.
      const std::uint64_t transform = cutout ? kTextureTransform.mask() : 0u;
      return VariantKey((bits_ & (projection | layered | peel | transform)) |
                        (cutout ? kAlphaMask.mask() : 0u));
    }
    if (pass == Pass::shadow_points || pass == Pass::lom_occlusion || pass == Pass::vsm_moments)
      return VariantKey((bits_ & kFrameMask & ~kAovs.mask() & ~kDebugCascades.mask() &
                         ~kShadowLayered.mask() & ~kToneMapping.mask() & ~kShadowPeel.mask() &
                         ~kEnvironment.mask() & ~kAlphaToCoverage.mask() &
                         ~kShadowReuse.mask()) |
                        kReceiveShadows.mask());
    // Programs without a shadow lookup have no visibility to store or load; blended ones are
    // never the pixel's one surface.
    const std::uint64_t reuse =
        has(kReceiveShadows) && !has(kAlphaBlend) ? 0u : kShadowReuse.mask();
    if (!has(kAlphaMask)) return VariantKey(bits_ & ~kAlphaToCoverage.mask() & ~reuse);
    return VariantKey(bits_ & ~reuse);
  }

 private:
  std::uint64_t bits_ = 0;
};

static_assert(VariantKey().valid());
static_assert(!VariantKey().set(VariantKey::kReflectionCube, 1).set(VariantKey::kReflectionSphere, 1).valid());
static_assert(!VariantKey().set(VariantKey::kShadowFilter, 2).valid());
static_assert(VariantKey().set(VariantKey::kShadow, 1).set(VariantKey::kShadowFilter, 2).valid());
static_assert(!VariantKey().set(VariantKey::kReflectionBox, 1).valid());
static_assert(VariantKey().set(VariantKey::kReflectionBox, 1).set(VariantKey::kReflectionCube, 1).valid());
static_assert(VariantKey().set(VariantKey::kNormalMap, 1).filtered_for(Pass::depth) == VariantKey());
static_assert(!VariantKey().set(VariantKey::kEmissiveTexture, 1).valid());
static_assert(VariantKey().set(VariantKey::kTextureTransform, 1).filtered_for(Pass::depth) ==
              VariantKey());
static_assert(VariantKey().set(VariantKey::kTextureTransform, 1).set(VariantKey::kAlphaMask, 1)
                  .filtered_for(Pass::depth) ==
              VariantKey().set(VariantKey::kTextureTransform, 1).set(VariantKey::kAlphaMask, 1));
static_assert(!VariantKey().set(VariantKey::kAlphaMask, 1).set(VariantKey::kAlphaBlend, 1).valid());
static_assert(VariantKey().set(VariantKey::kAlphaBlend, 1).filtered_for(Pass::depth) ==
              VariantKey().set(VariantKey::kAlphaMask, 1));
static_assert(!VariantKey()
                   .set(VariantKey::kAlphaBlend, 1)
                   .set(VariantKey::kReceiveShadows, 1)
                   .set(VariantKey::kShadow, 1)
                   .set(VariantKey::kShadowReuse, VariantKey::kReuseStore)
                   .filtered_for(Pass::forward)
                   .has(VariantKey::kShadowReuse));
static_assert(!VariantKey().set(VariantKey::kShadowProjection, 1).valid());
static_assert(!VariantKey().set(VariantKey::kShadowLightsMinus1, 1).valid());
static_assert(VariantKey()
                  .set(VariantKey::kShadow, 1)
                  .set(VariantKey::kShadowLightsMinus1, 3)
                  .filtered_for(Pass::depth) == VariantKey());
static_assert(
    VariantKey().set(VariantKey::kShadow, 1).set(VariantKey::kShadowProjection, 2).valid());
static_assert(!VariantKey()
                   .set(VariantKey::kShadow, 1)
                   .set(VariantKey::kShadowProjection, 2)
                   .set(VariantKey::kCascadeCountMinus1, 5)
                   .valid());
static_assert(VariantKey()
                  .set(VariantKey::kShadow, 1)
                  .set(VariantKey::kShadowProjection, 2)
                  .filtered_for(Pass::depth) == VariantKey());
static_assert(VariantKey()
                  .set(VariantKey::kShadow, 1)
                  .set(VariantKey::kShadowProjection, 3)
                  .set(VariantKey::kShadowFilter, 2)
                  .filtered_for(Pass::depth) ==
              VariantKey().set(VariantKey::kShadow, 1).set(VariantKey::kShadowProjection, 3));

static_assert(VariantKey().set(VariantKey::kAlphaToCoverage, 1).filtered_for(Pass::forward) ==
              VariantKey());
static_assert(VariantKey().set(VariantKey::kAlphaToCoverage, 1).set(VariantKey::kAlphaMask, 1)
                  .filtered_for(Pass::forward)
                  .has(VariantKey::kAlphaToCoverage));
static_assert(VariantKey().set(VariantKey::kAlphaToCoverage, 1).set(VariantKey::kAlphaMask, 1)
                  .filtered_for(Pass::depth) == VariantKey().set(VariantKey::kAlphaMask, 1));

/// A program a frame needs: a pass and its key.
struct ProgramRequest {
  Pass pass = Pass::forward;
  VariantKey key;
};

}  // namespace kaskad::render
