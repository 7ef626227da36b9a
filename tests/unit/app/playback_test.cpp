// Playback files: parsing, errors that name the file and the JSON path, and the pose of a track
// at any time (linear, Catmull-Rom through the keys, slerped rotations).
#include <gtest/gtest.h>

#include <glm/gtc/quaternion.hpp>

#include "components/transform.h"
#include "runtime/app/playback.h"

namespace kaskad {
namespace {

Result<Playback> parse(const std::string& text) { return parse_playback(text, "dir/test.json"); }

void expect_error(const std::string& text, const std::vector<std::string>& parts) {
  auto r = parse(text);
  ASSERT_FALSE(r.ok()) << text;
  const std::string msg = r.error().to_string();
  for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
}

TEST(Playback, AFullFileParses) {
  auto pb = parse(R"({"kaskad_playback": 1, "scene": "../scenes/default.json", "size": [320, 180],
    "frames": 20, "dt": 0.1, "set": ["shadow.cascade_count=2"],
    "camera": {"interpolation": "catmull_rom", "keys": [{"t": 0, "position": [0, 1, 5], "look_at": [0, 0, 0]},
                                                      {"t": 1, "position": [2, 1, 5], "fov_y_deg": 30}]},
    "timeline": [{"t": 0.5, "set": "shadow.fit_mode=crop"}, {"frame": 2, "set": "sun.light.intensity=2"},
                 {"entity": "box", "keys": [{"t": 0, "move": [0, 0, 0]}, {"t": 1, "move": [1, 0, 0]}]}],
    "capture": {"frames": [19, 0, 0], "every": 10, "aovs": true},
    "expect": {"golden": {"fail_percent": 1}, "misclassified_pct": {"frames": [0], "max": 0.5},
               "flicker": {"from": 0, "to": 19, "max_changed_pct": 0,
                           "within": {"min": [-1, 0, -1], "max": [1, 2, 1]}}, "compiles_after_prewarm": 0,
               "probe_captures": {"count": 2, "frames": [0, 10]}, "gl_errors": 0,
               "frame_time_ratio": {"a": [1, 9], "b": [10, 19], "max": 2}}})");
  ASSERT_TRUE(pb.ok()) << pb.error().to_string();
  EXPECT_EQ(pb->scene, std::filesystem::path("dir/../scenes/default.json"));
  EXPECT_EQ(pb->width, 320);
  EXPECT_EQ(pb->frames, 20);
  ASSERT_EQ(pb->events.size(), 2u);
  EXPECT_EQ(pb->events[0].frame, 2);  // sorted by frame
  EXPECT_EQ(pb->events[1].frame, 5);  // t 0.5 at dt 0.1
  ASSERT_EQ(pb->tracks.size(), 1u);
  EXPECT_TRUE(pb->tracks[0].relative);
  EXPECT_EQ(pb->capture, (std::vector<int>{0, 10, 19}));
  EXPECT_EQ(pb->golden->dir, std::filesystem::path("dir/goldens/test"));
  EXPECT_EQ(pb->probes->frames, (std::vector<int>{0, 10}));
  ASSERT_TRUE(pb->flicker && pb->flicker->within);
  EXPECT_EQ(pb->flicker->within->max, glm::vec3(1, 2, 1));
}

TEST(Playback, AFileMayNameItsSchema) {
  auto pb = parse(R"({"$schema": "../docs/reference/playback.schema.json", "scene": "a.json"})");
  EXPECT_TRUE(pb.ok()) << pb.error().to_string();
}

TEST(Playback, ErrorsNameTheFileThePathAndTheValidKeys) {
  expect_error(R"({"scene": "a.json", "frames": 0})", {"dir/test.json", "/frames", "[1, 1000000]"});
  expect_error(R"({"scene": "a.json", "speed": 2})", {"/speed", "valid keys here", "frames"});
  expect_error(R"({"frames": 2})", {"/scene"});
  expect_error(R"({"scene": "a.json", "frames": 4, "timeline": [{"frame": 9, "set": "a=1"}]})",
               {"/timeline/0/frame", "[0, 3]"});
  expect_error(R"({"scene": "a.json", "timeline": [{"frame": 0, "t": 0, "set": "a=1"}]})",
               {"/timeline/0", "exactly one of frame and t"});
  expect_error(R"({"scene": "a.json", "camera": {"keys": [{"t": 1, "position": [0,0,0]}, {"t": 1, "position": [1,0,0]}]}})",
               {"/camera/keys/1/t", "increase"});
  expect_error(R"({"scene": "a.json", "camera": {"keys": [{"t": 0, "position": [0,0,0], "look_at": [0,0,0]}]}})",
               {"/camera/keys/0/look_at", "own position"});
  expect_error(R"({"scene": "a.json", "camera": {"keys": [{"t": 0, "move": [0,0,0]}, {"t": 1, "position": [1,0,0]}]}})",
               {"/camera/keys/1/position", "all use position or all move"});
  expect_error(R"({"scene": "a.json", "expect": {"golden": {}}})", {"/expect/golden", "capture"});
  expect_error(R"({"scene": "a.json", "expect": {"flicker": {"from": 0, "to": 0, "max": 0}}})",
               {"/expect/flicker/to"});
  expect_error(R"({"scene": "a.json", "frames": 6, "expect": {"flicker": {"to": 5, "max": 0, "within": {"min": [0, 0, 0], "max": [1, -1, 1]}}}})",
               {"/expect/flicker/within/max", "at least min's"});
  expect_error(R"({"scene": "a.json", "frames": 6, "expect": {"flicker": {"to": 5, "max": 0, "within": {"min": [0, 0, 0]}}}})",
               {"/expect/flicker/within", "min and max"});
  expect_error(R"({"scene": "a.json",)", {"dir/test.json", "line 1", "malformed JSON"});
  expect_error(R"({"scene": "a.json", "frames": 1e999})", {"dir/test.json"});
}

TEST(Playback, EventsSetAddOrRemoveAndRepeat) {
  auto pb = parse(R"({"scene": "a.json", "frames": 10, "timeline": [
    {"frame": 1, "add": {"name": "crate", "primitive": {"shape": "box"}}},
    {"frame": 2, "remove": "crate"},
    {"frame": 3, "every": 3, "set": "shadow.filter=none"}]})");
  ASSERT_TRUE(pb.ok()) << pb.error().to_string();
  ASSERT_EQ(pb->events.size(), 5u);  // 1, 2, then 3, 6, 9
  EXPECT_TRUE(pb->events[0].add);
  EXPECT_EQ(pb->events[1].remove, "crate");
  EXPECT_EQ(pb->events[4].frame, 9);
  EXPECT_EQ(pb->events[4].assignment, "shadow.filter=none");
  expect_error(R"({"scene": "a.json", "timeline": [{"frame": 0, "set": "a=1", "remove": "b"}]})",
               {"/timeline/0", "one of set"});
  expect_error(R"({"scene": "a.json", "timeline": [{"frame": 0, "add": 3}]})",
               {"/timeline/0/add", "entity block"});
}

