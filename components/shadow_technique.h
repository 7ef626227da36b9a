// The traits of every shadow technique (ShadowTechnique, components/shadow_settings.h) in one
// table: what the renderer, the draw list and the systems ask of a technique is a question to
// its row, never a list of techniques. Row i describes enumerator i (checked below). Adding a
// technique that only changes the lookup: its enumerator and name (shadow_settings.h), its row
// here, and its GLSL lookup (content/shaders/README.md, "Shadow lookup files").
#pragma once

#include <array>
#include <cstddef>

#include "components/limits.h"
#include "components/shadow_settings.h"

namespace kaskad {

/// The pass a technique runs after the shadow maps and before the forward pass.
enum class ShadowExtraPass {
  none,         ///< the lookup reads the depth maps alone
  lom_peeling,  ///< LomPass: depth peels and occlusion factors (S1's layered occlusion map)
  moments,      ///< MomentsPass: blurred, mipmapped moments of each layer's depth
};

/// How far a technique's lookup reaches from the point's texel (filter_reach_texels()).
enum class ShadowReach {
  filter_footprint,  ///< the filter's footprint: 1.5 for the single taps and S4's 3x3, or the
                     ///< pcf_kernel's (N / 2 for an N x N box, the disc's radius plus one)
  pcss_search,       ///< PCSS's largest search radius plus one (kPcssMaxRadiusTexels + 1)
  one_texel,         ///< one texel (lom: the four neighbouring samples; the occlusion factors
                     ///< already hold the light's reach)
  blur_half_width,   ///< the moments blur's half width plus one (the lookup filters linearly)
};

/// One row of kShadowTechniques.
struct ShadowTechniqueTraits {
  ShadowTechnique technique;
  ShadowExtraPass extra_pass = ShadowExtraPass::none;
  /// Moments stored per texel by the moments pass: 0 (none), 2 (E[z], E[z^2]) or 4 (two warps).
  /// The shaders' TECHNIQUE_MOMENT_CHANNELS (FeatureManifest::defines()).
  int moment_channels = 0;
  /// The lookup uses the light's size (Light::angular_size_deg or Light::radius; a punctual
  /// light gives hard shadows); views of other techniques get size 0. The shaders'
  /// TECHNIQUE_NEEDS_LIGHT_SIZE.
  bool needs_light_size = false;
  ShadowReach reach = ShadowReach::filter_footprint;
  /// ShadowSettings::pcf_kernel picks the footprint of filter pcf3x3 (VariantKey::kShadowKernel).
  bool uses_pcf_kernel = false;
  /// The lookup reads only around the point with its compare filter, so it may read a scrolled
  /// layer at wrapped coordinates (render.shadow_scroll); lookups that search wide regions or
  /// read maps derived from the depth do not wrap.
  bool may_wrap = false;
};

/// Every technique, in enumerator order.
inline constexpr ShadowTechniqueTraits kShadowTechniques[] = {
    {.technique = ShadowTechnique::pcf, .uses_pcf_kernel = true, .may_wrap = true},
    {.technique = ShadowTechnique::pcss, .needs_light_size = true,
     .reach = ShadowReach::pcss_search},
    {.technique = ShadowTechnique::backprojection,
     .needs_light_size = true, .reach = ShadowReach::pcss_search},
    {.technique = ShadowTechnique::lom, .extra_pass = ShadowExtraPass::lom_peeling,
     .needs_light_size = true, .reach = ShadowReach::one_texel},
    {.technique = ShadowTechnique::vsm, .extra_pass = ShadowExtraPass::moments,
     .moment_channels = 2, .reach = ShadowReach::blur_half_width},
    {.technique = ShadowTechnique::evsm, .extra_pass = ShadowExtraPass::moments,
     .moment_channels = 4, .reach = ShadowReach::blur_half_width},
};

/// Techniques in the enum: one more than its last enumerator.
inline constexpr std::size_t kShadowTechniqueCount = std::size(kShadowTechniques);

namespace shadow_technique_detail {
constexpr bool rows_in_enum_order() {
  for (std::size_t i = 0; i < kShadowTechniqueCount; ++i)
    if (static_cast<std::size_t>(kShadowTechniques[i].technique) != i) return false;
  return true;
}
constexpr bool rows_consistent() {
  for (const ShadowTechniqueTraits& t : kShadowTechniques) {
    if ((t.extra_pass == ShadowExtraPass::moments) != (t.moment_channels != 0)) return false;
    if (t.moment_channels != 0 && t.moment_channels != 2 && t.moment_channels != 4) return false;
  }
  return true;
}
}  // namespace shadow_technique_detail

// One row per enumerator (enum_names() beside the enum is tied to its last one), row i for
// enumerator i.
static_assert(kShadowTechniqueCount == enum_names(ShadowTechnique{}).size(),
              "kShadowTechniques needs one row per ShadowTechnique");
static_assert(shadow_technique_detail::rows_in_enum_order(),
              "row i of kShadowTechniques must describe ShadowTechnique value i");
static_assert(shadow_technique_detail::rows_consistent(),
              "a technique with moments runs the moments pass, with 2 or 4 channels");

/// The row of technique `t` (a valid enumerator: validate_shadow_settings() checks files' values).
constexpr const ShadowTechniqueTraits& traits(ShadowTechnique t) {
  return kShadowTechniques[static_cast<std::size_t>(t)];
}

/// Texels a lookup reaches from the point's texel, by the technique's reach rule
/// (ShadowReach). Local lights keep this (plus the normal offset and one spare) free at their
/// maps' edges; map_bounds selection likewise (ShadowView::filter_reach carries it to
/// shadow.glsl's map_border()). Moments: their mip levels past 0 reach further, into texels the
/// blur left clear.
inline float filter_reach_texels(const ShadowSettings& s) {
  switch (traits(s.technique).reach) {
    case ShadowReach::one_texel: return 1.0f;
    case ShadowReach::blur_half_width: return float(s.vsm_blur / 2) + 1.0f;
    case ShadowReach::pcss_search: return float(kPcssMaxRadiusTexels) + 1.0f;
    case ShadowReach::filter_footprint: break;
  }
  if (s.filter != ShadowFilter::pcf3x3 || !traits(s.technique).uses_pcf_kernel) return 1.5f;
  switch (s.pcf_kernel) {
    case PcfKernel::k3x3: return 1.5f;
    case PcfKernel::k5x5: return 2.5f;
    case PcfKernel::k7x7: return 3.5f;
    case PcfKernel::k9x9: return 4.5f;
    case PcfKernel::poisson: return s.pcf_radius + 1.0f;
  }
  return 1.5f;
}

}  // namespace kaskad
