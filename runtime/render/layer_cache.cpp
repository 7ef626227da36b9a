#include "runtime/render/layer_cache.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace kaskad::render {

bool keeps_layer(bool cache, const DrawnLayer& drawn, std::uint64_t inputs,
                 const glm::ivec4& needed, bool held) {
  return cache && drawn.inputs != 0 && holds(drawn.rect, needed) &&
         (inputs == drawn.inputs || held);
}

bool holds(const glm::ivec4& outer, const glm::ivec4& inner) {
  return empty_rect(inner) || (outer.x <= inner.x && outer.y <= inner.y && outer.z >= inner.z &&
                               outer.w >= inner.w);
}

glm::ivec4 texel_rect(const glm::vec4& ndc, int size) {
  if (!(ndc.x <= ndc.z && ndc.y <= ndc.w)) return glm::ivec4(0);
  auto texel = [size](float v, bool up) {
    const float t = (v + 1.0f) * 0.5f * float(size);
    return std::clamp(int(up ? std::ceil(t) : std::floor(t)), 0, size);
  };
  return {texel(ndc.x, false), texel(ndc.y, false), texel(ndc.z, true), texel(ndc.w, true)};
}

glm::vec4 drawn_ndc(const glm::ivec4& r, int size) {
  const float texel = 2.0f / float(size);
  return glm::vec4(r) * texel - 1.0f + glm::vec4(-2, -2, 2, 2) * texel;
}

bool box_misses(const Aabb& box, const glm::mat4& light_vp, const glm::vec4& ndc) {
  const Aabb b = box.transformed(light_vp);
  return b.max.x < ndc.x || b.min.x > ndc.z || b.max.y < ndc.y || b.min.y > ndc.w;
}

glm::ivec4 shifted(const glm::ivec4& r, glm::ivec2 shift, int size) {
  if (empty_rect(r)) return glm::ivec4(0);
  const glm::ivec4 moved = glm::clamp(r + glm::ivec4(shift, shift), glm::ivec4(0), glm::ivec4(size));
  return empty_rect(moved) ? glm::ivec4(0) : moved;
}

std::vector<glm::ivec4> outside(const glm::ivec4& r, const glm::ivec4& kept) {
  if (empty_rect(r)) return {};
  const glm::ivec4 k(std::max(r.x, kept.x), std::max(r.y, kept.y), std::min(r.z, kept.z),
                     std::min(r.w, kept.w));
  if (empty_rect(kept) || empty_rect(k)) return {r};
  std::vector<glm::ivec4> out;
  if (r.y < k.y) out.push_back({r.x, r.y, r.z, k.y});
  if (k.w < r.w) out.push_back({r.x, k.w, r.z, r.w});
  if (r.x < k.x) out.push_back({r.x, k.y, k.x, k.w});
  if (k.z < r.z) out.push_back({k.z, k.y, r.z, k.w});
  return out;
}

bool moved_by_texels(const glm::mat4& before, const glm::mat4& now, int size, glm::ivec2& shift) {
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 4; ++row)
      if ((col != 3 || row > 1) && before[col][row] != now[col][row]) return false;
  for (int a = 0; a < 2; ++a) {
    const double texels = (double(now[3][a]) - double(before[3][a])) * 0.5 * size;
    const double whole = std::round(texels);
    if (!(std::abs(texels - whole) < 1e-3 && std::abs(whole) < size)) return false;
    shift[a] = int(whole);
  }
  return true;
}

glm::ivec2 scrolled_origin(glm::ivec2 origin, glm::ivec2 shift, int size) {
  return ((origin - shift) % size + size) % size;
}

void add_pieces(const glm::ivec4& r, glm::ivec2 origin, int size, std::vector<LayerPiece>& out) {
  if (empty_rect(r)) return;
  // Per axis: [lo, hi) of the unwrapped texture in [0, 2 size), cut at size.
  auto parts = [size](int lo, int hi, int o) {
    std::array<glm::ivec3, 2> p{};  // texture x0, x1, viewport
    int n = 0;
    if (lo + o < size) p[std::size_t(n++)] = {lo + o, std::min(hi + o, size), o};
    if (hi + o > size) p[std::size_t(n++)] = {std::max(lo + o, size) - size, hi + o - size, o - size};
    return std::pair(p, n);
  };
  const auto [xs, nx] = parts(r.x, r.z, origin.x);
  const auto [ys, ny] = parts(r.y, r.w, origin.y);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      const glm::ivec3 x = xs[std::size_t(i)], y = ys[std::size_t(j)];
      out.push_back({glm::ivec4(x.x, y.x, x.y, y.y), glm::ivec2(x.z, y.z)});
    }
}

}  // namespace kaskad::render
