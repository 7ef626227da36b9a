// The variant key: which compile-time features a program has. A 32-bit value with named bits
// and small integer fields (Filament's Variant, Bevy's MeshPipelineKey), split into
//   material features  (bits 0-15)  what a material uses      -> MATERIAL_HAS_* defines
//   frame features     (bits 16-31) what the frame needs      -> VARIANT_* defines
// Defines are produced from a key by one function (ShaderLibrary / FeatureManifest::defines),
// driven by content/shaders/features.json, which names every field below; the manifest loader
// checks that it matches this layout.
//
// Valid combinations (valid()):
//   reflection_cube and reflection_sphere exclude each other
//   reflection_box needs reflection_cube
//   shadow_filter != 0 and cascade_count != 1 need shadow
//   debug_cascades, cascade_selection and shadow_projection need shadow
//   shadow_projection != ortho has cascade_count 1 (cascades are directional only)
//   shadow_layered needs shadow; the depth pass keeps it (its vertex shader picks the layer)
//   shadow_lights != 1 needs shadow (the lookups of lights that do not exist are not compiled)
// filtered_for(Pass::depth) keeps only what the depth pass uses (alpha_mask, and the projection
// when it is dual_paraboloid: its vertex shader differs), so every material shares one or two
// shadow programs.
#pragma once

#include <cstdint>
#include <string>

namespace kaskad::render {

/// forward: colour + AOVs; depth: shadow maps; shadow_points: the shadow lookup evaluated at given
/// world points (Renderer::shadow_at_points(), the stability metrics).
enum class Pass : std::uint8_t { forward = 0, depth = 1, shadow_points = 2 };

constexpr const char* pass_name(Pass pass) {
  switch (pass) {
    case Pass::depth: return "depth";
    case Pass::shadow_points: return "points";
    case Pass::forward: break;
  }
  return "forward";
}

class VariantKey {
 public:
  // Layout: bit offset and width of each field. Change together with features.json.
  struct Field {
    std::uint8_t offset;
    std::uint8_t width;
    constexpr std::uint32_t mask() const { return ((1u << width) - 1u) << offset; }
    constexpr std::uint32_t max() const { return (1u << width) - 1u; }
  };
  // Material features.
  static constexpr Field kBaseColorTexture{0, 1};
  static constexpr Field kNormalMap{1, 1};
  static constexpr Field kAlphaMask{2, 1};
  static constexpr Field kEmissive{3, 1};
  static constexpr Field kReflectionCube{4, 1};
  static constexpr Field kReflectionSphere{5, 1};
  static constexpr Field kReceiveShadows{6, 1};
  static constexpr Field kReflectionBox{7, 1};
  static constexpr std::uint32_t kMaterialMask = 0x0000ffffu;
  // Frame features.
  static constexpr Field kShadow{16, 1};
  static constexpr Field kShadowFilter{17, 2};   ///< 0 none, 1 bilinear, 2 pcf3x3
  static constexpr Field kCascadeCountMinus1{19, 3};  ///< cascade count - 1 (1..8 cascades)
  static constexpr Field kAovs{22, 1};
  static constexpr Field kDebugCascades{23, 1};
  static constexpr Field kCascadeSelection{24, 1};  ///< 0 depth (S0's D), 1 map bounds
  /// ShadowProjection: 0 ortho, 1 perspective, 2 cube, 3 dual_paraboloid.
  static constexpr Field kShadowProjection{25, 2};
  static constexpr std::uint32_t kProjectionDualParaboloid = 3;
  static constexpr Field kShadowLayered{27, 1};  ///< depth pass: all layers in one pass
  /// Shadowed lights - 1 (1..4): the first plus the further directional ones the frame has.
  /// A count, not a switch, so loops over shadowed lights have a compile-time bound and a light
  /// that does not exist costs nothing (llvmpipe runs a zero-trip loop's body once, masked).
  static constexpr Field kShadowLightsMinus1{28, 2};
  static constexpr std::uint32_t kFrameMask = 0xffff0000u;

