// Which texels of a map layer a pass draws, keeps or scrolls: texel rectangles, the per-layer
// cache rule that the shadow, LOM and moments passes share, and the scrolling of a stable
// cascade by whole texels (render.shadow_scroll). GL-free: the passes (shadow_map_pass.cpp,
// lom_pass.cpp, moments_pass.cpp) turn the results into clears, scissors and viewports.
// Rectangles are texels (x0, y0, x1, y1) of a layer, ends exclusive; x0 >= x1 or y0 >= y1 is
// empty.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "components/bounds.h"

namespace kaskad::render {

/// What a layer of a pass's storage was last drawn from: a hash of its inputs (0: nothing
/// valid) and the texels drawn; outside them the layer holds stale data no lookup reads.
struct DrawnLayer {
  std::uint64_t inputs = 0;
  glm::ivec4 rect{0};
};

/// The per-layer cache rule: a layer keeps what it holds when the cache is on
/// (render.shadow_cache), it was drawn over at least the texels `needed` now, and its inputs
/// hash as then or its view holds it (`held`: ShadowView::held, a far cascade between refits).
bool keeps_layer(bool cache, const DrawnLayer& drawn, std::uint64_t inputs,
                 const glm::ivec4& needed, bool held);

/// Whether `r` holds no texel.
constexpr bool empty_rect(const glm::ivec4& r) { return r.x >= r.z || r.y >= r.w; }

/// Whether `inner` lies in `outer` (an empty one lies anywhere).
bool holds(const glm::ivec4& outer, const glm::ivec4& inner);

/// The texels of a layer of `size`^2 that cover the NDC rectangle `ndc` (min x, min y, max x,
/// max y); (0, 0, 0, 0) when it is empty.
glm::ivec4 texel_rect(const glm::vec4& ndc, int size);

/// The NDC rectangle (x0, y0, x1, y1) of texels `r` of a layer of `size`^2, two texels wider on
/// each side: casters are tested against it, as the rectangle is whole texels and the
/// rasteriser's coverage rules are its own.
glm::vec4 drawn_ndc(const glm::ivec4& r, int size);

/// Whether `box`, through the affine (ortho) light matrix `light_vp`, misses NDC rectangle `ndc`.
bool box_misses(const Aabb& box, const glm::mat4& light_vp, const glm::vec4& ndc);

/// `r` moved by `shift` texels and cut to a layer of `size`^2.
glm::ivec4 shifted(const glm::ivec4& r, glm::ivec2 shift, int size);

/// The texels of `r` outside `kept`: up to four disjoint rectangles (below, above, left and
/// right of it) that with r's part inside `kept` cover r exactly.
std::vector<glm::ivec4> outside(const glm::ivec4& r, const glm::ivec4& kept);

/// Whether ortho matrix `now` is `before` moved by whole texels of a layer of `size`^2 (every
/// entry the same but the x and y translation, by less than a layer), and by how many: a fixed
/// point's map texel moves by `shift`.
bool moved_by_texels(const glm::mat4& before, const glm::mat4& now, int size, glm::ivec2& shift);

/// The texture origin of a layer after its map moved by `shift` texels: map texel x lies at
/// texture texel (x + origin) mod size, so a fixed point stays on its texel. In [0, size).
glm::ivec2 scrolled_origin(glm::ivec2 origin, glm::ivec2 shift, int size);

/// A part of a layer drawn: texels `texture` of the texture (within one wrap) drawn through a
/// viewport at `viewport` (map texel x lands on texture texel x + viewport).
struct LayerPiece {
  glm::ivec4 texture;
  glm::ivec2 viewport;
};

/// Appends the pieces of map rectangle `r` in a layer of `size`^2 whose texture holds map texel
/// x at (x + origin) mod size (origin in [0, size)): up to two per axis, each within one wrap.
void add_pieces(const glm::ivec4& r, glm::ivec2 origin, int size, std::vector<LayerPiece>& out);

}  // namespace kaskad::render
