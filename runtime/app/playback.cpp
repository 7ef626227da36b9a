#include "runtime/app/playback.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "runtime/core/median.h"

extern char** environ;

#include <nlohmann/json.hpp>

#include "components/camera.h"
#include "components/light.h"
#include "components/limits.h"
#include "components/name.h"
#include "components/transform.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/scene_io.h"
#include "runtime/app/bench.h"
#include "runtime/app/player.h"
#include "runtime/app/stability.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/json_reader.h"
#include "runtime/gpu/context.h"
#include "runtime/gpu/gl_handles.h"
#include "runtime/reference/ray_tracer.h"
#include "runtime/reference/shadow_metrics.h"
#include "systems/camera_system.h"
#include "systems/transform_system.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace json_reader;

constexpr int kFormatVersion = 1;
constexpr int kMaxFrames = 1000000;

const std::vector<std::pair<const char*, Interpolation>> kInterpolations = {
    {"linear", Interpolation::linear}, {"catmull_rom", Interpolation::catmull_rom}};

// A list of frame indices in [0, frames).
std::vector<int> read_frames(const json& j, const std::string& where, int frames) {
  if (!j.is_array()) fail(where, "expected an array of frame numbers, got " + type_name(j));
  std::vector<int> out;
  for (std::size_t i = 0; i < j.size(); ++i) {
    const std::string at = where + "/" + std::to_string(i);
    if (!j[i].is_number_integer()) fail(at, "expected a frame number, got " + type_name(j[i]));
    const long long f = j[i].get<long long>();
    if (f < 0 || f >= frames)
      fail(at, "frame must be in [0, " + std::to_string(frames - 1) + "], was " + std::to_string(f));
    out.push_back(int(f));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// The frame an event or range end names: "frame" (an index) or "t" (seconds, rounded to the
// nearest frame).
int read_when(ObjectReader& r, const Playback& pb, const std::string& where) {
  const bool has_frame = r.has("frame"), has_t = r.has("t");
  if (has_frame == has_t) fail(where, "give exactly one of frame and t");
  if (has_frame) {
    int f = 0;
    r.integer("frame", f, 0, pb.frames - 1);
    return f;
  }
  float t = 0.0f;
  r.number("t", t, 0.0f, float(pb.dt * (pb.frames - 1)) + 1e-6f);
  return int(std::lround(double(t) / pb.dt));
}

Track read_track(const json& j, const std::string& where, bool camera) {
  Track track;
  ObjectReader r(j, where);
  if (!camera) {
    r.string("entity", track.entity);
    if (track.entity.empty()) fail(r.at("entity"), "name the entity the keys move");
  }
  r.enumeration("interpolation", track.interpolation, kInterpolations);
  r.boolean("loop", track.loop);
  if (!r.has("keys") || !r.raw("keys").is_array() || r.raw("keys").empty())
    fail(r.at("keys"), "expected a non-empty array of keys");
  const json& keys = r.raw("keys");
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const std::string at = r.at("keys") + "/" + std::to_string(i);
    ObjectReader k(keys[i], at);
    PoseKey key;
    float t = 0.0f;
    if (!k.has("t")) fail(at, "a key needs a time t (seconds)");
    k.number("t", t, 0.0f, 1.0e6f);
    key.t = t;
    glm::vec3 v;
    if (k.has("position") && k.has("move")) fail(at, "give only one of position and move");
    if (k.has("position")) {
      k.vector<3>("position", v, -kMaxCoordinate, kMaxCoordinate);
      key.position = v;
    }
    if (k.has("move")) {
      k.vector<3>("move", v, -kMaxCoordinate, kMaxCoordinate);
      key.position = v;
      if (i > 0 && !track.relative) fail(at + "/move", "a track's keys all use position or all move");
      track.relative = true;
    } else if (track.relative && key.position) {
      fail(at + "/position", "a track's keys all use position or all move");
    }
    if (k.has("look_at") && k.has("rotation")) fail(at, "give only one of look_at and rotation");
    if (k.has("look_at") && track.relative) fail(at + "/look_at", "look_at needs absolute positions");
    if (k.has("look_at")) {
      k.vector<3>("look_at", v, -kMaxCoordinate, kMaxCoordinate);
      key.look_at = v;
      if (!key.position) fail(at + "/look_at", "look_at needs a position in the same key");
      if (glm::length(v - *key.position) < 1e-6f) fail(at + "/look_at", "looks at its own position");
    }
    if (k.has("rotation")) {
      glm::vec4 q;
      k.vector<4>("rotation", q, -2.0f, 2.0f);
      if (glm::length(q) < 1e-6f) fail(at + "/rotation", "quaternion has zero length");
      q = glm::normalize(q);
      key.rotation = glm::quat(q.w, q.x, q.y, q.z);
    }
    if (k.has("scale")) {
      k.vector<3>("scale", v, -kMaxCoordinate, kMaxCoordinate);
      key.scale = v;
    }
    if (k.has("fov_y_deg")) {
      if (!camera) fail(at + "/fov_y_deg", "only camera keys have a field of view");
      float fov = 0.0f;
      k.number("fov_y_deg", fov, 0.01f, 179.0f);
      key.fov_y_deg = fov;
    }
    k.finish();
    if (!track.keys.empty() && !(key.t > track.keys.back().t))
      fail(at + "/t", "key times must increase");
    track.keys.push_back(key);
  }
  r.finish();
  return track;
}

void read_expect(ObjectReader& r, Playback& pb, const fs::path& base) {
  if (r.has("golden")) {
    GoldenExpect g;
    g.dir = base / "goldens" / pb.file.stem();
    ObjectReader gr(r.raw("golden"), r.at("golden"));
    std::string dir;
    gr.string("dir", dir);
    if (!dir.empty()) g.dir = base / dir;
    gr.number("fail_threshold", g.fail_threshold, 0.0f, 1.0f);
    gr.number("fail_percent", g.fail_percent, 0.0f, 100.0f);
    gr.number("warn_threshold", g.warn_threshold, 0.0f, 1.0f);
    gr.boolean("portable", g.portable);
    gr.finish();
    if (pb.capture.empty()) fail(r.at("golden"), "goldens compare captured frames: capture some");
    pb.golden = g;
  }
  if (r.has("misclassified_pct")) {
    MisclassifiedExpect m;
    ObjectReader mr(r.raw("misclassified_pct"), r.at("misclassified_pct"));
    if (!mr.has("frames")) fail(mr.at("frames"), "name the frames to check");
    m.frames = read_frames(mr.raw("frames"), mr.at("frames"), pb.frames);
    float max = 0.0f;
    mr.number("max", max, 0.0f, 100.0f);
    m.max_pct = max;
    mr.finish();
    pb.misclassified = m;
  }
  if (r.has("flicker")) {
    FlickerExpect f;
    ObjectReader fr(r.raw("flicker"), r.at("flicker"));
    fr.integer("from", f.from, 0, pb.frames - 1);
    f.to = pb.frames - 1;
    fr.integer("to", f.to, 0, pb.frames - 1);
    if (f.to <= f.from) fail(fr.at("to"), "the range needs two frames at least (to > from)");
    float v = 0.0f;
    if (fr.has("max")) {
      fr.number("max", v, 0.0f, 1.0f);
      f.max = v;
    }
    if (fr.has("min")) {
      fr.number("min", v, 0.0f, 1.0f);
      f.min = v;
    }
    if (fr.has("max_changed_pct")) {
      fr.number("max_changed_pct", v, 0.0f, 100.0f);
      f.max_changed_pct = v;
    }
    if (!f.max && !f.min && !f.max_changed_pct)
      fail(r.at("flicker"), "give max, min or max_changed_pct");
    fr.finish();
    pb.flicker = f;
  }
  if (r.has("compiles_after_prewarm")) {
    int n = 0;
    r.integer("compiles_after_prewarm", n, 0, 100000);
    pb.max_compiles_after_prewarm = n;
  }
  if (r.has("probe_captures")) {
    ProbeExpect p;
    ObjectReader pr(r.raw("probe_captures"), r.at("probe_captures"));
    if (pr.has("count")) {
      int n = 0;
      pr.integer("count", n, 0, kMaxFrames);
      p.captures = std::uint64_t(n);
    }
    if (pr.has("frames")) p.frames = read_frames(pr.raw("frames"), pr.at("frames"), pb.frames);
    pr.finish();
    pb.probes = p;
  }
  r.integer("gl_errors", pb.max_gl_errors, 0, 1000000);
  if (r.has("frame_time_ratio")) {
    RatioExpect q;
    ObjectReader qr(r.raw("frame_time_ratio"), r.at("frame_time_ratio"));
    auto range = [&](const char* key, int& from, int& to) {
      if (!qr.has(key)) fail(qr.at(key), "expected [from, to] frame numbers");
      const std::vector<int> v = read_frames(qr.raw(key), qr.at(key), pb.frames);
      if (v.size() != 2) fail(qr.at(key), "expected [from, to] with from < to");
      from = v[0];
      to = v[1];
    };
    range("a", q.a_from, q.a_to);
    range("b", q.b_from, q.b_to);
    float max = 0.0f;
    qr.number("max", max, 0.0f, 1.0e6f);
    q.max = max;
    qr.finish();
    pb.frame_time_ratio = q;
  }
  if (r.has("flat_resources")) {
    FlatExpect q;
    ObjectReader qr(r.raw("flat_resources"), r.at("flat_resources"));
    qr.integer("after", q.after, 0, pb.frames - 1);
    qr.integer("period", q.period, 0, kMaxFrames);
    float mib = float(q.max_rss_growth_mib);
    qr.number("max_rss_growth_mib", mib, 0.0f, 1.0e6f);
    q.max_rss_growth_mib = mib;
    int objects = 0;
    qr.integer("max_gl_object_growth", objects, 0, 1000000);
    q.max_gl_object_growth = objects;
    qr.finish();
    pb.flat_resources = q;
  }
  r.finish();
}

glm::vec3 catmull_rom(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2,
                      const glm::vec3& p3, float u) {
  // Uniform Catmull-Rom: passes through p1 at u = 0 and p2 at u = 1.
  const float u2 = u * u, u3 = u2 * u;
  return 0.5f * ((2.0f * p1) + (-p0 + p2) * u + (2.0f * p0 - 5.0f * p1 + 4.0f * p2 - p3) * u2 +
                 (-p0 + 3.0f * p1 - 3.0f * p2 + p3) * u3);
}

// The orientation a key gives, if any.
std::optional<glm::quat> key_rotation(const PoseKey& k) {
  if (k.rotation) return k.rotation;
  if (k.look_at && k.position) return look_rotation(glm::normalize(*k.look_at - *k.position));
  return std::nullopt;
}

}  // namespace

