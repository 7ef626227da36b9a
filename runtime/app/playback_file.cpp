// The playback file format: reading and validating a playback JSON into a Playback. The limits
// are declared in playback_internal.h, where the schema (playback_schema.cpp) takes them too.
#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "components/limits.h"
#include "components/transform.h"
#include "runtime/app/playback.h"
#include "runtime/app/playback_internal.h"
#include "runtime/core/json_reader.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace json_reader;
using namespace playback_detail;

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
    k.number("t", t, kKeyTime.lo, kKeyTime.hi);
    key.t = t;
    glm::vec3 v;
    if (k.has("position") && k.has("move")) fail(at, "give only one of position and move");
    if (k.has("position")) {
      k.vector<3>("position", v, kCoordinate.lo, kCoordinate.hi);
      key.position = v;
    }
    if (k.has("move")) {
      k.vector<3>("move", v, kCoordinate.lo, kCoordinate.hi);
      key.position = v;
      if (i > 0 && !track.relative) fail(at + "/move", "a track's keys all use position or all move");
      track.relative = true;
    } else if (track.relative && key.position) {
      fail(at + "/position", "a track's keys all use position or all move");
    }
    if (k.has("look_at") && k.has("rotation")) fail(at, "give only one of look_at and rotation");
    if (k.has("look_at") && track.relative) fail(at + "/look_at", "look_at needs absolute positions");
    if (k.has("look_at")) {
      k.vector<3>("look_at", v, kCoordinate.lo, kCoordinate.hi);
      key.look_at = v;
      if (!key.position) fail(at + "/look_at", "look_at needs a position in the same key");
      if (glm::length(v - *key.position) < 1e-6f) fail(at + "/look_at", "looks at its own position");
    }
    if (k.has("rotation")) {
      glm::vec4 q;
      k.vector<4>("rotation", q, kQuaternion.lo, kQuaternion.hi);
      if (glm::length(q) < 1e-6f) fail(at + "/rotation", "quaternion has zero length");
      q = glm::normalize(q);
      key.rotation = glm::quat(q.w, q.x, q.y, q.z);
    }
    if (k.has("scale")) {
      k.vector<3>("scale", v, kCoordinate.lo, kCoordinate.hi);
      key.scale = v;
    }
    if (k.has("fov_y_deg")) {
      if (!camera) fail(at + "/fov_y_deg", "only camera keys have a field of view");
      float fov = 0.0f;
      k.number("fov_y_deg", fov, kFovY.lo, kFovY.hi);
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
    gr.number("fail_threshold", g.fail_threshold, kChannelDifference.lo, kChannelDifference.hi);
    gr.number("fail_percent", g.fail_percent, kPercent.lo, kPercent.hi);
    gr.number("warn_threshold", g.warn_threshold, kChannelDifference.lo, kChannelDifference.hi);
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
    mr.number("max", max, kPercent.lo, kPercent.hi);
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
      fr.number("max", v, kFlicker.lo, kFlicker.hi);
      f.max = v;
    }
    if (fr.has("min")) {
      fr.number("min", v, kFlicker.lo, kFlicker.hi);
      f.min = v;
    }
    if (fr.has("max_changed_pct")) {
      fr.number("max_changed_pct", v, kPercent.lo, kPercent.hi);
      f.max_changed_pct = v;
    }
    if (!f.max && !f.min && !f.max_changed_pct)
      fail(r.at("flicker"), "give max, min or max_changed_pct");
    if (fr.has("within")) {
      ObjectReader wr(fr.raw("within"), fr.at("within"));
      Aabb box;
      wr.vector<3>("min", box.min, kCoordinate.lo, kCoordinate.hi);
      wr.vector<3>("max", box.max, kCoordinate.lo, kCoordinate.hi);
      if (!wr.has("min") || !wr.has("max")) fail(fr.at("within"), "give min and max (world corners)");
      if (glm::any(glm::lessThan(box.max, box.min)))
        fail(wr.at("max"), "every coordinate of max must be at least min's");
      wr.finish();
      f.within = box;
    }
    fr.finish();
    pb.flicker = f;
  }
  if (r.has("compiles_after_prewarm")) {
    int n = 0;
    r.integer("compiles_after_prewarm", n, kCompiles.lo, kCompiles.hi);
    pb.max_compiles_after_prewarm = n;
  }
  if (r.has("probe_captures")) {
    ProbeExpect p;
    ObjectReader pr(r.raw("probe_captures"), r.at("probe_captures"));
    if (pr.has("count")) {
      int n = 0;
      pr.integer("count", n, kRepeat.lo, kRepeat.hi);
      p.captures = std::uint64_t(n);
    }
    if (pr.has("frames")) p.frames = read_frames(pr.raw("frames"), pr.at("frames"), pb.frames);
    pr.finish();
    pb.probes = p;
  }
  r.integer("gl_errors", pb.max_gl_errors, kGlErrors.lo, kGlErrors.hi);
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
    qr.number("max", max, kRatio.lo, kRatio.hi);
    q.max = max;
    qr.finish();
    pb.frame_time_ratio = q;
  }
  if (r.has("flat_resources")) {
    FlatExpect q;
    ObjectReader qr(r.raw("flat_resources"), r.at("flat_resources"));
    qr.integer("after", q.after, 0, pb.frames - 1);
    qr.integer("period", q.period, kRepeat.lo, kRepeat.hi);
    float mib = float(q.max_rss_growth_mib);
    qr.number("max_rss_growth_mib", mib, kRssGrowthMib.lo, kRssGrowthMib.hi);
    q.max_rss_growth_mib = mib;
    int objects = 0;
    qr.integer("max_gl_object_growth", objects, kGlObjectGrowth.lo, kGlObjectGrowth.hi);
    q.max_gl_object_growth = objects;
    qr.finish();
    pb.flat_resources = q;
  }
  r.finish();
}


