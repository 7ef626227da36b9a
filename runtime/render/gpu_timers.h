// GPU time of the parts of a frame, from GL_TIME_ELAPSED queries. Parts may lie inside others
// (the prefiltering inside the probe captures): only one elapsed query can be active, so the
// outer part's query is ended when an inner part begins and a new one started when it ends,
// and each part's time is its own, without the parts inside it. A part may be timed in several
// intervals a frame; its time is their sum. Results are read a frame late.
// (GL_TIMESTAMP pairs would nest freely, but llvmpipe stamps them when the command is issued,
// not when its draws run, so they read about 0.)
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "runtime/gpu/gl_handles.h"

namespace kaskad::render {

enum class TimedPart : int {
  shadow_depth,     ///< the depth pass of every shadow view
  lom,              ///< S1's depth peels and occlusion factors (LomPass)
  moments,          ///< vsm/evsm moments and their blur (MomentsPass)
  probe_captures,   ///< reflection probe faces (without their prefiltering)
  probe_prefilter,  ///< pbr prefiltering and SH projection (probes' and the environment map's)
  forward,          ///< the main view
  count
};
inline constexpr std::size_t kTimedParts = std::size_t(TimedPart::count);

class GpuTimers {
 public:
  /// Ends the frame's timing and reads the frame before's results (see last()).
  void begin_frame();
  /// An interval of `part`. A begin/end pair of the part already open counts once.
  void begin(TimedPart part);
  void end(TimedPart part);
  /// Milliseconds per part (its own time, without parts timed inside it) of the frame before
  /// the last begin_frame(); 0 for parts not timed then, and for everything until two frames
  /// have been timed (llvmpipe's first queries of a context read garbage, and the first frame
  /// times uploads).
  const std::array<double, kTimedParts>& last() const { return last_ms_; }

 private:
  void start_interval(TimedPart part);
  void stop_interval();
  struct Interval {
    TimedPart part;
    std::size_t query;  // index into queries_
  };
  std::vector<gpu::Query> queries_;
  std::size_t used_ = 0;
  std::vector<Interval> intervals_;
  std::vector<TimedPart> open_;  // parts begun and not ended, innermost last
  std::array<int, kTimedParts> depth_{};
  std::array<double, kTimedParts> last_ms_{};
  int frames_ = 0;
};

}  // namespace kaskad::render