namespace {

// A parsed playback document: the checks and defaults.
Result<Playback> playback_from(const json& doc, const fs::path& file) {
  Playback pb;
  pb.file = file;
  const fs::path base = file.parent_path();
  try {
    ObjectReader r(doc, "");
    int version = kFormatVersion;
    r.integer("kaskad_playback", version, 1, kFormatVersion);
    std::string scene;
    r.string("scene", scene);
    if (scene.empty()) fail("/scene", "name the scene file (.json, .gltf or .glb)");
    pb.scene = base / scene;
    if (r.has("size")) {
      glm::vec2 size;
      r.vector<2>("size", size, 1.0f, 16384.0f);
      if (size.x != std::floor(size.x) || size.y != std::floor(size.y))
        fail("/size", "expected whole pixels");
      pb.width = int(size.x);
      pb.height = int(size.y);
    }
    r.integer("frames", pb.frames, 1, kMaxFrames);
    float dt = float(pb.dt);
    r.number("dt", dt, 1e-6f, 10.0f);
    pb.dt = dt;
    if (r.has("set")) {
      const json& sets = r.raw("set");
      if (!sets.is_array()) fail("/set", "expected an array of \"key=value\" strings");
      for (std::size_t i = 0; i < sets.size(); ++i) {
        if (!sets[i].is_string() || sets[i].get<std::string>().find('=') == std::string::npos)
          fail("/set/" + std::to_string(i), "expected a \"key=value\" string");
        pb.sets.push_back(sets[i].get<std::string>());
      }
    }
    if (r.has("camera")) pb.camera = read_track(r.raw("camera"), "/camera", true);
    if (r.has("timeline")) {
      const json& tl = r.raw("timeline");
      if (!tl.is_array()) fail("/timeline", "expected an array of events and tracks");
      for (std::size_t i = 0; i < tl.size(); ++i) {
        const std::string at = "/timeline/" + std::to_string(i);
        if (tl[i].is_object() && tl[i].contains("keys")) {
          pb.tracks.push_back(read_track(tl[i], at, false));
          continue;
        }
        ObjectReader er(tl[i], at);
        SetEvent ev;
        ev.where = at;
        ev.frame = read_when(er, pb, at);
        er.string("set", ev.assignment);
        er.string("remove", ev.remove);
        if (er.has("add")) {
          if (!er.raw("add").is_object()) fail(er.at("add"), "expected an entity block of a scene file");
          ev.add = er.raw("add");
        }
        const int kinds = !ev.assignment.empty() + !ev.remove.empty() + bool(ev.add);
        if (kinds != 1)
          fail(at, "an event has one of set (\"key=value\"), add (an entity block) or remove (a "
                   "name); or give keys to move an entity");
        if (!ev.assignment.empty() && ev.assignment.find('=') == std::string::npos)
          fail(er.at("set"), "expected \"key=value\"");
        int every = 0;
        er.integer("every", every, 0, kMaxFrames);
        er.finish();
        for (int f = ev.frame; f < pb.frames; f += every) {
          SetEvent copy = ev;
          copy.frame = f;
          pb.events.push_back(std::move(copy));
          if (every == 0) break;
        }
      }
      std::stable_sort(pb.events.begin(), pb.events.end(),
                       [](const SetEvent& a, const SetEvent& b) { return a.frame < b.frame; });
    }
    if (r.has("capture")) {
      ObjectReader cr(r.raw("capture"), "/capture");
      if (cr.has("frames")) pb.capture = read_frames(cr.raw("frames"), "/capture/frames", pb.frames);
      int every = 0;
      cr.integer("every", every, 0, kMaxFrames);
      for (int f = 0; every > 0 && f < pb.frames; f += every) pb.capture.push_back(f);
      cr.boolean("aovs", pb.capture_aovs);
      cr.finish();
      std::sort(pb.capture.begin(), pb.capture.end());
      pb.capture.erase(std::unique(pb.capture.begin(), pb.capture.end()), pb.capture.end());
    }
    if (r.has("expect")) {
      ObjectReader er(r.raw("expect"), "/expect");
      read_expect(er, pb, base);
    }
    r.finish();
  } catch (const ContentError& e) {
    return Error{file.string(), e.where, e.message};
  } catch (const json::exception& e) {
    return Error{file.string(), "", e.what()};
  }
  return pb;
}

}  // namespace

