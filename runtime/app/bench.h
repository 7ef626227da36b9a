// `kaskad bench`: sweeps render settings over scenes and charts speed against accuracy.
// For every scene x configuration: frame time (median of N frames after warm-up, AOVs off), CPU
// time per phase, GPU time per pass, counters, and shadow accuracy against the Embree reference
// (runtime/reference) on the AOVs of one more frame, and world-space flicker at fixed receiver
// points while the camera moves (runtime/app/stability.h). Rows go to a CSV as they finish (Ctrl-C keeps
// them); a matplotlib script (scripts/bench_chart.py, run with /usr/bin/python3) draws one chart per
// scene: frame ms on x, error on y, the Pareto front highlighted.
#pragma once

#include <chrono>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "runtime/result/result.h"

namespace kaskad {

struct BenchOptions {
  std::vector<std::filesystem::path> scenes;  ///< empty: the default scene
  std::string sweep;                          ///< "key=a,b;key2=c,d" (empty: default_sweep())
  std::filesystem::path out_dir = "out/bench";
  int frames = 10;  ///< timed frames per configuration (after one warm-up frame)
  int width = 640;
  int height = 360;
  bool chart = true;  ///< run scripts/bench_chart.py after the sweep
  /// Stability: frames of the camera path (runtime/app/stability.h); 0 or 1 = skip.
  int stability_frames = 16;
  int stability_points = 4096;  ///< at most this many fixed receiver points
  /// --shard i/n: this process runs runs i, i + n, ... of the scene x configuration list (in
  /// order), for a CI matrix or a job array; merge_bench() joins the shards' CSVs.
  int shard_index = 0, shard_count = 1;
};

/// One configuration: a label and its --set overrides.
struct BenchConfig {
  std::string label;
  std::vector<std::string> sets;
};

/// One progress line on stderr (bar, done/total, elapsed, ETA, what): rewritten in place on a
/// terminal; into a log, a line every 10 s and the last one.
void print_progress(std::size_t done, std::size_t total, double elapsed_s, const std::string& what);

/// Ends a progress line left on the terminal (nothing when there is none).
void end_progress();

/// Progress of a check that is usually quick (reading every configuration, every timeline
/// event): silent for its first 2 seconds, then print_progress() lines; the destructor ends them.
class CheckProgress {
 public:
  CheckProgress(std::size_t total, std::string what) : total_(total), what_(std::move(what)) {}
  CheckProgress(const CheckProgress&) = delete;
  CheckProgress& operator=(const CheckProgress&) = delete;
  ~CheckProgress() {
    if (shown_) end_progress();
  }
  /// `done` of the total are checked.
  void update(std::size_t done);

 private:
  std::size_t total_;
  std::string what_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  bool shown_ = false;
};

/// The most configurations a sweep may expand to (its products together): each is read before
/// the first frame and run for --frames frames.
inline constexpr std::size_t kMaxSweepConfigurations = 10000;

/// The sweep used when none is given: the settings whose speed/accuracy trade-off matters.
std::string default_sweep();

/// `--sweep soft`: the soft-shadow techniques and PCF kernels, for scenes whose lights
/// have a size (content/scenes/soft/): pcf with kernels 3x3, 5x5, 9x9 and a 16- and 32-tap
/// disc, pcss with 16 and 32 taps, backprojection, lom (S1's 1024^2 map, 4 and 8 layers), vsm
/// and evsm (default blur and bleeding reduction), each with the shadow cache off (maps redrawn
/// every frame). 12 configurations; chart them by rmse.
std::string soft_sweep();

/// Parses "key=v1,v2;key2=w1,w2" into the cartesian product, in order; products separated by
/// '|' are concatenated ("a=1;b=2|a=0;b=0" is two configurations). Errors: empty keys, missing
/// '=', empty value lists, a key given twice within one product.
Result<std::vector<BenchConfig>> parse_sweep(const std::string& spec);

/// The CSV header, one name per column (documented in docs/guide/bench.md, "CSV columns").
std::vector<std::string> bench_csv_columns();

/// `kaskad bench --merge DIR...`: concatenates the shards' bench.csv (same columns, else an
/// error naming the file) into OUT/bench.csv and draws the charts when `chart`. Every row is
/// checked first (its column count, numbers, a scene that is a file-name stem); an error names
/// the file and line, and nothing is written. bench.csv is written after the charts succeed.
Status merge_bench(const std::vector<std::filesystem::path>& dirs,
                   const std::filesystem::path& out_dir, bool chart);

/// Runs the sweep. Prints a progress bar with ETA on stderr; SIGINT stops after the current
/// configuration, keeping the rows written so far. Writes OUT/bench.csv and OUT/<scene>.png.
Status run_bench(const BenchOptions& options);

}  // namespace kaskad
