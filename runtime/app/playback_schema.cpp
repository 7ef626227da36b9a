// The JSON Schema of playback files, written as playback_file.cpp reads them: the same keys, the
// limits of playback_internal.h, closed objects where the reader refuses unknown keys. Ranges
// that depend on the file itself (a frame below "frames", an event's t within the run) are
// stated as the widest the reader could take; the reader checks the rest.
#include <nlohmann/json.hpp>

#include "runtime/app/playback.h"
#include "runtime/app/playback_internal.h"
#include "runtime/core/json_reader.h"

namespace kaskad {
namespace {

using json = nlohmann::json;
using namespace playback_detail;
using json_reader::num;

constexpr const char* kDraft = "https://json-schema.org/draft/2020-12/schema";

/// A closed object: only `props` (the reader refuses other keys, listing the valid ones).
json object(json props, const std::string& description) {
  return {{"type", "object"},
          {"properties", std::move(props)},
          {"additionalProperties", false},
          {"description", description}};
}

json integer(Bounds<int> b, const std::string& description) {
  return {{"type", "integer"}, {"minimum", b.lo}, {"maximum", b.hi}, {"description", description}};
}

json number(Bounds<float> b, const std::string& description) {
  return {{"type", "number"},
          {"minimum", num(b.lo)},
          {"maximum", num(b.hi)},
          {"description", description}};
}

json numbers(int n, Bounds<float> b, const std::string& description) {
  json j = number(b, description);
  j.erase("description");
  return {{"type", "array"},
          {"minItems", n},
          {"maxItems", n},
          {"items", j},
          {"description", description}};
}

json text(const std::string& description) {
  return {{"type", "string"}, {"description", description}};
}

/// A "key=value" assignment, as --set takes it.
json assignment(const std::string& description) {
  return {{"type", "string"}, {"pattern", "="}, {"description", description}};
}

/// Frame indices; each below the file's "frames" (the reader checks that bound).
json frames(const std::string& description) {
  return {{"type", "array"},
          {"items", {{"type", "integer"}, {"minimum", 0}, {"maximum", kMaxFrames - 1}}},
          {"description", description}};
}

json frame(const std::string& description) {
  return integer({0, kMaxFrames - 1}, description + " (below frames)");
}

json track(bool camera) {
  json key = {
      {"t", number(kKeyTime, "Time of the key, seconds; times increase")},
      {"position", numbers(3, kCoordinate, "World position")},
      {"move", numbers(3, kCoordinate,
                       "Metres along the entity's right, up and forward axes from its pose at "
                       "load; a track's keys all use position or all move")},
      {"look_at", numbers(3, kCoordinate, "A world point to face; needs position")},
      {"rotation", numbers(4, kQuaternion, "Quaternion x, y, z, w")},
      {"scale", numbers(3, kCoordinate, "Scale along the local axes")},
  };
  if (camera) key["fov_y_deg"] = number(kFovY, "Vertical field of view, degrees");
  json k = object(std::move(key), "A pose at a time; fields a key leaves out are interpolated "
                                  "between the keys that have them");
  k["required"] = {"t"};
  k["not"] = {{"anyOf", {{{"required", {"position", "move"}}}, {{"required", {"look_at", "rotation"}}}}}};
  k["dependentRequired"] = {{"look_at", {"position"}}};
  json interpolation = json::array();
  for (const auto& [name, value] : kInterpolations) interpolation.push_back(name);
  json props = {
      {"interpolation", {{"enum", interpolation}, {"description", "How positions go between keys"}}},
      {"loop", {{"type", "boolean"}, {"description", "Times wrap at the last key"}}},
      {"keys", {{"type", "array"}, {"minItems", 1}, {"items", k}, {"description", "Sorted by t"}}},
  };
  if (!camera) props["entity"] = {{"type", "string"}, {"minLength", 1}, {"description", "The entity the keys move"}};
  json j = object(std::move(props), camera ? "Keyframes of the scene's rendering camera"
                                           : "Keyframes of a named entity");
  j["required"] = camera ? json{"keys"} : json{"entity", "keys"};
  return j;
}

json event() {
  json j = object(
      {{"frame", frame("The frame the event comes before")},
       {"t", {{"type", "number"}, {"minimum", 0}, {"description", "Or the time, seconds (rounded to a frame)"}}},
       {"set", assignment("A --set assignment")},
       {"add", {{"type", "object"}, {"description", "An entity block of a scene file to add"}}},
       {"remove", {{"type", "string"}, {"minLength", 1}, {"description", "The entity to remove, with its children"}}},
       {"every", integer(kRepeat, "Repeat every this many frames (0: once)")}},
      "A timeline event: one of set, add or remove, at a frame or time");
  j["oneOf"] = {{{"required", {"frame"}}}, {{"required", {"t"}}}};
  j["allOf"] = {{{"oneOf", {{{"required", {"set"}}}, {{"required", {"add"}}}, {{"required", {"remove"}}}}}}};
  return j;
}

json expectations() {
  json golden = object(
      {{"dir", text("Folder of the golden images, relative to the playback file (goldens/<stem>)")},
       {"fail_threshold", number(kChannelDifference, "Per-channel difference that makes a pixel fail")},
       {"fail_percent", number(kPercent, "% of pixels that may fail")},
       {"warn_threshold", number(kChannelDifference, "Per-channel difference that warns")},
       {"portable", {{"type", "boolean"}, {"description", "Pixels are not driver-specific"}}}},
      "Captured frames against golden images; needs captures");
  json misclassified = object(
      {{"frames", frames("The frames to check")},
       {"max", number(kPercent, "% of receivers away from edges that may disagree")}},
      "Shadowed receivers against the ray-traced reference");
  misclassified["required"] = {"frames"};
  json flicker = object(
      {{"from", frame("First frame of the range")},
       {"to", frame("Last frame of the range, after from")},
       {"max", number(kFlicker, "Most flicker")},
       {"min", number(kFlicker, "Flicker must be above this")},
       {"max_changed_pct", number(kPercent, "% of samples that may change by more than an 8-bit step")},
       {"within", [] {
          json box = object({{"min", numbers(3, kCoordinate, "World corner, least x, y, z")},
                             {"max", numbers(3, kCoordinate, "World corner, greatest x, y, z")}},
                            "Only the receiver points inside this world box");
          box["required"] = {"min", "max"};
          return box;
        }()}},
      "Shadow flicker over a frame range");
  flicker["anyOf"] = {{{"required", {"max"}}}, {{"required", {"min"}}}, {{"required", {"max_changed_pct"}}}};
  json probes = object({{"count", integer(kRepeat, "Captures completed over the run, all probes")},
                        {"frames", frames("The frames on which a capture completed, exactly")}},
                       "Reflection probe captures");
  json range = frames("[from, to], from < to");
  range["minItems"] = 2;
  range["maxItems"] = 2;
  range["uniqueItems"] = true;
  json ratio = object({{"a", range}, {"b", range},
                       {"max", number(kRatio, "Most median frame time of b over a's")}},
                      "Median frame time of range b over range a");
  ratio["required"] = {"a", "b"};
  json flat = object(
      {{"after", frame("The warm-up frame the rest is measured against")},
       {"period", integer(kRepeat, "Frames after which the playback state repeats (0: none)")},
       {"max_rss_growth_mib", number(kRssGrowthMib, "Resident memory growth allowed, MiB")},
       {"max_gl_object_growth", integer(kGlObjectGrowth, "Live GL object growth allowed")}},
      "Memory and live GL objects stay flat after warm-up");
  return object({{"golden", golden},
                 {"misclassified_pct", misclassified},
                 {"flicker", flicker},
                 {"compiles_after_prewarm", integer(kCompiles, "Shader programs made after pre-warm")},
                 {"probe_captures", probes},
                 {"gl_errors", integer(kGlErrors, "GL errors allowed")},
                 {"frame_time_ratio", ratio},
                 {"flat_resources", flat}},
                "What must hold after the run");
}

}  // namespace

json playback_schema() {
  json size = numbers(2, kSize, "Output width and height, whole pixels");
  size["items"]["type"] = "integer";
  json sets = {{"type", "array"}, {"items", assignment("")}, {"description", "--set assignments applied at load"}};
  sets["items"].erase("description");
  json timeline = {{"type", "array"},
                   {"items", {{"if", {{"type", "object"}, {"required", {"keys"}}}},
                              {"then", track(false)},
                              {"else", event()}}},
                   {"description", "Events, and tracks (entries with keys)"}};
  json capture = object({{"frames", frames("Frames whose colour image is written")},
                         {"every", integer(kRepeat, "And every this many frames (0: none)")},
                         {"aovs", {{"type", "boolean"}, {"description", "Also their AOV EXR"}}}},
                        "Which frames to write");
  json j = object(
      {{"$schema", text("This schema's address, for editors")},
       {"kaskad_playback", integer({1, kFormatVersion}, "Format version")},
       {"scene", {{"type", "string"}, {"minLength", 1}, {"description", "Scene file (.json, .gltf or .glb), relative to the playback file"}}},
       {"size", size},
       {"frames", integer(kFrameCount, "Frames to run")},
       {"dt", number(kDt, "Seconds per frame")},
       {"set", sets},
       {"camera", track(true)},
       {"timeline", timeline},
       {"capture", capture},
       {"expect", expectations()}},
      "A Kaskad playback file (docs/guide/playback.md)");
  j["required"] = {"scene"};
  j["$schema"] = kDraft;
  j["title"] = "Kaskad playback";
  return j;
}

}  // namespace kaskad