TEST(Playback, TracksInterpolateLinearlyOrThroughTheKeys) {
  Track t;
  t.keys.push_back({.t = 0.0, .position = glm::vec3(0, 0, 0), .scale = glm::vec3(1)});
  t.keys.push_back({.t = 1.0, .position = glm::vec3(2, 0, 0)});
  t.keys.push_back({.t = 2.0, .position = glm::vec3(2, 2, 0), .scale = glm::vec3(3)});
  EXPECT_EQ(*sample_track(t, -1.0).position, glm::vec3(0, 0, 0));  // before the first key
  EXPECT_EQ(*sample_track(t, 5.0).position, glm::vec3(2, 2, 0));   // after the last
  EXPECT_EQ(*sample_track(t, 0.5).position, glm::vec3(1, 0, 0));
  EXPECT_EQ(*sample_track(t, 1.0).scale, glm::vec3(2));  // between the keys that have a scale
  t.interpolation = Interpolation::catmull_rom;
  for (double k : {0.0, 1.0, 2.0})  // through every key
    EXPECT_LT(glm::length(*sample_track(t, k).position - *t.keys[std::size_t(k)].position), 1e-6f);
  // Off the straight line between two keys: the spline bends towards the next key.
  EXPECT_GT(sample_track(t, 1.5).position->x, 2.0f);
}

TEST(Playback, RotationsSlerpAndLookAtAimsTheCamera) {
  Track t;
  t.keys.push_back({.t = 0.0, .position = glm::vec3(0, 0, 5), .look_at = glm::vec3(0, 0, 0)});
  t.keys.push_back({.t = 1.0, .position = glm::vec3(5, 0, 0), .look_at = glm::vec3(0, 0, 0)});
  const PoseKey mid = sample_track(t, 0.5);
  ASSERT_TRUE(mid.rotation);
  const glm::vec3 forward = *mid.rotation * glm::vec3(0, 0, -1);
  EXPECT_NEAR(forward.x, -std::sqrt(0.5f), 1e-5f);  // halfway between looking -z and -x
  EXPECT_NEAR(forward.z, -std::sqrt(0.5f), 1e-5f);
  EXPECT_NEAR(glm::length(*mid.rotation), 1.0f, 1e-6f);
}

TEST(Playback, ShardsSplitFilesDeterministically) {
  EXPECT_EQ(shard_files(7, 0, 3), (std::vector<std::size_t>{0, 3, 6}));
  EXPECT_EQ(shard_files(7, 2, 3), (std::vector<std::size_t>{2, 5}));
  EXPECT_EQ(shard_files(2, 0, 1), (std::vector<std::size_t>{0, 1}));
}

}  // namespace
}  // namespace kaskad
