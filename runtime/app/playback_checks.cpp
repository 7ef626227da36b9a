#include "runtime/app/playback_checks.h"

#include <algorithm>
#include <cstdio>

#include "components/light.h"
#include "components/transform.h"
#include "runtime/app/playback_internal.h"
#include "runtime/assets/image_io.h"
#include "runtime/core/median.h"
#include "runtime/reference/ray_tracer.h"
#include "runtime/reference/shadow_metrics.h"

namespace kaskad::playback_detail {

namespace fs = std::filesystem;

Status check_golden(const Playback& pb, int f, const fs::path& png, const fs::path& out,
                    bool update, Failures& failures) {
  const GoldenExpect& g = *pb.golden;
  const fs::path golden = g.dir / frame_name("frame", f, "png");
  if (update) {
    std::error_code ec;
    fs::create_directories(g.dir, ec);
    auto img = load_image(png);
    if (!img) return img.error();
    auto old = load_image(golden);
    const bool same = old && old->pixels == img->pixels && old->width == img->width;
    if (!same) {
      KASKAD_TRY(save_image(golden, *img));
      std::printf("golden    %s %s\n", golden.string().c_str(), old ? "updated" : "created");
    }
    return {};
  }
  auto want = load_image(golden);
  auto got = load_image(png);
  if (!got) return got.error();
  if (!want) {
    failures.add(f, "no golden image " + golden.string() + " (run with --update-goldens)");
    return {};
  }
  auto d = compare_images(*got, *want, g.fail_threshold, g.warn_threshold);
  if (!d) {
    failures.add(f, d.error().message + " (" + golden.string() + ")");
    return {};
  }
  const double pct = 100.0 * double(d->failing) / double(std::max<std::size_t>(1, d->pixels));
  if (pct > g.fail_percent) {
    const fs::path diff = out / frame_name("diff", f, "png");
    KASKAD_TRY(save_image(diff, d->diff));
    char msg[512];
    std::snprintf(msg, sizeof msg,
                  "golden: %.3f%% of pixels differ by more than %g (allowed %.3f%%), max "
                  "error %.4f; diff image %s",
                  pct, double(g.fail_threshold), double(g.fail_percent), d->max_error,
                  diff.string().c_str());
    failures.add(f, msg);
  } else if (d->warning > 0) {
    std::printf("warning   %s frame %d: %zu pixels differ by more than %g from the golden\n",
                pb.file.string().c_str(), f, d->warning, double(g.warn_threshold));
  }
  return {};
}

Result<double> check_misclassified(const Playback& pb, int f, const Scene& scene,
                                   render::Renderer& renderer, const FrameReport& report,
                                   Failures& failures) {
  const Image aov = renderer.read_aovs();
  if (report.shadows.empty()) {
    failures.add(f, "misclassified_pct: no shadowed light this frame");
    return -1.0;
  }
  auto tracer = reference::RayTracer::build(scene);
  if (!tracer) return tracer.error();
  // The light whose visibility the AOV shows.
  const ecs::Entity shown =
      report.shadows[std::size_t(aov_shadow_index(scene, report.shadows.size()))].light;
  const auto light = reference::reference_light(scene.world, shown);
  auto ref = tracer->shadow_reference(aov, light, {});
  if (!ref) return ref.error();
  auto m = reference::compare_shadows(aov, ref->image);
  if (!m) return m.error();
  const double pct = m->outside_edges.misclassified_pct;
  if (pct > pb.misclassified->max_pct) {
    char msg[256];
    std::snprintf(msg, sizeof msg,
                  "misclassified_pct: %.3f%% of receivers away from edges disagree with the "
                  "ray-traced reference (max %.3f%%)",
                  pct, pb.misclassified->max_pct);
    failures.add(f, msg);
  }
  return pct;
}

Status check_flicker(const Playback& pb, int f, render::Renderer& renderer,
                     const FrameReport& report, FlickerSamples& samples, Failures& failures) {
  const FlickerExpect& q = *pb.flicker;
  if (f < q.from || f > q.to) return {};
  if (f == q.from) {
    auto p = stability_points(renderer.read_aovs());
    if (!p) return p.error();
    samples.points = std::move(p.value());
    if (q.within) keep_points_within(samples.points, *q.within);
    if (samples.points.positions.empty())
      return Error{pb.file.string(), "expect.flicker",
                   "no receiver point seen on frame " + std::to_string(f) +
                       (q.within ? " lies within the box" : "")};
  }
  auto v = visibility_at_seen_points(renderer, report.camera, samples.points);
  if (!v) return v.error();
  samples.values.push_back(std::move(v.value()));
  if (f != q.to) return {};
  const auto s = reference::shadow_stability(samples.values);
  char msg[256];
  if (q.max && s.flicker > *q.max) {
    std::snprintf(msg, sizeof msg, "flicker over frames %d-%d: %.6g (max %g; %.3f%% of samples changed)",
                  q.from, q.to, s.flicker, *q.max, s.changed_pct);
    failures.add(f, msg);
  }
  if (q.max_changed_pct && s.changed_pct > *q.max_changed_pct) {
    std::snprintf(msg, sizeof msg,
                  "flicker over frames %d-%d: %.3f%% of samples changed by more than an "
                  "8-bit step (max %g%%)",
                  q.from, q.to, s.changed_pct, *q.max_changed_pct);
    failures.add(f, msg);
  }
  if (q.min && !(s.flicker > *q.min)) {
    std::snprintf(msg, sizeof msg, "flicker over frames %d-%d: %.6g, expected above %g", q.from,
                  q.to, s.flicker, *q.min);
    failures.add(f, msg);
  }
  std::printf("flicker   %s frames %d-%d: %.6g (%zu points, %.3f%% of samples changed)\n",
              pb.file.filename().string().c_str(), q.from, q.to, s.flicker, s.points,
              s.changed_pct);
  return {};
}

void sample_resources(const Playback& pb, int f, double rss, long gl_objects,
                      ResourceSamples& samples) {
  const FlatExpect& q = *pb.flat_resources;
  // The frames at the same point of the playback's cycle as the warm-up frame (every period
  // after it), or the last frame without a period.
  const bool in_cycle = f >= q.after && (q.period > 0 ? (f - q.after) % q.period == 0 : f == q.after);
  const bool sample = q.period > 0 ? in_cycle : f + 1 == pb.frames;
  if (sample) samples.rss_end = rss;
  if (f == q.after) {
    samples.rss_warm = samples.rss_max_after = rss;
    samples.gl_warm = samples.gl_max_after = gl_objects;
  } else if (f > q.after) {
    samples.rss_max_after = std::max(samples.rss_max_after, rss);
    samples.gl_max_after = std::max(samples.gl_max_after, gl_objects);
  }
  if (f == 0 || f + 1 == pb.frames || in_cycle)
    std::printf("resources %s frame %d: %.1f MiB resident (peak since warm-up %.1f), %ld GL "
                "objects\n",
                pb.file.filename().string().c_str(), f, rss, samples.rss_max_after, gl_objects);
}

void check_compiles(const Playback& pb, const RunRecord& run, Failures& failures) {
  if (pb.max_compiles_after_prewarm && run.compiles > *pb.max_compiles_after_prewarm)
    failures.add(-1, std::to_string(run.compiles) +
                         " shader programs compiled or loaded after pre-warm (max " +
                         std::to_string(*pb.max_compiles_after_prewarm) + ")");
}

void check_gl_errors(const Playback& pb, const RunRecord& run, Failures& failures) {
  if (run.gl_errors > pb.max_gl_errors)
    failures.add(-1, std::to_string(run.gl_errors) + " GL errors (max " +
                         std::to_string(pb.max_gl_errors) + ")");
}

void check_probe_captures(const ProbeExpect& q, const RunRecord& run, Failures& failures) {
  if (q.captures && run.probe_captures != *q.captures)
    failures.add(-1, "probe captures: " + std::to_string(run.probe_captures) + ", expected " +
                         std::to_string(*q.captures));
  if (!q.frames.empty() && run.probe_capture_frames != q.frames) {
    auto list = [](const std::vector<int>& frames) {
      std::string s;
      for (int f : frames) {
        if (!s.empty()) s += ' ';
        s += std::to_string(f);
      }
      return s;
    };
    failures.add(-1, "probe captures on frames [" + list(run.probe_capture_frames) +
                         "], expected [" + list(q.frames) + "]");
  }
}

void check_frame_time_ratio(const RatioExpect& q, const RunRecord& run, Failures& failures) {
  auto range_median = [&](int from, int to) {
    return median(std::vector<double>(run.frame_ms.begin() + from, run.frame_ms.begin() + to + 1));
  };
  const double a = range_median(q.a_from, q.a_to), b = range_median(q.b_from, q.b_to);
  const double ratio = a > 0.0 ? b / a : 0.0;
  if (ratio > q.max) {
    char msg[256];
    std::snprintf(msg, sizeof msg,
                  "frame time ratio: frames %d-%d take %.3g ms (median), %.3gx frames %d-%d's "
                  "%.3g ms (max %.3gx)",
                  q.b_from, q.b_to, b, ratio, q.a_from, q.a_to, a, q.max);
    failures.add(-1, msg);
  }
}

void check_flat_resources(const FlatExpect& q, const RunRecord& run, Failures& failures) {
  const ResourceSamples& s = run.resources;
  // Memory at the last sample against the warm-up frame, both at the same point of the
  // playback's cycle: settings toggled on the way reallocate maps and the driver keeps freed
  // pages a while, so peaks between say nothing of leaks.
  if (s.rss_end - s.rss_warm > q.max_rss_growth_mib) {
    char msg[256];
    std::snprintf(msg, sizeof msg,
                  "resident memory grew by %.1f MiB from frame %d to the last sample (max %.1f "
                  "MiB): %.1f -> %.1f MiB (peak %.1f)",
                  s.rss_end - s.rss_warm, q.after, q.max_rss_growth_mib, s.rss_warm, s.rss_end,
                  s.rss_max_after);
    failures.add(-1, msg);
  }
  if (s.gl_max_after - s.gl_warm > q.max_gl_object_growth)
    failures.add(-1, "live GL objects grew by " + std::to_string(s.gl_max_after - s.gl_warm) +
                         " after frame " + std::to_string(q.after) + " (max " +
                         std::to_string(q.max_gl_object_growth) + "): " +
                         std::to_string(s.gl_warm) + " -> " + std::to_string(s.gl_max_after));
}

void check_run(const Playback& pb, const RunRecord& run, Failures& failures) {
  check_compiles(pb, run, failures);
  check_gl_errors(pb, run, failures);
  if (pb.probes) check_probe_captures(*pb.probes, run, failures);
  if (pb.frame_time_ratio) check_frame_time_ratio(*pb.frame_time_ratio, run, failures);
  if (pb.flat_resources) check_flat_resources(*pb.flat_resources, run, failures);
}

}  // namespace kaskad::playback_detail
