// How an environment file holds its cube map: what load_cube_map() (runtime/assets/env_map.h)
// reads, what a static reflection probe's `layout` names (components/reflector.h) and what
// `kaskad envmap --layout` takes. Declared once, with its names (docs/guide/envmaps.md).
#pragma once

#include <array>
#include <cstddef>
#include <string_view>

namespace kaskad {

enum class EnvLayout { auto_detect, faces, horizontal_cross, vertical_cross, equirect, sphere };
constexpr std::array<std::string_view, 6> enum_names(EnvLayout) {
  return {"auto", "faces", "horizontal_cross", "vertical_cross", "equirect", "sphere"};
}
static_assert(enum_names(EnvLayout{}).size() == std::size_t(EnvLayout::sphere) + 1);

}  // namespace kaskad
