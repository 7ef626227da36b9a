// Internal to runtime/app: what the parts of `kaskad play` share. The playback file's reader
// (playback_file.cpp) and its JSON Schema (playback_schema.cpp) take their limits from here;
// the timeline (playback_timeline.cpp) applies events and poses for the runner
// (playback_runner.cpp), whose expectations are in playback_checks.cpp; shards and the command
// are play_command.cpp. The public API is playback.h.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "components/limits.h"
#include "components/transform.h"
#include "runtime/app/playback.h"
#include "runtime/assets/scene.h"
#include "runtime/ecs/world.h"
#include "runtime/result/result.h"

namespace kaskad::playback_detail {

// --- The file format's limits: the reader refuses a value outside them (naming the range) and
// the schema states them, both from these declarations.

inline constexpr int kFormatVersion = 1;
inline constexpr int kMaxFrames = 1000000;

/// The closed range [lo, hi] a number of a playback file must lie in.
template <class T>
struct Bounds {
  T lo, hi;
};

inline constexpr Bounds<int> kFrameCount{1, kMaxFrames};
inline constexpr Bounds<float> kSize{1.0f, 16384.0f};  ///< pixels, whole numbers
inline constexpr Bounds<float> kDt{1e-6f, 10.0f};     ///< seconds per frame
inline constexpr Bounds<float> kKeyTime{0.0f, 1.0e6f};  ///< seconds
inline constexpr Bounds<float> kCoordinate{-kMaxCoordinate, kMaxCoordinate};
/// Quaternion components before normalising (a unit quaternion's lie in [-1, 1]).
inline constexpr Bounds<float> kQuaternion{-2.0f, 2.0f};
inline constexpr Bounds<float> kFovY{0.01f, 179.0f};  ///< degrees
/// Repeats and counts over a run: an event's and capture's "every", flat_resources' period, the
/// probe capture count.
inline constexpr Bounds<int> kRepeat{0, kMaxFrames};
inline constexpr Bounds<float> kChannelDifference{0.0f, 1.0f};  ///< golden thresholds
inline constexpr Bounds<float> kPercent{0.0f, 100.0f};
inline constexpr Bounds<float> kFlicker{0.0f, 1.0f};  ///< reference::StabilityStats::flicker
inline constexpr Bounds<int> kCompiles{0, 100000};
inline constexpr Bounds<int> kGlErrors{0, 1000000};
inline constexpr Bounds<float> kRatio{0.0f, 1.0e6f};
inline constexpr Bounds<float> kRssGrowthMib{0.0f, 1.0e6f};
inline constexpr Bounds<int> kGlObjectGrowth{0, 1000000};

inline const std::vector<std::pair<const char*, Interpolation>> kInterpolations = {
    {"linear", Interpolation::linear}, {"catmull_rom", Interpolation::catmull_rom}};

// --- The timeline on a loaded scene (playback_timeline.cpp).

/// The first entity named `name`, or kNullEntity.
ecs::Entity find_named(const ecs::World& w, const std::string& name);
/// Moves entity e to `pose` of `track`. `start` is the entity's transform at load: relative
/// tracks move from it along its axes. An entity the timeline removed is left alone.
void apply_pose(ecs::World& w, ecs::Entity e, const Track& track, const PoseKey& pose,
                const Transform& start);
/// One timeline event of playback file `file` on a loaded scene.
Status apply_event(Scene& scene, const SetEvent& ev, const std::filesystem::path& file);

/// "prefix_NNNN.ext": the names of a run's per-frame outputs and of golden images.
inline std::string frame_name(const char* prefix, int f, const char* ext) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%s_%04d.%s", prefix, f, ext);
  return buf;
}

}  // namespace kaskad::playback_detail
