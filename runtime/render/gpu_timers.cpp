#include "runtime/render/gpu_timers.h"

#include <epoxy/gl.h>

namespace kaskad::render {

void GpuTimers::begin_frame() {
  while (!open_.empty()) end(open_.back());  // a frame that stopped on an error
  last_ms_.fill(0.0);
  if (frames_++ >= 2) {  // frame 0's queries are garbage on llvmpipe, and it times uploads
    for (const Interval& i : intervals_) {
      GLuint64 ns = 0;
      glGetQueryObjectui64v(queries_[i.query].id(), GL_QUERY_RESULT, &ns);
      last_ms_[std::size_t(i.part)] += double(ns) * 1e-6;
    }
  }
  intervals_.clear();
  used_ = 0;
  depth_.fill(0);
}

void GpuTimers::start_interval(TimedPart part) {
  if (used_ == queries_.size()) queries_.push_back(gpu::make_query(GL_TIME_ELAPSED));
  intervals_.push_back({part, used_});
  glBeginQuery(GL_TIME_ELAPSED, queries_[used_++].id());
}

void GpuTimers::stop_interval() { glEndQuery(GL_TIME_ELAPSED); }

void GpuTimers::begin(TimedPart part) {
  if (depth_[std::size_t(part)]++ > 0) return;
  if (!open_.empty()) stop_interval();
  open_.push_back(part);
  start_interval(part);
}

void GpuTimers::end(TimedPart part) {
  int& depth = depth_[std::size_t(part)];
  if (depth == 0 || --depth > 0 || open_.empty() || open_.back() != part) return;
  stop_interval();
  open_.pop_back();
  if (!open_.empty()) start_interval(open_.back());
}

}  // namespace kaskad::render