Result<Playback> parse_playback(const std::string& text, const fs::path& file) {
  auto doc = parse_json_text(text, file.string());
  if (!doc) return doc.error();
  return playback_from(*doc, file);
}

Result<Playback> read_playback(const fs::path& file) {
  auto doc = parse_json_file(file);  // folders, unreadable and empty files: the shared messages
  if (!doc) return doc.error();
  return playback_from(*doc, file);
}

PoseKey sample_track(const Track& track, double t) {
  PoseKey out;
  out.t = t;
  const auto& k = track.keys;
  if (k.empty()) return out;
  if (track.loop && k.back().t > k.front().t && t > k.back().t)
    t = k.front().t + std::fmod(t - k.front().t, k.back().t - k.front().t);
  // The segment [i, i + 1] holding t (clamped to the ends).
  std::size_t i = 0;
  while (i + 1 < k.size() && k[i + 1].t <= t) ++i;
  const std::size_t j = std::min(i + 1, k.size() - 1);
  // Each field between the nearest keys that have it (a key may leave fields out), by the
  // fraction of the time between those two keys.
  struct Span {
    std::size_t a = 0, b = 0;
    float u = 0.0f;
    bool found = false;
  };
  auto span = [&](auto has) {
    Span sp;
    for (std::size_t n = 0; n <= i; ++n)
      if (has(k[n])) sp.a = n, sp.found = true;
    sp.b = sp.a;
    for (std::size_t n = j; n < k.size(); ++n)
      if (has(k[n])) {
        if (!sp.found) sp.a = n;
        sp.b = n;
        sp.found = true;
        break;
      }
    if (sp.b != sp.a)
      sp.u = float(std::clamp((t - k[sp.a].t) / (k[sp.b].t - k[sp.a].t), 0.0, 1.0));
    return sp;
  };
  if (const Span sp = span([](const PoseKey& p) { return bool(p.position); }); sp.found) {
    const glm::vec3 a = *k[sp.a].position, b = *k[sp.b].position;
    if (track.interpolation == Interpolation::catmull_rom && sp.a == i && sp.b == j && j != i) {
      const glm::vec3 p0 = i > 0 && k[i - 1].position ? *k[i - 1].position : a;
      const glm::vec3 p3 = j + 1 < k.size() && k[j + 1].position ? *k[j + 1].position : b;
      out.position = catmull_rom(p0, a, b, p3, sp.u);
    } else {
      out.position = glm::mix(a, b, sp.u);
    }
  }
  if (const Span sp = span([](const PoseKey& p) { return bool(key_rotation(p)); }); sp.found)
    out.rotation = glm::slerp(*key_rotation(k[sp.a]), *key_rotation(k[sp.b]), sp.u);
  if (const Span sp = span([](const PoseKey& p) { return bool(p.scale); }); sp.found)
    out.scale = glm::mix(*k[sp.a].scale, *k[sp.b].scale, sp.u);
  if (const Span sp = span([](const PoseKey& p) { return bool(p.fov_y_deg); }); sp.found)
    out.fov_y_deg = *k[sp.a].fov_y_deg + (*k[sp.b].fov_y_deg - *k[sp.a].fov_y_deg) * sp.u;
  return out;
}

std::vector<std::size_t> shard_files(std::size_t count, int index, int n) {
  std::vector<std::size_t> out;
  for (std::size_t i = std::size_t(index); n > 0 && i < count; i += std::size_t(n)) out.push_back(i);
  return out;
}

