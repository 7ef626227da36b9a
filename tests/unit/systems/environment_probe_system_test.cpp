// EnvironmentProbeSystem: the schedule of every update mode (pure), the capture cameras against
// GL's cube-map face table, and the system on a world (centres, on_change, counters).
#include <gtest/gtest.h>

#include <bit>

#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/transform.h"
#include "runtime/assets/primitives.h"
#include "systems/environment_probe_system.h"
#include "systems/transform_system.h"

namespace kaskad {
namespace {

Reflector with(ProbeUpdate update, int faces_per_frame = 6, int every_n = 10) {
  Reflector r;
  r.update = update;
  r.faces_per_frame = faces_per_frame;
  r.every_n = every_n;
  if (update == ProbeUpdate::static_file) r.file = "env.hdr";
  return r;
}

// Frames on which a capture completed, over `frames` frames with a constant signature.
std::vector<std::uint64_t> completions(const Reflector& r, int frames, ProbeState& s) {
  std::vector<std::uint64_t> done;
  for (int k = 0; k < frames; ++k)
    if (schedule_probe(r, s, std::uint64_t(k), 42).swap) done.push_back(std::uint64_t(k));
  return done;
}

TEST(ProbeSchedule, EveryNCapturesOnMultiplesOfN) {
  ProbeState s;
  const auto done = completions(with(ProbeUpdate::every_n, 6, 10), 35, s);
  EXPECT_EQ(done, (std::vector<std::uint64_t>{0, 10, 20, 30}));
  EXPECT_EQ(s.captures, 4u);
  EXPECT_EQ(s.faces_rendered, 24u);
}

TEST(ProbeSchedule, EveryOneCapturesEveryFrame) {
  ProbeState s;
  const auto done = completions(with(ProbeUpdate::every_n, 6, 1), 5, s);
  EXPECT_EQ(done, (std::vector<std::uint64_t>{0, 1, 2, 3, 4}));
}

TEST(ProbeSchedule, FirstFrameCapturesOnce) {
  ProbeState s;
  EXPECT_EQ(completions(with(ProbeUpdate::first_frame), 50, s), (std::vector<std::uint64_t>{0}));
  EXPECT_EQ(s.faces_rendered, 6u);
}

TEST(ProbeSchedule, StaticFileLoadsOnceAndNeverCaptures) {
  ProbeState s;
  const Reflector r = with(ProbeUpdate::static_file);
  int loads = 0;
  for (int k = 0; k < 20; ++k) {
    const ProbeWork w = schedule_probe(r, s, std::uint64_t(k), std::uint64_t(k));
    loads += w.load;
    EXPECT_EQ(w.faces, 0);
    EXPECT_FALSE(w.swap);
    if (k == 0) {
      EXPECT_TRUE(w.load);
    }
  }
  EXPECT_EQ(loads, 1);
  EXPECT_TRUE(s.has_map);
  EXPECT_EQ(s.faces_rendered, 0u);
}

// Time slicing: every face exactly once per capture, at most faces_per_frame a frame (all six on
// the first capture, when nothing is shown yet), the visible buffer only ever changes to a buffer
// with all six faces done.
TEST(ProbeSchedule, TimeSlicingNeverShowsAPartialCube) {
  for (int per_frame = 1; per_frame <= 6; ++per_frame) {
    SCOPED_TRACE("faces_per_frame " + std::to_string(per_frame));
    const Reflector r = with(ProbeUpdate::every_n, per_frame, 10);
    ProbeState s;
    std::array<std::uint8_t, 2> written{};  // faces written into each buffer since it was shown
    int shown = -1;                         // buffer visible (-1: none yet)
    for (int k = 0; k < 60; ++k) {
      const int back = 1 - s.front;
      const bool first_capture = !s.has_map;
      const ProbeWork w = schedule_probe(r, s, std::uint64_t(k), 0);
      EXPECT_LE(std::popcount(unsigned(w.faces)), first_capture ? 6 : per_frame);
      if (k == 0) {
        EXPECT_TRUE(w.swap) << "the first capture is whole on its first frame";
      }
      EXPECT_EQ(written[std::size_t(back)] & w.faces, 0) << "a face rendered twice in one capture";
      written[std::size_t(back)] |= w.faces;
      if (w.swap) {
        EXPECT_EQ(s.front, back);
        EXPECT_EQ(written[std::size_t(back)], kAllFaces);
        shown = back;
        written[std::size_t(back)] = 0;  // the next capture into it starts afresh
      }
      if (shown >= 0) {
        EXPECT_EQ(s.front, shown) << "visible buffer changed without a full cube";
      }
      EXPECT_EQ(s.has_map, shown >= 0);
    }
    const int frames_per_capture = (6 + per_frame - 1) / per_frame;
    EXPECT_EQ(s.captures, 6u);  // started on 0, 10, ..., 50; all finish within 60 frames
    EXPECT_EQ(s.last_capture_frame, std::uint64_t(50 + frames_per_capture - 1));
  }
}

TEST(ProbeSchedule, EveryNShorterThanASlicedCaptureWaitsForIt) {
  // The first capture is whole on frame 0. Then 1 face per frame takes 6 frames and N = 2
  // triggers meanwhile: each capture completes and the next starts right after (2-7, 8-13,
  // 14-19), so the visible cube is always whole and captures never overlap.
  ProbeState s;
  const auto done = completions(with(ProbeUpdate::every_n, 1, 2), 20, s);
  EXPECT_EQ(done, (std::vector<std::uint64_t>{0, 7, 13, 19}));
}

TEST(ProbeSchedule, OnChangeCapturesWhenTheSignatureChanges) {
  const Reflector r = with(ProbeUpdate::on_change);
  ProbeState s;
  std::vector<std::uint64_t> done;
  for (int k = 0; k < 30; ++k) {
    const std::uint64_t signature = k < 12 ? 7 : (k < 20 ? 8 : 9);
    if (schedule_probe(r, s, std::uint64_t(k), signature).swap) done.push_back(std::uint64_t(k));
  }
  EXPECT_EQ(done, (std::vector<std::uint64_t>{0, 12, 20}));
}

TEST(ProbeSchedule, OnChangeDuringASlicedCaptureCapturesAgain) {
  const Reflector r = with(ProbeUpdate::on_change, 2);
  ProbeState s;
  std::vector<std::uint64_t> done;
  for (int k = 0; k < 12; ++k)
    if (schedule_probe(r, s, std::uint64_t(k), k == 3 ? 5 : 6).swap) done.push_back(std::uint64_t(k));
  // The first capture is whole on frame 0. Frame 3 sees signature 5: a sliced capture runs on
  // frames 3-5. Frame 4 sees 6 again while it runs: that requests another capture, which starts
  // when the running one completes and runs on frames 6-8.
  EXPECT_EQ(done, (std::vector<std::uint64_t>{0, 5, 8}));
}

// GL 4.5 table 8.19: for face f, direction = (major axis) with s = sc/|ma|, t = tc/|ma| mapped
// to [-1, 1]. Written out here independently of the system's lookAt table.
glm::vec3 gl_face_direction(int face, float s, float t) {
  switch (face) {
    case 0: return {1, -t, -s};
    case 1: return {-1, -t, s};
    case 2: return {s, 1, t};
    case 3: return {s, -1, -t};
    case 4: return {s, -t, 1};
    default: return {-s, -t, -1};
  }
}

TEST(ProbeCapture, FaceCamerasMatchGlCubeMapOrientation) {
  const glm::vec3 c(1.5f, -2.0f, 3.0f);
  const glm::mat4 proj = cube_face_projection(0.1f, 50.0f);
  for (int f = 0; f < 6; ++f) {
    const glm::mat4 vp = proj * cube_face_view(f, c);
    for (float s : {-0.7f, 0.0f, 0.4f})
      for (float t : {-0.5f, 0.0f, 0.8f}) {
        const glm::vec4 clip = vp * glm::vec4(c + 3.0f * gl_face_direction(f, s, t), 1.0f);
        ASSERT_GT(clip.w, 0.0f);
        EXPECT_NEAR(clip.x / clip.w, s, 1e-5f) << "face " << f;
        EXPECT_NEAR(clip.y / clip.w, t, 1e-5f) << "face " << f;
      }
    // Rotation only: a proper rotation (no mirror, so culling stays back-face).
    EXPECT_NEAR(glm::determinant(glm::mat3(cube_face_view(f, c))), 1.0f, 1e-5f);
  }
}

struct ProbeWorld {
  ecs::World w;
  AssetStore assets;
  ecs::Entity mirror, near_box, far_box;
  ProbeWorld(ProbeUpdate update) {
    const MeshId box = assets.add_mesh(make_primitive(PrimitiveShape::box, 8));
    auto add = [&](glm::vec3 at) {
      const ecs::Entity e = w.create();
      w.emplace<Transform>(e, Transform{at, {1, 0, 0, 0}, glm::vec3(1.0f)});
      MeshRenderer mr;
      mr.mesh = box;
      w.emplace<MeshRenderer>(e, mr);
      w.emplace<Material>(e);
      return e;
    };
    mirror = add({0, 0, 0});
    near_box = add({3, 0, 0});
    far_box = add({500, 0, 0});
    Reflector r;
    r.update = update;
    r.far = 20.0f;
    w.emplace<Reflector>(mirror, r);
    update_transforms(w, assets);
  }
  ProbeData frame(std::uint64_t k) {
    update_transforms(w, assets);
    return update_environment_probes(w, k);
  }
  ProbeData frame_with(std::uint64_t k, int bounces) {
    update_transforms(w, assets);
    return update_environment_probes(w, k, /*commit=*/true, bounces);
  }
};

TEST(EnvironmentProbeSystem, StaticSceneNeverRecapturesOnChange) {
  ProbeWorld pw(ProbeUpdate::on_change);
  int captures = 0;
  for (int k = 0; k < 20; ++k) captures += pw.frame(std::uint64_t(k)).captures_this_frame;
  EXPECT_EQ(captures, 1);
  EXPECT_EQ(pw.w.get<ProbeState>(pw.mirror).captures, 1u);
}

TEST(EnvironmentProbeSystem, MovedObjectInRangeTriggersACapture) {
  ProbeWorld pw(ProbeUpdate::on_change);
  pw.frame(0);
  pw.frame(1);
  pw.w.get<Transform>(pw.near_box).translation.y += 0.5f;
  EXPECT_EQ(pw.frame(2).captures_this_frame, 1);
  EXPECT_EQ(pw.frame(3).captures_this_frame, 0);
  pw.w.get<Material>(pw.near_box).base_color = glm::vec4(1, 0, 0, 1);
  EXPECT_EQ(pw.frame(4).captures_this_frame, 1);
  // Out of range (500 m away, far = 20 m): no capture.
  pw.w.get<Transform>(pw.far_box).translation.y += 3.0f;
  EXPECT_EQ(pw.frame(5).captures_this_frame, 0);
  // Excluded layers do not count either.
  pw.w.get<Reflector>(pw.mirror).exclude_layers = 1u << 4;
  pw.w.get<MeshRenderer>(pw.near_box).layer = 4;
  pw.frame(6);  // the exclusion itself changes what is in range
  pw.w.get<Transform>(pw.near_box).translation.z += 1.0f;
  EXPECT_EQ(pw.frame(7).captures_this_frame, 0);
  // The reflector moving moves the capture centre: re-capture.
  pw.w.get<Transform>(pw.mirror).translation.x += 0.25f;
  EXPECT_EQ(pw.frame(8).captures_this_frame, 1);
  EXPECT_EQ(pw.w.get<ProbeState>(pw.mirror).captures, 5u);
}

TEST(EnvironmentProbeSystem, PlanningDoesNotAdvanceState) {
  ProbeWorld pw(ProbeUpdate::first_frame);
  const ProbeData planned = update_environment_probes(pw.w, 0, /*commit=*/false);
  EXPECT_EQ(planned.faces_this_frame, 6);
  EXPECT_FALSE(pw.w.has<ProbeState>(pw.mirror));
  EXPECT_EQ(pw.frame(0).faces_this_frame, 6);
  EXPECT_EQ(pw.frame(1).faces_this_frame, 0);
}

// A reflector destroyed and another created in its entity slot: the renderer's maps are named
// by index and generation, so the new probe never inherits the old one's maps; it captures all
// six faces on its first frame.
TEST(EnvironmentProbeSystem, AReflectorInAReusedSlotGetsAFreshCapture) {
  ProbeWorld pw(ProbeUpdate::every_n);
  pw.w.get<Reflector>(pw.mirror).every_n = 100;
  const ProbeData first = pw.frame(0);
  ASSERT_EQ(first.probes.size(), 1u);
  EXPECT_EQ(first.faces_this_frame, 6);
  EXPECT_EQ(pw.frame(1).faces_this_frame, 0);
  const ProbeHandle old_handle = first.probes[0].job.handle;
  ASSERT_TRUE(old_handle.valid());

  const ecs::Entity old_entity = pw.mirror;
  pw.w.destroy(old_entity);
  const ecs::Entity reused = pw.w.create();
  ASSERT_EQ(reused.index, old_entity.index);  // the precondition of this test: the slot is reused
  ASSERT_NE(reused.generation, old_entity.generation);
  pw.w.emplace<Transform>(reused, Transform{{0, 1, 0}, {1, 0, 0, 0}, glm::vec3(1.0f)});
  MeshRenderer mr;
  mr.mesh = pw.w.get<MeshRenderer>(pw.near_box).mesh;
  pw.w.emplace<MeshRenderer>(reused, mr);
  Reflector r;
  r.update = ProbeUpdate::every_n;
  r.every_n = 100;
  pw.w.emplace<Reflector>(reused, r);

  const ProbeData next = pw.frame(2);
  ASSERT_EQ(next.probes.size(), 1u);
  EXPECT_EQ(next.probes[0].entity, reused);
  EXPECT_NE(next.probes[0].job.handle, old_handle);
  EXPECT_EQ(next.probes[0].job.handle, pw.w.get<ProbeState>(reused).handle);
  EXPECT_EQ(next.faces_this_frame, 6);  // a fresh capture (frame 2 is no multiple of 100)
  EXPECT_EQ(next.captures_this_frame, 1);
  EXPECT_TRUE(next.probes[0].has_map);
}

TEST(EnvironmentProbeSystem, CentreIsTheBoundsCentreUnlessGiven) {
  ProbeWorld pw(ProbeUpdate::first_frame);
  // A mesh whose local bounds are centred at (1, 0, 0): the pivot sits off the geometric centre.
  MeshData shifted = make_primitive(PrimitiveShape::box, 8);
  for (glm::vec3& p : shifted.positions) p.x += 1.0f;
  shifted.compute_bounds();
  pw.w.get<MeshRenderer>(pw.mirror).mesh = pw.assets.add_mesh(std::move(shifted));
  pw.w.get<Transform>(pw.mirror).translation = {2, 1, 0};
  const ProbeData d = pw.frame(0);
  ASSERT_EQ(d.probes.size(), 1u);
  EXPECT_NEAR(d.probes[0].job.center.x, 3.0f, 1e-5f);  // bounds centre, not the pivot (2, 1, 0)
  EXPECT_NEAR(d.probes[0].job.center.y, 1.0f, 1e-5f);
  EXPECT_TRUE(pw.w.get<ProbeState>(pw.mirror).warned_off_centre);
  pw.w.get<Reflector>(pw.mirror).has_center = true;
  pw.w.get<Reflector>(pw.mirror).center = {7, 8, 9};
  EXPECT_EQ(pw.frame(1).probes[0].job.center, glm::vec3(7, 8, 9));
}

// render.probe_bounces: bounce rounds run only where they change something, a first capture
// with at least one other probe capturing all six faces beside it.
TEST(ProbeRounds, OnlyFirstCapturesInCompanyGetBounceRounds) {
  EXPECT_EQ(probe_capture_rounds(2, true, 2), 2);
  EXPECT_EQ(probe_capture_rounds(5, true, 4), 4);
  EXPECT_EQ(probe_capture_rounds(1, true, 3), 1);   // alone: it never sees itself
  EXPECT_EQ(probe_capture_rounds(3, false, 3), 1);  // re-captures read maps that have bounced
  EXPECT_EQ(probe_capture_rounds(0, false, 2), 1);
}

// The buffers of a job's rounds, for every round count and target: the last round writes the
// target (the map then shown), each round writes the other buffer than the one before, and a
// capture in round r reads the buffer the probe wrote in round r - 1, never the one it writes in
// round r. A job of one round keeps today's rule: while it swaps, captures see the old front.
TEST(ProbeRounds, EachRoundReadsThePreviousRoundsBuffer) {
  for (int rounds = 1; rounds <= kMaxProbeBounces; ++rounds)
    for (int target = 0; target < 2; ++target) {
      SCOPED_TRACE(std::to_string(rounds) + " rounds, target " + std::to_string(target));
      render::ProbeJob job;
      job.faces = kAllFaces;
      job.rounds = rounds;
      job.target = job.visible = target;
      EXPECT_EQ(render::capture_buffer(job, rounds), target);
      EXPECT_EQ(render::probe_read_buffer(job, 0), target);  // the main view: the new map
      for (int r = 1; r <= rounds; ++r) {
        EXPECT_NE(render::probe_read_buffer(job, r), render::capture_buffer(job, r));
        if (r > 1) {
          EXPECT_EQ(render::probe_read_buffer(job, r), render::capture_buffer(job, r - 1));
        }
      }
    }
  render::ProbeJob sliced;  // a time-sliced capture that has not finished: reads see the front
  sliced.faces = 0x3;
  sliced.target = 1;
  sliced.visible = 0;
  for (int r = 0; r <= 3; ++r) EXPECT_EQ(render::probe_read_buffer(sliced, r), 0);
}

// Two mirrors (the reflections demo's every_n 10, one of them time-sliced): their first captures
// run in `bounces` rounds, counted in the face counters; round 1 writes each probe's back buffer
// and the last one the buffer shown from then on. Later captures are single rounds again.
TEST(EnvironmentProbeSystem, FirstCapturesOfTwoMirrorsRunInBounceRounds) {
  for (int bounces = 1; bounces <= kMaxProbeBounces; ++bounces) {
    SCOPED_TRACE("probe_bounces " + std::to_string(bounces));
    ProbeWorld pw(ProbeUpdate::every_n);
    Reflector sliced;
    sliced.update = ProbeUpdate::every_n;
    sliced.faces_per_frame = 2;
    pw.w.emplace<Reflector>(pw.near_box, sliced);
    const ProbeData first = pw.frame_with(0, bounces);
    ASSERT_EQ(first.probes.size(), 2u);
    EXPECT_EQ(first.rounds, bounces);
    EXPECT_EQ(first.faces_this_frame, 12 * bounces);
    EXPECT_EQ(first.captures_this_frame, 2);
    EXPECT_EQ(first.faces_total, 12u * std::uint64_t(bounces));
    for (const ProbeData::Entry& p : first.probes) {
      const ProbeState& s = pw.w.get<ProbeState>(p.entity);
      EXPECT_EQ(p.job.rounds, bounces);
      EXPECT_EQ(p.job.faces, kAllFaces);
      EXPECT_EQ(s.faces_rendered, 6u * std::uint64_t(bounces));
      EXPECT_EQ(s.captures, 1u);
      EXPECT_EQ(p.job.visible, s.front);
      EXPECT_EQ(render::capture_buffer(p.job, bounces), s.front);
      EXPECT_EQ(render::capture_buffer(p.job, 1), 1 - ProbeState{}.front);  // the back buffer
    }
    // Frame 10: the whole re-capture and the sliced one's first two faces, one round each.
    for (std::uint64_t k = 1; k < 10; ++k) EXPECT_EQ(pw.frame_with(k, bounces).faces_this_frame, 0);
    const ProbeData again = pw.frame_with(10, bounces);
    EXPECT_EQ(again.rounds, 1);
    EXPECT_EQ(again.faces_this_frame, 6 + 2);
  }
}

// A reflector added later captures for the first time while an older one re-captures: both
// take part in the rounds; the older one's round 1 reads and leaves alone the map it showed.
TEST(EnvironmentProbeSystem, ARecaptureBesideAFirstCaptureKeepsItsShownMapForRoundOne) {
  for (int bounces = 2; bounces <= kMaxProbeBounces; ++bounces) {
    SCOPED_TRACE("probe_bounces " + std::to_string(bounces));
    ProbeWorld pw(ProbeUpdate::every_n);
    pw.w.get<Reflector>(pw.mirror).every_n = 1;
    EXPECT_EQ(pw.frame_with(0, bounces).rounds, 1);  // alone
    const int shown = pw.w.get<ProbeState>(pw.mirror).front;
    Reflector added;
    added.update = ProbeUpdate::first_frame;
    pw.w.emplace<Reflector>(pw.near_box, added);
    const ProbeData d = pw.frame_with(1, bounces);
    EXPECT_EQ(d.rounds, bounces);
    const ProbeData::Entry* old = d.find(pw.mirror);
    ASSERT_NE(old, nullptr);
    EXPECT_EQ(old->job.rounds, bounces);
    EXPECT_NE(render::capture_buffer(old->job, 1), shown);
    EXPECT_EQ(render::probe_read_buffer(old->job, 1), shown);
    EXPECT_EQ(pw.w.get<ProbeState>(pw.mirror).front, render::capture_buffer(old->job, bounces));
  }
}

}  // namespace
}  // namespace kaskad
