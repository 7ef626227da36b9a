// The draw list's order (runtime/render/draw_list.h), without GL. Draws that may share one
// instanced draw must be neighbours in every pass's order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <tuple>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "runtime/render/draw_list.h"

namespace kaskad::render {
namespace {

// Materials that sort apart, and two that differ only by the sign of a zero (equal materials).
std::vector<Material> materials() {
  std::vector<Material> out(7);
  out[1].base_color = {0.2f, 0.4f, 0.6f, 1.0f};
  out[2].roughness = 0.9f;
  out[3].metallic = 0.0f;
  out[4].metallic = -0.0f;  // equal to out[3]
  out[5].alpha_mode = AlphaMode::mask;
  out[5].features = VariantKey().set(VariantKey::kAlphaMask, 1).bits();
  out[5].alpha_cutoff = 0.3f;
  out[6].double_sided = true;
  out[6].metallic = 1.0f;
  return out;
}

FrameInput shuffled_draws(int count, unsigned seed) {
  std::mt19937 gen(seed);
  const std::vector<Material> mats = materials();
  FrameInput frame;
  for (int i = 0; i < count; ++i) {
    DrawItem d;
    d.mesh = MeshId{std::uint32_t(gen() % 3)};
    d.material = mats[gen() % mats.size()];
    d.receive_shadows = gen() % 4 != 0;
    d.model[3] = glm::vec4(float(i), 0.0f, 0.0f, 1.0f);
    if (gen() % 5 == 0) d.model[0].x = -1.0f;  // a mirroring transform: the other winding
    frame.draws.push_back(d);
  }
  frame.shadow_views.push_back(ShadowView{});
  frame.shadow_views.back().layer_count = 4;
  return frame;
}

// Every class of draws (by `same`) occupies one run of `order`, in ascending draw index unless
// `ascending` is false (a class that spans several materials, sorted by material within). The
// materials that differ only by a zero's sign are equal, so they share their runs too.
template <typename Same>
void expect_runs(const std::vector<std::uint32_t>& order, std::size_t draws, Same same,
                 const char* what, bool ascending = true) {
  std::vector<std::uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  ASSERT_EQ(sorted.size(), draws) << what;
  for (std::uint32_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i) << what;  // a permutation
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::uint32_t i = order[k];
    if (k > 0 && same(order[k - 1], i)) {
      if (ascending) {
        EXPECT_LT(order[k - 1], i) << what << ": a run keeps the draws' order";
      }
      continue;
    }
    for (std::size_t j = 0; j < k; ++j)
      if (same(order[j], i)) {
        ADD_FAILURE() << what << ": draw " << i << " is apart from draw " << order[j];
        return;
      }
  }
}

// Each order is sorted by its keys (materials by material_sorts_before()), every class of draws
// that may share one call (a multi-draw) is one run of it, and within that every class that may
// share one instanced draw.
TEST(DrawList, EveryOrderIsSortedAndDrawsThatMayShareADrawAreNeighbours) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const FrameInput frame = shuffled_draws(3000, seed);
    const DrawList list = build_draw_list(frame, frame_variant(frame));
    const auto& d = frame.draws;
    auto fwd = [&](std::uint32_t a) { return list.keys[a].filtered_for(Pass::forward); };
    auto same_call = [&](std::uint32_t a, std::uint32_t b) {
      return fwd(a) == fwd(b) && d[a].material == d[b].material &&
             mirrors(d[a].model) == mirrors(d[b].model);
    };
    expect_runs(list.forward_order, d.size(), same_call, "forward calls", false);
    expect_runs(
        list.forward_order, d.size(),
        [&](std::uint32_t a, std::uint32_t b) { return same_call(a, b) && d[a].mesh == d[b].mesh; },
        "forward");
    // Sorted by (key, winding, material, mesh): no draw sorts before the one ahead of it.
    auto forward_less = [&](std::uint32_t a, std::uint32_t b) {
      if (fwd(a) != fwd(b)) return fwd(a) < fwd(b);
      if (mirrors(d[a].model) != mirrors(d[b].model)) return mirrors(d[b].model);
      if (material_sorts_before(d[a].material, d[b].material)) return true;
      if (material_sorts_before(d[b].material, d[a].material)) return false;
      return d[a].mesh < d[b].mesh;
    };
    for (std::size_t k = 1; k < list.forward_order.size(); ++k)
      EXPECT_FALSE(forward_less(list.forward_order[k], list.forward_order[k - 1])) << k;
    // The depth pass: one draw per mesh whatever the material, unless alpha-masked.
    auto depth = [&](std::uint32_t a) { return list.keys[a].filtered_for(Pass::depth); };
    auto same_depth_call = [&](std::uint32_t a, std::uint32_t b) {
      if (depth(a) != depth(b) || mirrors(d[a].model) != mirrors(d[b].model)) return false;
      return !list.keys[a].has(VariantKey::kAlphaMask) || d[a].material == d[b].material;
    };
    expect_runs(list.depth_order, d.size(), same_depth_call, "depth calls", false);
    expect_runs(
        list.depth_order, d.size(),
        [&](std::uint32_t a, std::uint32_t b) {
          return same_depth_call(a, b) && d[a].mesh == d[b].mesh;
        },
        "depth", false);
    // Sorted by (key, winding, mesh, material) where the key has no alpha mask, else (key,
    // winding, material, mesh).
    auto depth_less = [&](std::uint32_t a, std::uint32_t b) {
      if (depth(a) != depth(b)) return depth(a) < depth(b);
      if (mirrors(d[a].model) != mirrors(d[b].model)) return mirrors(d[b].model);
      if (!list.keys[a].has(VariantKey::kAlphaMask) && d[a].mesh != d[b].mesh) return d[a].mesh < d[b].mesh;
      if (material_sorts_before(d[a].material, d[b].material)) return true;
      if (material_sorts_before(d[b].material, d[a].material)) return false;
      return d[a].mesh < d[b].mesh;
    };
    for (std::size_t k = 1; k < list.depth_order.size(); ++k)
      EXPECT_FALSE(depth_less(list.depth_order[k], list.depth_order[k - 1])) << k;
  }
}