namespace {

struct FrameRow {
  int frame = 0;
  double t = 0.0, frame_ms = 0.0;
  FrameReport report;
  int compiles = 0;  ///< programs built after pre-warm, so far
  double misclassified_pct = -1.0;
};

// Resident set size of this process, MiB (Linux /proc/self/statm; 0 elsewhere).
double resident_mib() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  if (!(statm >> pages_total >> pages_resident)) return 0.0;
  return double(pages_resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

ecs::Entity find_named(const ecs::World& w, const std::string& name) {
  ecs::Entity found = ecs::kNullEntity;
  w.view<Name>().each([&](ecs::Entity e, const Name& n) {
    if (n.value == name && !found.valid()) found = e;
  });
  return found;
}

// `start` is the entity's transform at load: relative tracks move from it along its axes.
void apply_pose(ecs::World& w, ecs::Entity e, const Track& track, const PoseKey& pose,
                const Transform& start) {
  if (!w.alive(e) || !w.has<Transform>(e)) return;  // removed by the timeline
  Transform& t = w.get<Transform>(e);
  if (pose.position && track.relative) {
    const glm::vec3 m = *pose.position;
    t.translation = start.translation + start.rotation * glm::vec3(m.x, m.y, -m.z);
  } else if (pose.position) {
    t.translation = *pose.position;
  }
  if (pose.rotation) t.rotation = *pose.rotation;
  if (pose.scale) t.scale = *pose.scale;
  if (pose.fov_y_deg && w.has<Camera>(e)) w.get<Camera>(e).fov_y_deg = *pose.fov_y_deg;
}

std::string frame_name(const char* prefix, int f, const char* ext) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%s_%04d.%s", prefix, f, ext);
  return buf;
}

// One timeline event of playback file `file` on a loaded scene.
Status apply_event(Scene& scene, const SetEvent& ev, const fs::path& file) {
  if (ev.add) {
    auto e = add_entity(scene, *ev.add, ev.where + "/add", file);
    if (!e) return e.error();
    update_transforms(scene.world, scene.assets);
    return {};
  }
  if (!ev.remove.empty()) return remove_entity(scene, ev.remove);
  return apply_live_override(scene, ev.assignment);
}

// Loads the scene of `pb` with its sets and size, and checks every timeline event and track
// against a second copy first, so that a bad key fails before the first frame. With a
// renderer, every state the timeline reaches is pre-warmed on that copy: toggles mid-run
// compile nothing.
Result<Scene> load_checked(const Playback& pb, render::Renderer* prewarm = nullptr,
                           const FrameContext* ctx = nullptr) {
  std::vector<std::string> sets = pb.sets;
  sets.push_back("render.width=" + std::to_string(pb.width));
  sets.push_back("render.height=" + std::to_string(pb.height));
  auto scene = load_scene(pb.scene, sets);
  if (!scene) {
    Error e = scene.error();
    e.message += " (the scene of " + pb.file.string() + ", /scene)";
    return e;
  }
  auto trial = load_scene(pb.scene, sets);
  if (!trial) return trial.error();
  const bool points = bool(pb.flicker);  // the flicker gate reads the points pass
  if (prewarm) KASKAD_TRY(prewarm_frame(*trial, *prewarm, *ctx, {}, points));
  for (const SetEvent& ev : pb.events) {
    if (auto st = apply_event(*trial, ev, pb.file); !st) {
      Error e = st.error();
      e.message += " (timeline event at frame " + std::to_string(ev.frame) +
                   (e.file == pb.file.string() ? "" : " of " + pb.file.string()) + ")";
      return e;
    }
    if (prewarm) KASKAD_TRY(prewarm_frame(*trial, *prewarm, *ctx, {}, points));
  }
  for (const Track& tr : pb.tracks)
    if (!find_named(scene->world, tr.entity).valid())
      return Error{pb.file.string(), "/timeline", "no entity named '" + tr.entity + "' in " +
                                                      pb.scene.string()};
  if (pb.camera) {
    const CameraState cam = select_camera(scene->world, 1.0f);
    if (!cam.entity.valid()) return Error{pb.file.string(), "/camera", "the scene has no camera"};
    if (scene->world.get<Transform>(cam.entity).parent.valid())
      return Error{pb.file.string(), "/camera", "the camera has a parent; keys move root cameras"};
  }
  return scene;
}

struct FileResult {
  std::vector<PlayFailure> failures;
  int frames = 0;
  double wall_s = 0.0;
  int captured = 0;
};

// `out` is the file's own output folder.
Result<FileResult> play_one(Player& player, const Playback& pb, const PlayOptions& options,
                            const fs::path& out) {
  FileResult result;
  const auto t_start = std::chrono::steady_clock::now();
  auto fail_at = [&](int frame, const std::string& message) {
    result.failures.push_back({pb.file.string(), frame, message});
  };
  FrameContext ctx;
  ctx.width = pb.width;
  ctx.height = pb.height;
  // AOVs for every frame when any frame needs them: one program set, no compiles mid-run.
  ctx.write_aovs = pb.capture_aovs || pb.misclassified || pb.flicker;
  const int gl_errors_before = gpu::debug_error_count();
  auto scene = load_checked(pb, player.renderer.get(), &ctx);
  if (!scene) return scene.error();
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) return Error{out.string(), "", "cannot create the output folder: " + ec.message()};
  // Captures and diff images of an earlier run of this file would pass for this run's.
  static const std::regex earlier(R"((frame|diff)_\d{4}\.png|aov_\d{4}\.exr)");
  for (const auto& entry : fs::directory_iterator(out, ec))
    if (entry.is_regular_file(ec) && std::regex_match(entry.path().filename().string(), earlier))
      fs::remove(entry.path(), ec);

  // The output size the camera allows (an own aspect fits inside the playback's size).
  ctx.width = scene->render.width;
  ctx.height = scene->render.height;
  player.renderer->shaders().first_frame_done();
  // Every program made from here on counts, compiled or loaded from the binary cache: either
  // is a hitch in the middle of the run.
  auto programs_made = [&] {
    const render::ShaderStats& s = player.renderer->shaders().stats();
    return s.programs_compiled + s.cache_hits;
  };
  const int compiles_before = programs_made();

