// The GL-free rule for which texels of a map layer are kept, drawn or scrolled
// (runtime/render/layer_cache.h): invariants first, checked texel by texel on small layers.
#include "runtime/render/layer_cache.h"

#include <gtest/gtest.h>

#include <vector>

#include <glm/gtc/matrix_transform.hpp>

namespace kaskad::render {
namespace {

// How many of `rects` hold texel (x, y).
int covering(const std::vector<glm::ivec4>& rects, int x, int y) {
  int n = 0;
  for (const glm::ivec4& r : rects) n += x >= r.x && x < r.z && y >= r.y && y < r.w ? 1 : 0;
  return n;
}

bool inside(const glm::ivec4& r, int x, int y) { return x >= r.x && x < r.z && y >= r.y && y < r.w; }

TEST(LayerCache, OutsidePlusKeptCoversTheRectangleOnceEach) {
  const int size = 12;
  const glm::ivec4 r(1, 2, 10, 11);
  // Kept rectangles everywhere around and inside r, empty ones included.
  for (int x0 = 0; x0 <= size; x0 += 3)
    for (int y0 = 0; y0 <= size; y0 += 3)
      for (int x1 = x0; x1 <= size; x1 += 4)
        for (int y1 = y0; y1 <= size; y1 += 4) {
          const glm::ivec4 kept(x0, y0, x1, y1);
          const std::vector<glm::ivec4> out = outside(r, kept);
          EXPECT_LE(out.size(), 4u);
          for (int x = 0; x < size; ++x)
            for (int y = 0; y < size; ++y) {
              const int expected = inside(r, x, y) && !inside(kept, x, y) ? 1 : 0;
              ASSERT_EQ(covering(out, x, y), expected)
                  << "texel " << x << "," << y << " kept " << x0 << "," << y0 << "," << x1 << ","
                  << y1;
            }
        }
}

TEST(LayerCache, PiecesCoverTheWrappedRectangleOnceWithinTheTexture) {
  const int size = 8;
  const glm::ivec4 r(1, 3, 7, 8);
  for (int ox = 0; ox < size; ++ox)
    for (int oy = 0; oy < size; ++oy) {
      std::vector<LayerPiece> pieces;
      add_pieces(r, {ox, oy}, size, pieces);
      EXPECT_LE(pieces.size(), 4u);
      std::vector<int> hits(std::size_t(size * size), 0);
      for (const LayerPiece& p : pieces) {
        const glm::ivec4 t = p.texture;
        ASSERT_TRUE(t.x >= 0 && t.y >= 0 && t.z <= size && t.w <= size && !empty_rect(t));
        for (int x = t.x; x < t.z; ++x)
          for (int y = t.y; y < t.w; ++y) {
            // The map texel the piece's viewport puts on texture texel (x, y) is inside r.
            EXPECT_TRUE(inside(r, x - p.viewport.x, y - p.viewport.y));
            ++hits[std::size_t(y * size + x)];
          }
      }
      // Every map texel of r lies at (x + origin) mod size, and nothing else is drawn.
      for (int x = 0; x < size; ++x)
        for (int y = 0; y < size; ++y) {
          const int mx = ((x - ox) % size + size) % size, my = ((y - oy) % size + size) % size;
          EXPECT_EQ(hits[std::size_t(y * size + x)], inside(r, mx, my) ? 1 : 0)
              << "origin " << ox << "," << oy << " texture texel " << x << "," << y;
        }
    }
}

TEST(LayerCache, MovedByWholeTexelsAndTheOriginFollows) {
  const int size = 64;
  const glm::mat4 before = glm::ortho(-10.0f, 10.0f, -10.0f, 10.0f, 0.0f, 50.0f);
  glm::mat4 now = before;
  now[3][0] += 3.0f * 2.0f / size;   // three texels along x
  now[3][1] -= 5.0f * 2.0f / size;   // five back along y
  glm::ivec2 shift(0);
  ASSERT_TRUE(moved_by_texels(before, now, size, shift));
  EXPECT_EQ(shift, glm::ivec2(3, -5));
  // A fixed point moved by `shift` map texels stays on its texture texel.
  const glm::ivec2 origin = scrolled_origin({2, 1}, shift, size);
  EXPECT_EQ(origin, glm::ivec2(63, 6));
  for (int a = 0; a < 2; ++a) {
    const int x = 20;
    EXPECT_EQ((x + glm::ivec2(2, 1)[a]) % size, (x + shift[a] + origin[a]) % size);
  }
  glm::mat4 half = before;
  half[3][0] += 0.5f * 2.0f / size;
  EXPECT_FALSE(moved_by_texels(before, half, size, shift));
  glm::mat4 scaled = before;
  scaled[0][0] *= 1.01f;
  EXPECT_FALSE(moved_by_texels(before, scaled, size, shift));
}

TEST(LayerCache, ShiftedAndTexelRects) {
  EXPECT_EQ(shifted({2, 2, 6, 6}, {3, -1}, 8), glm::ivec4(5, 1, 8, 5));
  EXPECT_EQ(shifted({2, 2, 6, 6}, {9, 0}, 8), glm::ivec4(0));
  EXPECT_EQ(texel_rect({-1.0f, -1.0f, 1.0f, 1.0f}, 16), glm::ivec4(0, 0, 16, 16));
  EXPECT_EQ(texel_rect({-0.5f, -0.6f, 0.1f, 2.0f}, 16), glm::ivec4(4, 3, 9, 16));
  EXPECT_EQ(texel_rect({0.5f, 0.0f, 0.1f, 1.0f}, 16), glm::ivec4(0));
  EXPECT_TRUE(holds({0, 0, 8, 8}, {1, 1, 7, 7}));
  EXPECT_TRUE(holds({0, 0, 0, 0}, {3, 3, 3, 9}));  // an empty rectangle lies anywhere
  EXPECT_FALSE(holds({1, 1, 7, 7}, {0, 1, 7, 7}));
}

TEST(LayerCache, KeepsALayerOnlyWhenCachedDrawnOverEnoughAndUnchangedOrHeld) {
  const DrawnLayer drawn{42, {0, 0, 8, 8}};
  const glm::ivec4 needed(1, 1, 6, 6);
  EXPECT_TRUE(keeps_layer(true, drawn, 42, needed, false));
  EXPECT_FALSE(keeps_layer(false, drawn, 42, needed, false));                 // cache off
  EXPECT_FALSE(keeps_layer(true, drawn, 43, needed, false));                  // inputs changed
  EXPECT_TRUE(keeps_layer(true, drawn, 43, needed, true));                    // held
  EXPECT_FALSE(keeps_layer(true, drawn, 42, {0, 0, 9, 8}, true));             // needs more texels
  EXPECT_FALSE(keeps_layer(true, DrawnLayer{0, {0, 0, 8, 8}}, 0, needed, true));  // never drawn
}

}  // namespace
}  // namespace kaskad::render