// A parsed playback document: the checks and defaults.
Result<Playback> playback_from(const json& doc, const fs::path& file) {
  Playback pb;
  pb.file = file;
  const fs::path base = file.parent_path();
  try {
    ObjectReader r(doc, "");
    int version = kFormatVersion;
    r.integer("kaskad_playback", version, 1, kFormatVersion);
    std::string schema;  // "$schema": the file's JSON Schema, for editors (`kaskad schema`)
    r.string("$schema", schema);
    std::string scene;
    r.string("scene", scene);
    if (scene.empty()) fail("/scene", "name the scene file (.json, .gltf or .glb)");
    pb.scene = base / scene;
    if (r.has("size")) {
      glm::vec2 size;
      r.vector<2>("size", size, kSize.lo, kSize.hi);
      if (size.x != std::floor(size.x) || size.y != std::floor(size.y))
        fail("/size", "expected whole pixels");
      pb.width = int(size.x);
      pb.height = int(size.y);
    }
    r.integer("frames", pb.frames, kFrameCount.lo, kFrameCount.hi);
    float dt = float(pb.dt);
    r.number("dt", dt, kDt.lo, kDt.hi);
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
          ev.add = std::make_shared<const json>(er.raw("add"));
        }
        const int kinds = !ev.assignment.empty() + !ev.remove.empty() + bool(ev.add);
        if (kinds != 1)
          fail(at, "an event has one of set (\"key=value\"), add (an entity block) or remove (a "
                   "name); or give keys to move an entity");
        if (!ev.assignment.empty() && ev.assignment.find('=') == std::string::npos)
          fail(er.at("set"), "expected \"key=value\"");
        int every = 0;
        er.integer("every", every, kRepeat.lo, kRepeat.hi);
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
      cr.integer("every", every, kRepeat.lo, kRepeat.hi);
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

}  // namespace kaskad