  const ecs::Entity camera = pb.camera ? select_camera(scene->world, 1.0f).entity : ecs::kNullEntity;
  const Transform camera_start = pb.camera ? scene->world.get<Transform>(camera) : Transform{};
  struct Moved {
    ecs::Entity entity;
    const Track* track;
    Transform start;
  };
  std::vector<Moved> moved;
  for (const Track& tr : pb.tracks) {
    const ecs::Entity e = find_named(scene->world, tr.entity);
    moved.push_back({e, &tr, scene->world.get<Transform>(e)});
  }

  // Rows are kept in memory and written atomically at the end (and when a run fails midway,
  // nothing half-written is left behind).
  std::ostringstream csv;
  csv << "frame,t,frame_ms,cpu_transforms_ms,cpu_camera_ms,cpu_shadows_ms,cpu_probes_ms,"
         "cpu_draw_list_ms,cpu_render_ms,gpu_shadow_ms,gpu_forward_ms,gpu_probe_ms,draw_calls,"
         "shadow_draw_calls,shadow_triangles,probe_faces,probe_captures,compiles_after_prewarm,"
         "misclassified_pct,rss_mib,gl_objects,mesh_draws,shadow_mesh_draws\n";
  double rss_warm = 0.0, rss_max_after = 0.0, rss_end = 0.0;
  long gl_warm = 0, gl_max_after = 0;
  std::vector<double> frame_ms;
  std::vector<int> capture_frames;
  std::vector<std::vector<float>> flicker_values;
  StabilityPoints points;
  SystemState systems;  // this run's: a fresh scene, frames from 0
  FrameReport report;
  std::size_t next_event = 0;
  const std::set<int> capture(pb.capture.begin(), pb.capture.end());
  const std::set<int> checked =
      pb.misclassified ? std::set<int>(pb.misclassified->frames.begin(), pb.misclassified->frames.end())
                       : std::set<int>{};
  for (int f = 0; f < pb.frames; ++f) {
    const double t = f * pb.dt;
    // 1. Timeline: events due now, then the tracks' poses.
    for (; next_event < pb.events.size() && pb.events[next_event].frame <= f; ++next_event)
      KASKAD_TRY(apply_event(*scene, pb.events[next_event], pb.file));
    if (pb.camera) {
      apply_pose(scene->world, camera, *pb.camera, sample_track(*pb.camera, t), camera_start);
      // An auto_frame camera's planes were fitted from where the load put it; as in the
      // editor, they follow the keys, or a camera moved in would clip what it moves up to.
      if (Camera& c = scene->world.get<Camera>(camera); c.auto_frame) {
        const Aabb bounds = scene_bounds(scene->world);
        if (!bounds.empty())
          fit_planes_to_bounds(c, scene->world.get<Transform>(camera).translation, bounds);
      }
    }
    for (const Moved& m : moved)
      apply_pose(scene->world, m.entity, *m.track, sample_track(*m.track, t), m.start);
    // 2. The frame, timed with the GPU waited on.
    ctx.index = std::uint64_t(f);
    const auto t0 = std::chrono::steady_clock::now();
    KASKAD_TRY(run_frame(*scene, *player.renderer, ctx, systems, report));
    player.renderer->finish();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    frame_ms.push_back(ms);
    FrameRow row;
    row.frame = f;
    row.t = t;
    row.frame_ms = ms;
    row.compiles = programs_made() - compiles_before;
    if (report.probes.captures_this_frame > 0) capture_frames.push_back(f);
    // 3. Outputs and the checks of this frame.
    if (capture.count(f)) {
      const fs::path png = out / frame_name("frame", f, "png");
      KASKAD_TRY(save_image(png, player.renderer->read_color()));
      ++result.captured;
      if (pb.capture_aovs)
        KASKAD_TRY(save_image(out / frame_name("aov", f, "exr"), player.renderer->read_aovs()));
      if (pb.golden) {
        const fs::path golden = pb.golden->dir / frame_name("frame", f, "png");
        if (options.update_goldens) {
          fs::create_directories(pb.golden->dir, ec);
          auto img = load_image(png);
          if (!img) return img.error();
          auto old = load_image(golden);
          const bool same = old && old->pixels == img->pixels && old->width == img->width;
          if (!same) {
            KASKAD_TRY(save_image(golden, *img));
            std::printf("golden    %s %s\n", golden.string().c_str(), old ? "updated" : "created");
          }
        } else {
          auto want = load_image(golden);
          auto got = load_image(png);
          if (!got) return got.error();
          if (!want) {
            fail_at(f, "no golden image " + golden.string() + " (run with --update-goldens)");
          } else if (auto d = compare_images(*got, *want, pb.golden->fail_threshold,
                                             pb.golden->warn_threshold);
                     !d) {
            fail_at(f, d.error().message + " (" + golden.string() + ")");
          } else {
            const double pct = 100.0 * double(d->failing) / double(std::max<std::size_t>(1, d->pixels));
            if (pct > pb.golden->fail_percent) {
              const fs::path diff = out / frame_name("diff", f, "png");
              KASKAD_TRY(save_image(diff, d->diff));
              char msg[512];
              std::snprintf(msg, sizeof msg,
                            "golden: %.3f%% of pixels differ by more than %g (allowed %.3f%%), max "
                            "error %.4f; diff image %s",
                            pct, double(pb.golden->fail_threshold), double(pb.golden->fail_percent),
                            d->max_error, diff.string().c_str());
              fail_at(f, msg);
            } else if (d->warning > 0) {
              std::printf("warning   %s frame %d: %zu pixels differ by more than %g from the golden\n",
                          pb.file.string().c_str(), f, d->warning, double(pb.golden->warn_threshold));
            }
          }
        }
      }
    }
    if (checked.count(f)) {
      const Image aov = player.renderer->read_aovs();
      if (report.shadows.empty()) {
        fail_at(f, "misclassified_pct: no shadowed light this frame");
      } else {
        auto tracer = reference::RayTracer::build(*scene);
        if (!tracer) return tracer.error();
        // The light whose visibility the AOV shows.
        const ecs::Entity shown =
            report.shadows[std::size_t(aov_shadow_index(*scene, report.shadows.size()))].light;
        const auto light = reference::reference_light(
            scene->world.get<Light>(shown), scene->world.get<WorldTransform>(shown).matrix);
        auto ref = tracer->shadow_reference(aov, light, {});
        if (!ref) return ref.error();
        auto m = reference::compare_shadows(aov, ref->image);
        if (!m) return m.error();
        row.misclassified_pct = m->outside_edges.misclassified_pct;
        if (row.misclassified_pct > pb.misclassified->max_pct) {
          char msg[256];
          std::snprintf(msg, sizeof msg,
                        "misclassified_pct: %.3f%% of receivers away from edges disagree with the "
                        "ray-traced reference (max %.3f%%)",
                        row.misclassified_pct, pb.misclassified->max_pct);
          fail_at(f, msg);
        }
      }
    }
    if (pb.flicker && f >= pb.flicker->from && f <= pb.flicker->to) {
      if (f == pb.flicker->from) {
        auto p = stability_points(player.renderer->read_aovs());
        if (!p) return p.error();
        points = std::move(p.value());
      }
      auto v = visibility_at_seen_points(*player.renderer, report.camera, points);
      if (!v) return v.error();
      flicker_values.push_back(std::move(v.value()));
      if (f == pb.flicker->to) {
        const auto s = reference::shadow_stability(flicker_values);
        char msg[256];
        if (pb.flicker->max && s.flicker > *pb.flicker->max) {
          std::snprintf(msg, sizeof msg, "flicker over frames %d-%d: %.6g (max %g; %.3f%% of samples changed)",
                        pb.flicker->from, pb.flicker->to, s.flicker, *pb.flicker->max, s.changed_pct);
          fail_at(f, msg);
        }
        if (pb.flicker->max_changed_pct && s.changed_pct > *pb.flicker->max_changed_pct) {
          std::snprintf(msg, sizeof msg,
                        "flicker over frames %d-%d: %.3f%% of samples changed by more than an "
                        "8-bit step (max %g%%)",
                        pb.flicker->from, pb.flicker->to, s.changed_pct, *pb.flicker->max_changed_pct);
          fail_at(f, msg);
        }
        if (pb.flicker->min && !(s.flicker > *pb.flicker->min)) {
          std::snprintf(msg, sizeof msg, "flicker over frames %d-%d: %.6g, expected above %g",
                        pb.flicker->from, pb.flicker->to, s.flicker, *pb.flicker->min);
          fail_at(f, msg);
        }
        std::printf("flicker   %s frames %d-%d: %.6g (%zu points, %.3f%% of samples changed)\n",
                    pb.file.filename().string().c_str(), pb.flicker->from, pb.flicker->to,
                    s.flicker, s.points, s.changed_pct);
      }
    }
    const double rss = resident_mib();
    const long gl_objects = gpu::live_gl_objects();
    if (pb.flat_resources) {
      const FlatExpect& q = *pb.flat_resources;
      const bool sample = q.period > 0 ? f >= q.after && (f - q.after) % q.period == 0
                                       : f + 1 == pb.frames;
      if (sample) rss_end = rss;
    }
    if (pb.flat_resources && f == pb.flat_resources->after) {
      rss_warm = rss_max_after = rss;
      gl_warm = gl_max_after = gl_objects;
    } else if (pb.flat_resources && f > pb.flat_resources->after) {
      rss_max_after = std::max(rss_max_after, rss);
      gl_max_after = std::max(gl_max_after, gl_objects);
    }
    if (pb.flat_resources &&
        (f == 0 || f + 1 == pb.frames ||
         (f >= pb.flat_resources->after &&
          (pb.flat_resources->period > 0
               ? (f - pb.flat_resources->after) % pb.flat_resources->period == 0
               : f == pb.flat_resources->after))))
      std::printf("resources %s frame %d: %.1f MiB resident (peak since warm-up %.1f), %ld GL "
                  "objects\n",
                  pb.file.filename().string().c_str(), f, rss, rss_max_after, gl_objects);
    const auto& st = report.stats;
    char line[640];
    std::snprintf(line, sizeof line,
                  "%d,%.6g,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%d,%d,%zu,%d,%d,%d,%s,%.2f,%ld,%d,%d\n", f,
                  t, ms, report.transforms_ms, report.camera_ms, report.shadows_ms, report.probes_ms,
                  report.draw_list_ms, report.render_ms, st.shadow_gpu_ms, st.forward_gpu_ms,
                  st.probe_gpu_ms, st.draw_calls, st.shadow_draw_calls, st.shadow_triangles,
                  st.probe_faces, report.probes.captures_this_frame, row.compiles,
                  row.misclassified_pct < 0 ? "" : std::to_string(row.misclassified_pct).c_str(),
                  rss, gl_objects, st.mesh_draws, st.shadow_mesh_draws);
    csv << line;
    print_progress(std::size_t(f + 1), std::size_t(pb.frames),
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count(),
                   pb.file.filename().string());
  }
  end_progress();
  KASKAD_TRY(write_file_atomic(out / "frames.csv", csv.str()));

