// content/scenes/terrain.json at its default settings: a 2 km terrain with a crate about 10 m
// from the camera. Sample-distribution splits (split_scheme auto, log over the visible
// receivers' depths) must give the crate's cascade at least 4x finer texels than S0's mixed
// split (lambda 0.5, the default before), with no more misclassified receivers against the
// Embree reference.
#include <gtest/gtest.h>

#include <cstdio>

#include "components/bounds.h"
#include "components/light.h"
#include "components/name.h"
#include "components/transform.h"
#include "runtime/app/player.h"
#include "runtime/reference/ray_tracer.h"
#include "runtime/reference/shadow_metrics.h"
#include "tests/render/player_fixture.h"

namespace kaskad {
namespace {

struct TerrainRun {
  float crate_depth = 0.0f;     ///< metres of view depth
  int crate_cascade = -1;       ///< the cascade whose depth range holds it
  float crate_texel = 0.0f;     ///< metres per texel of that cascade
  double misclassified_pct = 0.0;  ///< away from shadow edges
};

class TerrainTest : public PlayerTest {
 protected:
  static TerrainRun run(std::vector<std::string> sets) {
    TerrainRun out;
    sets.push_back("render.width=320");
    sets.push_back("render.height=180");
    auto scene = load_scene(content_dir() / "scenes" / "terrain.json", sets);
    EXPECT_TRUE(scene.ok()) << scene.error().to_string();
    if (!scene.ok()) return out;
    auto t = render_frames(*player_, *scene, {});
    EXPECT_TRUE(t.ok()) << t.error().to_string();
    if (!t.ok()) return out;
    const ShadowData& sh = t->last.shadow();
    EXPECT_TRUE(sh.light.valid());
    if (!sh.light.valid()) return out;
    ecs::Entity crate = ecs::kNullEntity;
    scene->world.view<Name>().each([&](ecs::Entity e, const Name& n) {
      if (n.value == "crate") crate = e;
    });
    EXPECT_TRUE(crate.valid());
    if (!crate.valid()) return out;
    const glm::vec3 c = scene->world.get<WorldBounds>(crate).box.center();
    out.crate_depth = -(t->last.camera.view * glm::vec4(c, 1.0f)).z;
    for (int i = 0; i < sh.cascade_count; ++i)
      if (out.crate_depth >= sh.splits[std::size_t(i)] &&
          out.crate_depth < sh.splits[std::size_t(i) + 1])
        out.crate_cascade = i;
    EXPECT_GE(out.crate_cascade, 0) << "the crate lies in no cascade";
    if (out.crate_cascade < 0) return out;
    out.crate_texel = sh.texel_size[std::size_t(out.crate_cascade)];
    const Image aov = player_->renderer->read_aovs();
    auto tracer = reference::RayTracer::build(*scene);
    EXPECT_TRUE(tracer.ok()) << tracer.error().to_string();
    if (!tracer.ok()) return out;
    const auto light = reference::reference_light(scene->world, sh.light);
    auto ref = tracer->shadow_reference(aov, light, {});
    EXPECT_TRUE(ref.ok());
    if (!ref.ok()) return out;
    auto m = reference::compare_shadows(aov, ref->image);
    EXPECT_TRUE(m.ok());
    if (m.ok()) out.misclassified_pct = m->outside_edges.misclassified_pct;
    return out;
  }
};

TEST_F(TerrainTest, AutoSplitsGiveTheNearCrateFinerTexels) {
  const TerrainRun before = run({"shadow.split_scheme=mixed"});
  const TerrainRun now = run({});
  std::printf("[ terrain crate ] %.1f m away: mixed (S0, lambda 0.5) cascade %d, %.4f m/texel, "
              "%.3f%% misclassified; auto cascade %d, %.4f m/texel, %.3f%% misclassified\n",
              double(now.crate_depth), before.crate_cascade, double(before.crate_texel),
              before.misclassified_pct, now.crate_cascade, double(now.crate_texel),
              now.misclassified_pct);
  ASSERT_GT(now.crate_texel, 0.0f);
  EXPECT_LE(now.crate_texel * 4.0f, before.crate_texel);
  EXPECT_LE(now.misclassified_pct, before.misclassified_pct);
}

}  // namespace
}  // namespace kaskad
