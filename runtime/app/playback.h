// `kaskad play`: scripted, deterministic scene playback with expectations, for CI.
//
// A playback file (JSON, README "Scene playback") names a scene, an output size, a frame count
// and a fixed time step; camera keyframes; a timeline of --set events and entity transform
// keyframes; which frames to capture; and what to expect: golden images per captured frame
// (OpenImageIO's compare, as idiff), misclassified % against the ray-traced reference, flicker
// over a frame range, compiles after pre-warm, probe captures, GL errors and a frame-time ratio.
// Time is the frame index times dt: nothing reads the wall clock, so a file gives the same
// pixels on the same driver.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <glm/gtc/quaternion.hpp>

#include "components/bounds.h"
#include "runtime/result/result.h"

namespace kaskad {

enum class Interpolation { linear, catmull_rom };

/// A pose at a time (seconds). Orientation from look_at, else rotation; position may be absent
/// for entity keys that only rotate or scale.
struct PoseKey {
  double t = 0.0;
  std::optional<glm::vec3> position;
  std::optional<glm::quat> rotation;
  std::optional<glm::vec3> look_at;
  std::optional<glm::vec3> scale;
  std::optional<float> fov_y_deg;
};

/// Keyframes of one entity (the camera or a named entity), sorted by time. Before the first key
/// the first holds, after the last the last.
struct Track {
  std::string entity;  ///< empty for the camera track: the scene's rendering camera
  Interpolation interpolation = Interpolation::linear;
  /// Keys give "move" instead of "position": metres along the entity's own right, up and
  /// forward (-Z) axes from its pose at load, so one path suits any scene (PoseKey::position
  /// then holds the move).
  bool relative = false;
  bool loop = false;  ///< times wrap at the last key (periodic motion for long runs)
  std::vector<PoseKey> keys;
};

/// A --set assignment applied before the frame with this index is rendered (events with
/// "every" are expanded into one per repeat when the file is read).
struct SetEvent {
  int frame = 0;
  std::string assignment;  ///< "key=value"; empty for add and remove events
  std::string remove;      ///< the entity to remove (with its children)
  /// An entity block of a scene file to add; shared by the copies an "every" repeats.
  std::shared_ptr<const nlohmann::json> add;
  std::string where;       ///< the event's JSON path, for messages
};

struct GoldenExpect {
  std::filesystem::path dir;      ///< goldens/<file stem> by default, beside the playback file
  float fail_threshold = 0.02f;   ///< per-channel difference that makes a pixel fail (idiff -fail)
  float fail_percent = 0.1f;      ///< % of pixels that may fail (idiff -failpercent)
  float warn_threshold = 0.01f;   ///< per-channel difference that warns (idiff -warn)
  bool portable = false;          ///< pixels are driver-specific: false (see README)
};

struct MisclassifiedExpect {
  std::vector<int> frames;
  double max_pct = 1.0;  ///< away from shadow edges
};

struct FlickerExpect {
  int from = 0, to = 0;                    ///< inclusive frame range
  std::optional<double> max, min;          ///< bounds on reference::StabilityStats::flicker
  /// Bound on StabilityStats::changed_pct: samples that changed by more than an 8-bit step
  /// (the blend band's float rounding, ~1e-10, does not count).
  std::optional<double> max_changed_pct;
  /// Only the receiver points inside this world box (`within`; none: every point seen): the
  /// static receivers of a scene with moving casters, whose shadows may rightly change.
  std::optional<Aabb> within;
};

struct RatioExpect {
  int a_from = 0, a_to = 0, b_from = 0, b_to = 0;  ///< median frame ms of b over a
  double max = 2.0;
};

struct ProbeExpect {
  std::optional<std::uint64_t> captures;  ///< captures completed over the run, all probes
  std::vector<int> frames;                ///< the frames on which a capture completed, exactly
};

/// Resident memory and live GL objects stay flat after warm-up (soak runs).
struct FlatExpect {
  int after = 100;      ///< the warm-up frame the rest is measured against
  /// Frames after which the whole playback state repeats (camera, tracks, toggles): memory is
  /// compared at after, after + period, ... so that every sample has the same maps allocated.
  /// 0: compare the warm-up frame with the last.
  int period = 0;
  double max_rss_growth_mib = 16.0;  ///< last sample against the first
  long max_gl_object_growth = 0;     ///< any frame after warm-up against the first sample
};

struct Playback {
  std::filesystem::path file;   ///< where it was read from
  std::filesystem::path scene;  ///< resolved against the playback file
  int width = 320, height = 180;
  int frames = 1;
  double dt = 1.0 / 60.0;  ///< seconds per frame
  std::vector<std::string> sets;  ///< applied at load, like --set
  std::optional<Track> camera;
  std::vector<Track> tracks;      ///< entity transform keyframes
  std::vector<SetEvent> events;   ///< sorted by frame
  std::vector<int> capture;       ///< frames whose colour image is written (sorted, unique)
  bool capture_aovs = false;      ///< also their AOV EXR
  std::optional<GoldenExpect> golden;
  std::optional<MisclassifiedExpect> misclassified;
  std::optional<FlickerExpect> flicker;
  std::optional<int> max_compiles_after_prewarm;
  std::optional<ProbeExpect> probes;
  int max_gl_errors = 0;
  std::optional<RatioExpect> frame_time_ratio;
  std::optional<FlatExpect> flat_resources;
};

/// Reads and validates a playback file. Errors name the file and the JSON path, and list the
/// valid keys for an unknown one (like scene files).
Result<Playback> read_playback(const std::filesystem::path& file);

/// Parses a playback document (the fuzz target's entry; `file` names it in errors and resolves
/// relative paths).
Result<Playback> parse_playback(const std::string& text, const std::filesystem::path& file);

/// The JSON Schema of playback files (docs/reference/playback.schema.json, `kaskad schema`),
/// from the reader's keys and limits.
nlohmann::json playback_schema();

/// The pose of a track at time t (seconds): positions interpolated linearly or by a centripetal-
/// free uniform Catmull-Rom spline through the keys, rotations (rotation or look_at) by slerp,
/// scale and fov linearly. Fields no key has stay empty.
PoseKey sample_track(const Track& track, double t);

struct PlayOptions {
  std::filesystem::path out_dir = "out/play";
  bool update_goldens = false;
  int shard_index = 0, shard_count = 1;  ///< --shard i/n: files i, i + n, ... (sorted order)
  bool headless = true;
};

/// One failed expectation: which file and frame, and what.
struct PlayFailure {
  std::string file;
  int frame = -1;  ///< -1: the whole run
  std::string message;
};

/// Runs the playback files (this shard's), writes OUT/<stem>/frame_NNNN.png (captures),
/// OUT/<stem>/frames.csv, OUT/<stem>/diff_NNNN.png for failing goldens and OUT/summary.json;
/// prints a line per file. Returns the failures (empty: all expectations held). A file that
/// cannot be read or run is one failure (frame -1, in the summary too) and the others still run;
/// an error only when the output folder or the GL context cannot be made.
Result<std::vector<PlayFailure>> run_playbacks(const std::vector<std::filesystem::path>& files,
                                               const PlayOptions& options);

/// Which of `count` sorted files shard i of n runs: i, i + n, i + 2n, ...
std::vector<std::size_t> shard_files(std::size_t count, int index, int n);

/// `kaskad play --merge DIR...`: combines the summary.json of shard output folders into
/// OUT/summary.json and lists the failed files; returns how many failed. Every summary is checked
/// first (version, shard, each entry's fields); an error names the file and JSON pointer, and
/// nothing is written.
Result<std::size_t> merge_summaries(const std::vector<std::filesystem::path>& dirs,
                                    const std::filesystem::path& out_dir);

/// What `kaskad play` was asked for (runtime/cli/ reads it from the command line).
struct PlayCommandOptions {
  std::vector<std::filesystem::path> inputs;  ///< playback files, and folders for their *.json
  PlayOptions run;                            ///< out_dir, update_goldens, shard, headless
  bool out_given = false;  ///< --out named: its parent must exist (the default out/play is made whole)
  bool merge = false;      ///< --merge: the inputs are shard output folders to merge
  int jobs = 1;            ///< --jobs N: N shard processes into OUT/shard-i, then one merged summary
};

/// `kaskad play`: runs the playback files (or merges shard summaries, or runs --jobs shard
/// processes). Exit status: 0 all expectations held, 1 an expectation failed or a file could not
/// be read or run, 2 usage error (no files, --jobs with --shard).
int run_play(const PlayCommandOptions& command);

}  // namespace kaskad