  // 4. Whole-run expectations.
  const int compiles = programs_made() - compiles_before;
  if (pb.max_compiles_after_prewarm && compiles > *pb.max_compiles_after_prewarm)
    fail_at(-1, std::to_string(compiles) + " shader programs compiled or loaded after pre-warm (max " +
                    std::to_string(*pb.max_compiles_after_prewarm) + ")");
  const int gl_errors = gpu::debug_error_count() - gl_errors_before;
  if (gl_errors > pb.max_gl_errors)
    fail_at(-1, std::to_string(gl_errors) + " GL errors (max " + std::to_string(pb.max_gl_errors) + ")");
  if (pb.probes) {
    if (pb.probes->captures && report.probes.captures_total != *pb.probes->captures)
      fail_at(-1, "probe captures: " + std::to_string(report.probes.captures_total) + ", expected " +
                      std::to_string(*pb.probes->captures));
    if (!pb.probes->frames.empty() && capture_frames != pb.probes->frames) {
      std::string got;
      for (int f : capture_frames) got += (got.empty() ? "" : " ") + std::to_string(f);
      std::string want;
      for (int f : pb.probes->frames) want += (want.empty() ? "" : " ") + std::to_string(f);
      fail_at(-1, "probe captures on frames [" + got + "], expected [" + want + "]");
    }
  }
  if (pb.frame_time_ratio) {
    const auto& q = *pb.frame_time_ratio;
    auto range_median = [&](int from, int to) {
      return median(std::vector<double>(frame_ms.begin() + from, frame_ms.begin() + to + 1));
    };
    const double a = range_median(q.a_from, q.a_to), b = range_median(q.b_from, q.b_to);
    const double ratio = a > 0.0 ? b / a : 0.0;
    if (ratio > q.max) {
      char msg[256];
      std::snprintf(msg, sizeof msg,
                    "frame time ratio: frames %d-%d take %.3g ms (median), %.3gx frames %d-%d's "
                    "%.3g ms (max %.3gx)",
                    q.b_from, q.b_to, b, ratio, q.a_from, q.a_to, a, q.max);
      fail_at(-1, msg);
    }
  }
  if (pb.flat_resources) {
    const auto& q = *pb.flat_resources;
    // Memory at the last sample against the warm-up frame, both at the same point of the
    // playback's cycle: settings toggled on the way reallocate maps and the driver keeps freed
    // pages a while, so peaks between say nothing of leaks.
    if (rss_end - rss_warm > q.max_rss_growth_mib) {
      char msg[256];
      std::snprintf(msg, sizeof msg,
                    "resident memory grew by %.1f MiB from frame %d to the last sample (max %.1f "
                    "MiB): %.1f -> %.1f MiB (peak %.1f)",
                    rss_end - rss_warm, q.after, q.max_rss_growth_mib, rss_warm, rss_end,
                    rss_max_after);
      fail_at(-1, msg);
    }
    if (gl_max_after - gl_warm > q.max_gl_object_growth)
      fail_at(-1, "live GL objects grew by " + std::to_string(gl_max_after - gl_warm) +
                      " after frame " + std::to_string(q.after) + " (max " +
                      std::to_string(q.max_gl_object_growth) + "): " + std::to_string(gl_warm) +
                      " -> " + std::to_string(gl_max_after));
  }
  result.frames = pb.frames;
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return result;
}

}  // namespace

