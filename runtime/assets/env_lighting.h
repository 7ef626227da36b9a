// Image-based lighting from cube maps on the CPU (components/ibl.h has the per-pixel formulas):
// the 9 SH coefficients of a cube's radiance and its GGX-prefiltered radiance. The GPU computes
// both for the renderer (content/shaders/sh_project.frag, ibl_prefilter.frag, IblMaps); these
// are their reference twins, used by the tests and by the reflection reference.
#pragma once

#include <cstdint>

#include "components/ibl.h"
#include "runtime/assets/env_map.h"

namespace kaskad {

/// The radiance's SH coefficients: sum over every texel of texel * Y_i(direction) * solid angle,
/// the solid angles normalised to add up to 4 pi (as sh_project.frag does). Empty cube: zeros.
Sh9 project_sh9(const CubeMap& cube);

/// The radiance around direction r convolved with the GGX lobe of `roughness` (N = V = R,
/// weighted by N.L): ibl_prefilter.frag's quantity, by plain importance sampling of `samples`
/// directions of the full-resolution cube (slow; a reference). Empty cube: zero.
glm::vec3 prefiltered_radiance(const CubeMap& cube, const glm::vec3& r, float roughness,
                               std::uint32_t samples);

}  // namespace kaskad
