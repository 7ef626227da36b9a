// The caster-face rule (caster_face_blocks(), caster_cull()): the table written out in full,
// and the shadow pass's GL culling reading as the same rule.
#include "components/shadow_settings.h"

#include <gtest/gtest.h>

namespace kaskad {
namespace {

constexpr CullMode kModes[] = {CullMode::back, CullMode::front, CullMode::none};

TEST(CasterFaces, EveryCaseOfTheRule) {
  struct Case {
    CullMode cull;
    bool double_sided, front_faces_light, blocks;
  };
  // The rule's wording, row by row (components/shadow_settings.h).
  constexpr Case kTable[] = {
      // Single-sided: back culls the face turned away from the light...
      {CullMode::back, false, true, true},
      {CullMode::back, false, false, false},
      // ... front the face turned towards it, none neither.
      {CullMode::front, false, true, false},
      {CullMode::front, false, false, true},
      {CullMode::none, false, true, true},
      {CullMode::none, false, false, true},
      // Double-sided: both faces, whatever the light's cull.
      {CullMode::back, true, true, true},
      {CullMode::back, true, false, true},
      {CullMode::front, true, true, true},
      {CullMode::front, true, false, true},
      {CullMode::none, true, true, true},
      {CullMode::none, true, false, true},
  };
  for (const Case& c : kTable)
    EXPECT_EQ(caster_face_blocks(c.cull, c.double_sided, c.front_faces_light), c.blocks)
        << "cull " << enum_names(CullMode{})[std::size_t(c.cull)] << ", double_sided "
        << c.double_sided << ", front faces the light " << c.front_faces_light;
}

// The shadow pass culls GL faces by caster_cull(): with GL_BACK culled, a front face (the one
// facing the light in the map) is drawn, with GL_FRONT a back face. Drawn must mean blocks.
TEST(CasterFaces, ThePassesCullingIsTheRule) {
  for (const CullMode cull : kModes)
    for (const bool double_sided : {false, true})
      for (const bool front : {false, true}) {
        const CullMode gl = caster_cull(cull, double_sided);
        const bool drawn = gl == CullMode::none || (gl == CullMode::back) == front;
        EXPECT_EQ(drawn, caster_face_blocks(cull, double_sided, front));
      }
  // Double-sided materials are drawn without culling, single-sided ones with the light's.
  for (const CullMode cull : kModes) {
    EXPECT_EQ(caster_cull(cull, true), CullMode::none);
    EXPECT_EQ(caster_cull(cull, false), cull);
  }
}

// Every face blocks from one side at least: no cull mode loses a caster entirely, and a closed
// mesh (every ray through it crosses a face of each orientation) blocks under any of them.
TEST(CasterFaces, SomeFaceOfAClosedMeshAlwaysBlocks) {
  for (const CullMode cull : kModes)
    for (const bool double_sided : {false, true})
      EXPECT_TRUE(caster_face_blocks(cull, double_sided, true) ||
                  caster_face_blocks(cull, double_sided, false));
}

static_assert(caster_face_blocks(CullMode::back, false, true));
static_assert(!caster_face_blocks(CullMode::back, false, false));

}  // namespace
}  // namespace kaskad
