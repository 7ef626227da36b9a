// Internal to runtime/app: the expectations of a playback file, one function per kind. The
// runner (playback_runner.cpp) calls the per-frame ones in frame order and check_run() once the
// last frame is done; each adds what did not hold to a Failures and returns an error only when
// the check itself cannot be made (an image that cannot be read, a tracer that cannot be built).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "runtime/app/playback.h"
#include "runtime/app/stability.h"
#include "runtime/assets/scene.h"
#include "runtime/render/renderer.h"
#include "runtime/result/result.h"
#include "systems/frame.h"

namespace kaskad::playback_detail {

/// The failed expectations of one playback file, in the order they were found.
struct Failures {
  std::string file;
  std::vector<PlayFailure> list;
  /// frame -1: the whole run.
  void add(int frame, const std::string& message) { list.push_back({file, frame, message}); }
};

// --- Per frame.

/// expect.golden on captured frame f (written to `png`): with `update`, writes the golden when
/// its pixels differ; else compares, writing OUT/diff_NNNN.png into `out` when too many differ.
Status check_golden(const Playback& pb, int f, const std::filesystem::path& png,
                    const std::filesystem::path& out, bool update, Failures& failures);

/// expect.misclassified_pct on frame f: the AOV's shadowed receivers away from edges against
/// the ray-traced reference of the light it shows. Returns the measured %, -1 when the frame
/// has no shadowed light (a failure).
Result<double> check_misclassified(const Playback& pb, int f, const Scene& scene,
                                   render::Renderer& renderer, const FrameReport& report,
                                   Failures& failures);

/// What the flicker expectation gathers over its frame range.
struct FlickerSamples {
  StabilityPoints points;                ///< fixed receiver points, found on the first frame
  std::vector<std::vector<float>> values;  ///< their visibility, one row per frame
};
/// expect.flicker: samples frame f when it lies in the range, and checks the bounds on its
/// last frame.
Status check_flicker(const Playback& pb, int f, render::Renderer& renderer,
                     const FrameReport& report, FlickerSamples& samples, Failures& failures);

/// Resident memory and live GL objects at the frames expect.flat_resources compares.
struct ResourceSamples {
  double rss_warm = 0.0, rss_max_after = 0.0, rss_end = 0.0;  ///< MiB
  long gl_warm = 0, gl_max_after = 0;
};
/// expect.flat_resources' sampling of frame f (with `rss` MiB resident and `gl_objects` live),
/// printing a line at the frames it compares.
void sample_resources(const Playback& pb, int f, double rss, long gl_objects,
                      ResourceSamples& samples);

// --- Over the whole run.

/// What a run measured that the whole-run expectations read.
struct RunRecord {
  int compiles = 0;   ///< programs compiled or loaded after pre-warm
  int gl_errors = 0;  ///< GL debug errors during the run
  std::uint64_t probe_captures = 0;      ///< completed over the run, all probes
  std::vector<int> probe_capture_frames;  ///< frames on which a capture completed
  std::vector<double> frame_ms;           ///< by frame index
  ResourceSamples resources;
};

void check_compiles(const Playback& pb, const RunRecord& run, Failures& failures);
void check_gl_errors(const Playback& pb, const RunRecord& run, Failures& failures);
void check_probe_captures(const ProbeExpect& q, const RunRecord& run, Failures& failures);
void check_frame_time_ratio(const RatioExpect& q, const RunRecord& run, Failures& failures);
void check_flat_resources(const FlatExpect& q, const RunRecord& run, Failures& failures);

/// Every whole-run expectation `pb` has, in the order above.
void check_run(const Playback& pb, const RunRecord& run, Failures& failures);

}  // namespace kaskad::playback_detail