Result<std::vector<PlayFailure>> run_playbacks(const std::vector<fs::path>& files,
                                               const PlayOptions& options) {
  if (options.shard_count < 1 || options.shard_index < 0 ||
      options.shard_index >= options.shard_count)
    return Error{"--shard", "", "expected i/n with 0 <= i < n"};
  std::vector<fs::path> sorted = files;
  std::sort(sorted.begin(), sorted.end());
  std::vector<PlayFailure> failures;
  json summary = {
      {"kaskad_play_summary", 1},
      {"shard", std::to_string(options.shard_index) + "/" + std::to_string(options.shard_count)},
      {"files", json::array()}};
  // A file that cannot be read or run fails on its own: it is reported at once and recorded in
  // the summary, and the other files still run.
  auto fail_file = [&](const fs::path& file, const Error& error) {
    end_progress();
    std::fprintf(stderr, "kaskad: error: %s\n", error.to_string().c_str());
    std::printf("play      %-40s %6d frames %8.1f s  FAILED (cannot run)\n",
                file.filename().string().c_str(), 0, 0.0);
    failures.push_back({file.string(), -1, error.to_string()});
    summary["files"].push_back(
        {{"file", file.string()},
         {"frames", 0},
         {"captured", 0},
         {"wall_s", 0.0},
         {"ok", false},
         {"failures", json::array({{{"frame", -1}, {"message", error.to_string()}}})}});
  };
  // Every file of the shard is read before anything renders: a bad file fails at once.
  std::vector<Playback> playbacks;
  for (std::size_t i : shard_files(sorted.size(), options.shard_index, options.shard_count)) {
    auto pb = read_playback(sorted[i]);
    if (pb)
      playbacks.push_back(std::move(pb.value()));
    else
      fail_file(sorted[i], pb.error());
  }
  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec) return Error{options.out_dir.string(), "", "cannot create the output folder: " + ec.message()};
  std::optional<Player> player;
  if (!playbacks.empty()) {
    gpu::ContextOptions opt;
    opt.headless = options.headless;
    auto made = Player::create(opt);
    if (!made) return made.error();
    player.emplace(std::move(made.value()));
  }

  for (const Playback& pb : playbacks) {
    // Output folders by file name; files of the same name from different folders get their
    // folder's name in front.
    std::string name = pb.file.stem().string();
    for (const Playback& other : playbacks)
      if (&other != &pb && other.file.stem() == pb.file.stem()) {
        name = pb.file.parent_path().filename().string() + "_" + name;
        break;
      }
    auto r = play_one(*player, pb, options, options.out_dir / name);
    if (!r) {
      fail_file(pb.file, r.error());
      continue;
    }
    json failed = json::array();
    for (const PlayFailure& f : r->failures) {
      failed.push_back({{"frame", f.frame}, {"message", f.message}});
      failures.push_back(f);
    }
    summary["files"].push_back({{"file", pb.file.string()},
                                {"frames", r->frames},
                                {"captured", r->captured},
                                {"wall_s", r->wall_s},
                                {"ok", r->failures.empty()},
                                {"failures", failed}});
    std::printf("play      %-40s %6d frames %8.1f s  %s\n", pb.file.filename().string().c_str(),
                r->frames, r->wall_s,
                r->failures.empty() ? "ok" : ("FAILED (" + std::to_string(r->failures.size()) + ")").c_str());
    for (const PlayFailure& f : r->failures)
      std::printf("  %s%s: %s\n", f.file.c_str(),
                  f.frame >= 0 ? (" frame " + std::to_string(f.frame)).c_str() : "", f.message.c_str());
  }
  KASKAD_TRY(write_file_atomic(options.out_dir / "summary.json", summary.dump(2) + "\n"));
  return failures;
}