  constexpr VariantKey() = default;
  constexpr explicit VariantKey(std::uint32_t bits) : bits_(bits) {}

  constexpr std::uint32_t bits() const { return bits_; }
  constexpr std::uint32_t get(Field f) const { return (bits_ & f.mask()) >> f.offset; }
  constexpr VariantKey& set(Field f, std::uint32_t value) {
    bits_ = (bits_ & ~f.mask()) | ((value << f.offset) & f.mask());
    return *this;
  }
  constexpr bool has(Field f) const { return get(f) != 0; }

  constexpr VariantKey material() const { return VariantKey(bits_ & kMaterialMask); }
  constexpr VariantKey frame() const { return VariantKey(bits_ & kFrameMask); }
  constexpr VariantKey operator|(VariantKey o) const { return VariantKey(bits_ | o.bits_); }
  constexpr bool operator==(const VariantKey&) const = default;
  constexpr auto operator<=>(const VariantKey&) const = default;

  /// The combination rules in the header comment. Unused bits must be zero.
  constexpr bool valid() const {
    constexpr std::uint32_t used =
        kBaseColorTexture.mask() | kNormalMap.mask() | kAlphaMask.mask() | kEmissive.mask() |
        kReflectionCube.mask() | kReflectionSphere.mask() | kReceiveShadows.mask() |
        kReflectionBox.mask() |
        kShadow.mask() | kShadowFilter.mask() | kCascadeCountMinus1.mask() | kAovs.mask() |
        kDebugCascades.mask() | kCascadeSelection.mask() | kShadowProjection.mask() |
        kShadowLayered.mask() | kShadowLightsMinus1.mask();
    if (bits_ & ~used) return false;
    if (has(kReflectionCube) && has(kReflectionSphere)) return false;
    if (has(kReflectionBox) && !has(kReflectionCube)) return false;
    if (get(kShadowFilter) > 2) return false;
    if (!has(kShadow) && (has(kShadowFilter) || has(kCascadeCountMinus1) || has(kDebugCascades) ||
                          has(kCascadeSelection) || has(kShadowProjection) || has(kShadowLayered) ||
                          has(kShadowLightsMinus1)))
      return false;
    if (has(kShadowProjection) && has(kCascadeCountMinus1)) return false;
    return true;
  }

  /// The part of the key a pass's shaders read. The depth pass only needs alpha masking; the
  /// shadow-points pass only the shadow lookup's frame features (a receiver, without AOVs or the
  /// debug tint); the forward pass needs everything.
  constexpr VariantKey filtered_for(Pass pass) const {
    if (pass == Pass::depth) {
      const std::uint32_t projection = get(kShadowProjection) == kProjectionDualParaboloid
                                           ? kShadowProjection.mask() | kShadow.mask()
                                           : 0u;
      const std::uint32_t layered =
          has(kShadowLayered) ? kShadowLayered.mask() | kShadow.mask() : 0u;
      return VariantKey(bits_ & (kAlphaMask.mask() | projection | layered));
    }
    if (pass == Pass::shadow_points)
      return VariantKey((bits_ & kFrameMask & ~kAovs.mask() & ~kDebugCascades.mask() &
                         ~kShadowLayered.mask()) |
                        kReceiveShadows.mask());
    return *this;
  }

 private:
  std::uint32_t bits_ = 0;
};

static_assert(VariantKey().valid());
static_assert(!VariantKey().set(VariantKey::kReflectionCube, 1).set(VariantKey::kReflectionSphere, 1).valid());
static_assert(!VariantKey().set(VariantKey::kShadowFilter, 2).valid());
static_assert(VariantKey().set(VariantKey::kShadow, 1).set(VariantKey::kShadowFilter, 2).valid());
static_assert(!VariantKey().set(VariantKey::kReflectionBox, 1).valid());
static_assert(VariantKey().set(VariantKey::kReflectionBox, 1).set(VariantKey::kReflectionCube, 1).valid());
static_assert(VariantKey().set(VariantKey::kNormalMap, 1).filtered_for(Pass::depth) == VariantKey());
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

}  // namespace kaskad::render