// The order does not depend on the order the draws arrive in: the same multiset of draws, fed
// in two orders, gives the same sequence of (key, material, mesh).
TEST(DrawList, TheOrderOfClassesIsTheSameWhateverOrderDrawsArriveIn) {
  FrameInput a = shuffled_draws(500, 9u);
  FrameInput b = a;
  std::reverse(b.draws.begin(), b.draws.end());
  auto classes = [](const FrameInput& f) {
    const DrawList list = build_draw_list(f, frame_variant(f));
    std::vector<std::tuple<std::uint64_t, bool, std::uint32_t, AlphaMode, float, float, float>> out;
    for (std::uint32_t i : list.forward_order) {
      const DrawItem& d = f.draws[i];
      out.emplace_back(list.keys[i].bits(), mirrors(d.model), std::uint32_t(d.mesh),
                       d.material.alpha_mode, d.material.roughness, d.material.base_color.r,
                       d.material.metallic == 0.0f ? 0.0f : d.material.metallic);
    }
    return out;
  };
  EXPECT_EQ(classes(a), classes(b));
}

// Blended draws leave the forward and capture orders (the depth order keeps them: they cast as
// cut-outs), and back_to_front() sorts them farthest first along the view direction, equal
// distances in draw order, with bounds' centres or, without bounds, the model's origin.
TEST(DrawList, BlendedDrawsAreDrawnApartAndBackToFront) {
  FrameInput frame;
  const float z[] = {-2.0f, -8.0f, -5.0f, -8.0f, -1.0f};  // view depths 2, 8, 5, 8 and an opaque 1
  for (int i = 0; i < 5; ++i) {
    DrawItem d;
    d.mesh = MeshId{0};
    if (i < 4) {
      d.material.alpha_mode = AlphaMode::blend;
      d.material.features = VariantKey::kAlphaBlend.mask();
    }
    if (i == 2) {
      d.model[3] = glm::vec4(0, 0, z[i], 1);  // no bounds: its origin
    } else {
      d.bounds = Aabb::from_corners(glm::vec3(-1, -1, z[i] - 0.5f), glm::vec3(1, 1, z[i] + 0.5f));
      d.model[3] = glm::vec4(100, 0, 100, 1);  // far from its bounds: not used
    }
    frame.draws.push_back(d);
  }
  frame.shadow_views.push_back(ShadowView{});
  frame.probes.push_back(ProbeJob{});
  const DrawList list = build_draw_list(frame, frame_variant(frame));
  EXPECT_EQ(list.forward_order, std::vector<std::uint32_t>{4});
  EXPECT_EQ(list.capture_order, std::vector<std::uint32_t>{4});
  EXPECT_EQ(list.blend_draws, (std::vector<std::uint32_t>{0, 1, 2, 3}));
  EXPECT_EQ(list.depth_order.size(), 5u);
  // Blended casters use the alpha-masked depth program.
  EXPECT_TRUE(list.keys[0].filtered_for(Pass::depth).has(VariantKey::kAlphaMask));
  // A camera at the origin looking down -z: view depth -z.
  const glm::mat4 view(1.0f);
  EXPECT_EQ(back_to_front(frame, list.blend_draws, view_depth_plane(view)),
            (std::vector<std::uint32_t>{1, 3, 2, 0}));
  // Turned round (looking down +z from z = -10): the order reverses, ties still in draw order.
  const glm::mat4 behind = glm::lookAt(glm::vec3(0, 0, -10), glm::vec3(0, 0, 0), glm::vec3(0, 1, 0));
  EXPECT_EQ(back_to_front(frame, list.blend_draws, view_depth_plane(behind)),
            (std::vector<std::uint32_t>{0, 2, 1, 3}));
  // A perspective view-projection's clip w is the same distance (probe faces).
  const glm::mat4 proj = glm::perspective(glm::radians(90.0f), 1.0f, 0.1f, 100.0f);
  const glm::vec4 plane = clip_depth_plane(proj * behind);
  EXPECT_NEAR(glm::dot(plane, glm::vec4(0, 0, -5, 1)), 5.0f, 1e-4f);
  EXPECT_EQ(back_to_front(frame, list.blend_draws, plane), (std::vector<std::uint32_t>{0, 2, 1, 3}));
}

}  // namespace
}  // namespace kaskad::render