Result<std::size_t> merge_summaries(const std::vector<fs::path>& dirs, const fs::path& out_dir) {
  json merged = {{"kaskad_play_summary", 1}, {"merged_from", json::array()}, {"files", json::array()}};
  std::size_t failed = 0, files = 0;
  for (const fs::path& dir : dirs) {
    const fs::path file = dir / "summary.json";
    auto doc = parse_json_file(file);
    if (!doc) {
      Error e = doc.error();
      e.message += " (is this a kaskad play --out folder?)";
      return e;
    }
    if (!doc->is_object() || !doc->contains("files") || !(*doc)["files"].is_array())
      return Error{file.string(), "/files", "not a kaskad play summary"};
    merged["merged_from"].push_back(file.string());
    for (const json& f : (*doc)["files"]) {
      if (!f.is_object() || !f.contains("ok") || !f["ok"].is_boolean() || !f.contains("file"))
        return Error{file.string(), "/files", "an entry lacks file or ok"};
      ++files;
      if (!f["ok"].get<bool>()) {
        ++failed;
        std::printf("FAILED    %s\n", f["file"].dump().c_str());
        if (f.contains("failures") && f["failures"].is_array())
          for (const json& x : f["failures"]) std::printf("  %s\n", x.dump().c_str());
      }
      merged["files"].push_back(f);
    }
  }
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  const fs::path path = out_dir / "summary.json";
  KASKAD_TRY(write_file_atomic(path, merged.dump(2) + "\n"));
  std::printf("merged    %zu summaries, %zu files, %zu failed -> %s\n", dirs.size(), files, failed,
              path.string().c_str());
  return failed;
}

int run_play(const PlayCommandOptions& command) {
  auto usage = [](const std::string& msg) {
    std::fprintf(stderr, "kaskad play: %s\n(run `kaskad play --help` for usage)\n", msg.c_str());
    return 2;
  };
  const PlayOptions& options = command.run;
  const std::vector<fs::path>& inputs = command.inputs;
  const bool out_given = command.out_given;
  const bool merge = command.merge;
  const int jobs = command.jobs;
  // Like every output folder Kaskad makes: one level, in a folder that exists (the default
  // out/play is made whole).
  if (out_given) {
    const fs::path parent = options.out_dir.has_parent_path() ? options.out_dir.parent_path() : ".";
    std::error_code ec;
    if (!fs::is_directory(parent, ec)) {
      std::fprintf(
          stderr,
          "kaskad: error: %s: the folder it goes in does not exist (--out makes one level)\n",
          options.out_dir.string().c_str());
      return 1;
    }
  }
  if (merge) {
    if (inputs.empty()) return usage("--merge needs the output folders of the shards");
    auto failed = merge_summaries(inputs, options.out_dir);
    if (!failed) {
      std::fprintf(stderr, "kaskad: error: %s\n", failed.error().to_string().c_str());
      return 1;
    }
    return *failed == 0 ? 0 : 1;
  }
  // A folder stands for its *.json files.
  std::vector<fs::path> files;
  for (const fs::path& in : inputs) {
    std::error_code ec;
    if (fs::is_directory(in, ec)) {
      for (const auto& entry : fs::directory_iterator(in, ec))
        if (entry.path().extension() == ".json") files.push_back(entry.path());
    } else {
      files.push_back(in);
    }
  }
  if (files.empty()) return usage("name playback files or folders of them");
  if (jobs > 1) {
    if (options.shard_count > 1) return usage("give --jobs or --shard, not both");
    // One process per shard (one GL context each), then one merged summary.
    std::error_code ec;
    fs::create_directories(options.out_dir, ec);
    if (ec) {
      std::fprintf(stderr, "kaskad: error: %s: cannot create the output folder: %s\n",
                   options.out_dir.string().c_str(), ec.message().c_str());
      return 1;
    }
    std::vector<pid_t> children;
    std::vector<fs::path> dirs;
    for (int j = 0; j < jobs; ++j) {
      dirs.push_back(options.out_dir / ("shard-" + std::to_string(j)));
      std::vector<std::string> args = {"kaskad", "play", "--shard",
                                       std::to_string(j) + "/" + std::to_string(jobs), "--out",
                                       dirs.back().string(), options.headless ? "--headless" : "--window"};
      if (options.update_goldens) args.push_back("--update-goldens");
      for (const fs::path& f : files) args.push_back(f.string());
      std::vector<char*> cargs;
      for (std::string& a : args) cargs.push_back(a.data());
      cargs.push_back(nullptr);
      pid_t pid = 0;
      if (posix_spawn(&pid, "/proc/self/exe", nullptr, nullptr, cargs.data(), environ) != 0) {
        std::fprintf(stderr, "kaskad: error: cannot start a play process for shard %d\n", j);
        return 1;
      }
      children.push_back(pid);
    }
    bool crashed = false;
    for (std::size_t j = 0; j < children.size(); ++j) {
      int status = 0;
      waitpid(children[j], &status, 0);
      // 0 and 1 are results with a summary; anything else (a signal, a usage error), or no
      // summary, is a broken run.
      std::error_code ec;
      const bool summary = fs::exists(dirs[j] / "summary.json", ec);
      if (WIFEXITED(status) && WEXITSTATUS(status) <= 1 && summary) continue;
      crashed = true;
      const std::string how = WIFSIGNALED(status)
                                  ? "was killed by signal " + std::to_string(WTERMSIG(status))
                                  : "exited with status " + std::to_string(WEXITSTATUS(status));
      std::fprintf(stderr, "kaskad: error: the process of shard %zu/%d %s\n", j, jobs, how.c_str());
      // A shard that left no summary is recorded as failed, so the merge still reports the rest.
      if (!summary) {
        fs::create_directory(dirs[j], ec);
        const std::string message = "the shard process " + how + " before writing its summary";
        const json stub = {
            {"kaskad_play_summary", 1},
            {"shard", std::to_string(j) + "/" + std::to_string(jobs)},
            {"files",
             json::array({{{"file", dirs[j].string()},
                           {"ok", false},
                           {"failures", json::array({{{"frame", -1}, {"message", message}}})}}})}};
        if (auto st = write_file_atomic(dirs[j] / "summary.json", stub.dump(2) + "\n"); !st)
          std::fprintf(stderr, "kaskad: error: %s\n", st.error().to_string().c_str());
      }
    }
    auto failed = merge_summaries(dirs, options.out_dir);
    if (!failed) {
      std::fprintf(stderr, "kaskad: error: %s\n", failed.error().to_string().c_str());
      return 1;
    }
    return crashed || *failed != 0 ? 1 : 0;
  }
  auto failures = run_playbacks(files, options);
  if (!failures) {
    std::fprintf(stderr, "kaskad: error: %s\n", failures.error().to_string().c_str());
    return 1;
  }
  std::printf("summary   %s: %zu failed expectation(s)\n",
              (options.out_dir / "summary.json").string().c_str(), failures->size());
  return failures->empty() ? 0 : 1;
}

}  // namespace kaskad
