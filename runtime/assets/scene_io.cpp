#include "runtime/assets/scene_io.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/euler_angles.hpp>

#include "components/camera.h"
#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/name.h"
#include "components/probe_state.h"
#include "components/reflector.h"
#include "components/transform.h"
#include "runtime/assets/env_lighting.h"
#include "runtime/assets/gltf_loader.h"
#include "runtime/assets/material_file.h"
#include "runtime/assets/primitives.h"
#include "runtime/assets/reflector_io.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/field_io.h"
#include "runtime/core/file_io.h"
#include "runtime/core/json_reader.h"
#include "runtime/core/log.h"

namespace kaskad {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;
using field_io::read_fields;
using field_io::write_fields;
using json_reader::ContentError;
using json_reader::ObjectReader;
using json_reader::fail;
using json_reader::join;
using json_reader::num;
using json_reader::parse_json_file;
using json_reader::type_name;
using json_reader::vec;

constexpr int kFormatVersion = 1;

constexpr float kBig = float(kMaxCoordinate);

// The table's fields and ranges (components/shadow_settings.h), then the rules across fields
// (validate_shadow_settings(), whose message starts with the bad key).
void read_shadow(ObjectReader& r, ShadowSettings& s) {
  read_fields(r, s);
  r.finish();
  if (std::string bad = validate_shadow_settings(s); !bad.empty())
    fail(r.at(bad.substr(0, bad.find(' ')).c_str()), bad);
}

json write_shadow(const ShadowSettings& s, const ShadowSettings* defaults) {
  return write_fields(s, defaults);
}

// Rotation from exactly one of: rotation (quaternion x,y,z,w as in glTF), euler_deg (XYZ),
// look_at (a world point, needs the translation) or direction (the -Z axis in world space).
void read_rotation(ObjectReader& r, Transform& t) {
  int given = 0;
  for (const char* k : {"rotation", "euler_deg", "look_at", "direction"}) given += r.has(k);
  if (given > 1)
    fail(r.at("rotation"), "give only one of rotation, euler_deg, look_at, direction");
  if (r.has("rotation")) {
    glm::vec4 q{0, 0, 0, 1};
    r.vector<4>("rotation", q, -2.0f, 2.0f);
    const float len = glm::length(q);
    if (len < 1e-6f) fail(r.at("rotation"), "quaternion has zero length");
    // Renormalise only what is visibly off: a saved unit quaternion must read back bit-exact.
    if (std::abs(len - 1.0f) > 1e-5f) q /= len;
    t.rotation = glm::quat(q.w, q.x, q.y, q.z);
  } else if (r.has("euler_deg")) {
    glm::vec3 e{0.0f};
    r.vector<3>("euler_deg", e, -36000.0f, 36000.0f);
    t.rotation = glm::quat_cast(glm::eulerAngleXYZ(glm::radians(e.x), glm::radians(e.y),
                                                   glm::radians(e.z)));
  } else if (r.has("look_at") || r.has("direction")) {
    glm::vec3 dir;
    if (r.has("look_at")) {
      glm::vec3 target{0.0f};
      r.vector<3>("look_at", target, -kBig, kBig);
      dir = target - t.translation;
    } else {
      dir = glm::vec3(0.0f);
      r.vector<3>("direction", dir, -kBig, kBig);
    }
    const char* key = r.has("look_at") ? "look_at" : "direction";
    if (glm::length(dir) < 1e-6f) fail(r.at(key), "direction has zero length");
    t.rotation = look_rotation(glm::normalize(dir));
  }
}

// An inline material block: the built-in parameters, features derived from the values.
Material read_inline_material(ObjectReader& mr) {
  Material m;
  read_fields(mr, m);
  mr.finish();
  m.features = derive_material_features(m);
  return m;
}

void read_render(ObjectReader& r, RenderSettings& s) {
  read_fields(r, s);
  // Exposure in EV (stops): the scale is 2^EV. Either form, not both; saved as `exposure`.
  if (r.has("exposure_ev")) {
    if (r.has("exposure"))
      fail(r.at("exposure_ev"), "give exposure (a scale) or exposure_ev (stops), not both");
    float ev = 0.0f;
    r.number("exposure_ev", ev, kMinExposureEv, kMaxExposureEv);
    s.exposure = std::exp2(ev);
  }
  r.finish();
}

// One reader per component block, shared by scene files and --set on imported entities.
void read_transform(ObjectReader& tr, Transform& t) {
  tr.vector<3>("translation", t.translation, -kBig, kBig);
  tr.vector<3>("scale", t.scale, -kBig, kBig);
  read_rotation(tr, t);
}

void read_renderer(ObjectReader& rr, MeshRenderer& m) {
  read_fields(rr, m);
  rr.finish();
}

// Returns whether the block says cast_shadows.
bool read_light(ObjectReader& lr, Light& l) {
  const bool cast_given = lr.has("cast_shadows");
  const bool size_given = lr.has("size");
  read_fields(lr, l);
  lr.finish();
  if (l.type == LightType::directional && l.radius > 0.0f)
    fail(lr.at("radius"), "is for spot and point lights; a directional light's size is "
                          "angular_size_deg");
  if (l.type == LightType::area && l.radius > 0.0f)
    fail(lr.at("radius"), "is for spot and point lights; an area light's size is size [width, "
                          "height] (metres)");
  if (l.type != LightType::directional && l.angular_size_deg > 0.0f)
    fail(lr.at("angular_size_deg"), "is for directional lights; a spot or point light's size is "
                                    "radius (metres), an area light's size [width, height]");
  if (size_given && l.type != LightType::area)
    fail(lr.at("size"), "is for area lights (type \"area\"); a spot or point light's size is "
                        "radius, a directional light's angular_size_deg");
  if (l.type == LightType::area && l.outer_cone_deg > 80.0f)
    fail(lr.at("outer_cone_deg"), "of an area light must be at most 80 (its shadow map is one "
                                  "perspective map over the cone), was " + json(num(l.outer_cone_deg)).dump());
  if (l.inner_cone_deg > l.outer_cone_deg)  // both values: a --set of one names the other
    fail(lr.at("inner_cone_deg"), "must not exceed outer_cone_deg (" +
                                      json(num(l.outer_cone_deg)).dump() + "), was " +
                                      json(num(l.inner_cone_deg)).dump());
  return cast_given;
}

void read_camera(ObjectReader& cr, Camera& c) {
  read_fields(cr, c);
  cr.finish();
  if (!(c.far > c.near)) fail(cr.at("far"), "far must be greater than near");
}

struct Pending {
  ecs::Entity entity;
  std::string parent;
  std::string where;
};

// The first directional light of a file, and whether its block says cast_shadows.
struct FirstSun {
  ecs::Entity entity = ecs::kNullEntity;
  bool cast_shadows_given = false;
};

std::vector<NodeOverride> read_node_overrides(const json& nodes, const std::string& where);
json write_node_overrides(const Scene& scene, ecs::Entity model);

void parse_entity(const json& j, const std::string& path, Scene& scene,
                  std::map<std::string, ecs::Entity>& by_name, std::vector<Pending>& parents,
                  FirstSun& first_sun) {
  ecs::World& w = scene.world;
  ObjectReader r(j, path);
  const ecs::Entity e = w.create();
  std::string name;
  r.string("name", name);
  if (!name.empty()) {
    if (name.find('.') != std::string::npos || name.find('=') != std::string::npos)
      fail(r.at("name"), "names may not contain '.' or '=' (they are used in --set keys)");
    if (by_name.count(name)) fail(r.at("name"), "duplicate entity name '" + name + "'");
    by_name[name] = e;
    w.emplace<Name>(e, Name{name});
  }
  Transform t;
  if (r.has("transform")) {
    ObjectReader tr(r.raw("transform"), r.at("transform"));
    read_transform(tr, t);
    std::string parent;
    tr.string("parent", parent);
    if (!parent.empty()) parents.push_back({e, parent, tr.at("parent")});
    tr.finish();
  }
  w.emplace<Transform>(e, t);

  const bool has_primitive = r.has("primitive"), has_model = r.has("model");
  if (has_primitive && has_model) fail(path, "an entity has either a primitive or a model, not both");
  if (has_primitive) {
    PrimitiveMesh p;
    ObjectReader pr(r.raw("primitive"), r.at("primitive"));
    read_fields(pr, p);
    if (pr.has("tiles")) {
      if (p.shape != PrimitiveShape::terrain && p.tiles != 1)
        fail(r.at("primitive") + "/tiles", "tiles applies to the terrain shape only");
      if (p.segments % p.tiles != 0)
        fail(r.at("primitive") + "/tiles", "segments (" + std::to_string(p.segments) +
                                               ") must be a multiple of tiles (" +
                                               std::to_string(p.tiles) + ")");
    }
    pr.finish();
    w.emplace<PrimitiveMesh>(e, p);
  }
  if (has_model) {
    ModelRef m;
    ObjectReader mr(r.raw("model"), r.at("model"));
    mr.string("path", m.path);
    if (mr.has("nodes")) m.nodes = read_node_overrides(mr.raw("nodes"), mr.at("nodes"));
    mr.finish();
    if (m.path.empty()) fail(r.at("model") + "/path", "a model needs a path");
    w.emplace<ModelRef>(e, m);
  }
  if (r.has("renderer")) {
    if (!has_primitive && !has_model) fail(r.at("renderer"), "renderer needs a primitive or model");
    MeshRenderer mrend;
    ObjectReader rr(r.raw("renderer"), r.at("renderer"));
    read_renderer(rr, mrend);
    w.emplace<MeshRenderer>(e, mrend);
  } else if (has_primitive || has_model) {
    w.emplace<MeshRenderer>(e);
  }
  if (r.has("material")) {
    if (!has_primitive)
      fail(r.at("material"), has_model ? "models use their glTF materials; remove this block"
                                       : "material needs a primitive");
    const json& mj = r.raw("material");
    if (mj.is_object() && mj.contains("file")) {
      ObjectReader fr(mj, r.at("material"));
      MaterialRef ref;
      fr.string("file", ref.path);
      fr.finish();  // a file reference stands alone: no inline fields beside it
      if (ref.path.empty()) fail(fr.at("file"), "empty material file path");
      w.emplace<MaterialRef>(e, ref);
      w.emplace<Material>(e);
    } else {
      ObjectReader mr(mj, r.at("material"));
      w.emplace<Material>(e, read_inline_material(mr));
    }
  } else if (has_primitive) {
    w.emplace<Material>(e);
  }
  if (r.has("light")) {
    Light l;
    ObjectReader lr(r.raw("light"), r.at("light"));
    const bool cast_given = read_light(lr, l);
    if (l.type == LightType::directional && !first_sun.entity.valid())
      first_sun = {e, cast_given};
    w.emplace<Light>(e, l);
    ShadowSettings s = scene.shadow_defaults;
    if (r.has("shadow")) {
      ObjectReader sr(r.raw("shadow"), r.at("shadow"));
      read_shadow(sr, s);
    }
    w.emplace<ShadowSettings>(e, s);
  } else if (r.has("shadow")) {
    fail(r.at("shadow"), "shadow settings belong to an entity with a light");
  }
  if (r.has("reflector")) {
    if (!has_primitive && !has_model) fail(r.at("reflector"), "a reflector needs a primitive or model");
    Reflector refl;
    ObjectReader rr(r.raw("reflector"), r.at("reflector"));
    read_reflector(rr, refl);
    w.emplace<Reflector>(e, refl);
  }
  if (r.has("camera")) {
    Camera c;
    ObjectReader cr(r.raw("camera"), r.at("camera"));
    read_camera(cr, c);
    w.emplace<Camera>(e, c);
  }
  r.finish();
}

// Paths are relative to the scene file: rebased when the scene is written somewhere else.
std::string rebase_path(const Scene& scene, const fs::path& base, const std::string& path) {
  if (base.empty() || path.empty() || !fs::path(path).is_relative()) return path;
  const fs::path abs = fs::absolute(scene.file.parent_path() / path).lexically_normal();
  return abs.lexically_relative(fs::absolute(base).lexically_normal()).generic_string();
}

json entity_to_json(const Scene& scene, ecs::Entity e, const fs::path& base) {
  const ecs::World& w = scene.world;
  json j = json::object();
  if (const auto* n = w.try_get<Name>(e)) j["name"] = n->value;
  if (const auto* t = w.try_get<Transform>(e)) {
    json tj = {{"translation", vec(t->translation)},
               {"rotation", json::array({num(t->rotation.x), num(t->rotation.y),
                                         num(t->rotation.z), num(t->rotation.w)})},
               {"scale", vec(t->scale)}};
    if (t->parent.valid() && w.alive(t->parent))
      if (const auto* pn = w.try_get<Name>(t->parent)) tj["parent"] = pn->value;
    j["transform"] = tj;
  }
  if (const auto* p = w.try_get<PrimitiveMesh>(e)) {
    j["primitive"] = write_fields(*p);
    if (p->shape != PrimitiveShape::terrain) j["primitive"].erase("tiles");
  }
  auto rebase = [&](const std::string& path) { return rebase_path(scene, base, path); };
  if (const auto* m = w.try_get<ModelRef>(e)) {
    j["model"] = {{"path", rebase(m->path)}};
    if (!m->nodes.empty()) j["model"]["nodes"] = write_node_overrides(scene, e);
  }
  if (const auto* mr = w.try_get<MeshRenderer>(e))
    j["renderer"] = write_fields(*mr);
  if (const auto* ref = w.try_get<MaterialRef>(e)) {
    j["material"] = {{"file", rebase(ref->path)}};
  } else if (const auto* m = w.try_get<Material>(e)) {
    j["material"] = write_fields(*m);
  }
  if (const auto* l = w.try_get<Light>(e)) {
    j["light"] = write_fields(*l);
    if (l->type != LightType::area) j["light"].erase("size");
    if (const auto* s = w.try_get<ShadowSettings>(e)) {
      json sj = write_shadow(*s, &scene.shadow_defaults);
      if (!sj.empty()) j["shadow"] = sj;
    }
  }
  if (const auto* refl = w.try_get<Reflector>(e)) {
    j["reflector"] = reflector_to_json(*refl);
    if (!refl->file.empty()) j["reflector"]["file"] = rebase(refl->file);
  }
  if (const auto* c = w.try_get<Camera>(e)) {
    j["camera"] = write_fields(*c);
  }
  return j;
}

bool entity_less(ecs::Entity a, ecs::Entity b) { return a.index < b.index; }

}  // namespace

Result<json> read_scene_document(const fs::path& file) {
  const std::string ext = lowercase_extension(file);
  if (ext == ".gltf" || ext == ".glb") {
    // Inspect the file for its own lights and cameras; the real import happens in instantiate.
    Scene probe;
    auto report = import_gltf(file, probe.world, probe.assets, ecs::kNullEntity, ecs::kNullEntity,
                              false);
    if (!report) return report.error();
    // A bare model gets a ground to catch its shadow; saved as "on", so the saved scene file
    // renders the same.
    json doc = {{"kaskad_scene", kFormatVersion},
                {"render", {{"ground", "on"}}},
                {"entities", json::array()}};
    doc["entities"].push_back({{"name", "model"}, {"model", {{"path", file.filename().string()}}}});
    if (report->cameras == 0) {
      // Default camera: looks at the model from the front, slightly above; auto_frame backs it
      // off until the bounds fit.
      doc["entities"].push_back(
          {{"name", "camera"},
           {"transform", {{"direction", {-0.45, -0.35, -0.82}}}},
           {"camera", {{"auto_frame", true}, {"active", true}}}});
    }
    if (report->lights == 0) {
      doc["entities"].push_back(
          {{"name", "sun"},
           {"transform", {{"direction", {0.3, -0.75, -0.6}}}},
           {"light", {{"type", "directional"}, {"intensity", 2.5}, {"cast_shadows", true}}}});
    }
    return doc;
  }
  if (ext != ".json")
    return Error{file.string(), "", "unknown scene file type '" + ext + "' (expected .json, .gltf or .glb)"};
  return parse_json_file(file);
}

namespace {

std::vector<std::string> split_key(const std::string& key) {
  std::vector<std::string> parts;
  for (std::size_t start = 0;;) {
    const auto dot = key.find('.', start);
    parts.push_back(key.substr(start, dot - start));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return parts;
}

std::string keys_of(const json& j) {
  std::vector<std::string> k;
  if (j.is_object())
    for (auto it = j.begin(); it != j.end(); ++it) k.push_back(it.key());
  return join(k);
}

// The ways of giving a transform's rotation; a scene file takes any one of them.
constexpr std::array<const char*, 4> kRotationKeys = {"rotation", "euler_deg", "look_at",
                                                     "direction"};

// Sets the field at `parts` (below `node`, an entity or settings block) to the value `text`
// (JSON, else a bare string). `key` is the whole --set key, for messages.
Status set_field(json* node, const std::vector<std::string>& parts, const std::string& key,
                 const std::string& text) {
  if (parts.empty()) return Error{"--set", key, "name a field; valid keys: " + keys_of(*node)};
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string& p = parts[i];
    if (node->is_object()) {
      // A transform's rotation may be set in any form a scene file accepts: the new form
      // replaces the old one.
      const bool rotation_form =
          i + 1 == parts.size() && i > 0 && parts[i - 1] == "transform" &&
          std::find(kRotationKeys.begin(), kRotationKeys.end(), p) != kRotationKeys.end();
      if (rotation_form) {
        for (const char* k : kRotationKeys) node->erase(k);
        (*node)[p] = nullptr;
      }
      // Likewise the exposure, as a scale or in EV (the saved form has the scale).
      if (i == 0 && key.starts_with("render.") && (p == "exposure" || p == "exposure_ev")) {
        node->erase("exposure");
        node->erase("exposure_ev");
        (*node)[p] = nullptr;
      }
      if (!node->contains(p))
        return Error{"--set", key,
                     "unknown key '" + p + "'; valid keys here: " + keys_of(*node) +
                         (i > 0 && parts[i - 1] == "transform"
                              ? " (rotation also as euler_deg, look_at or direction)"
                              : "")};
      node = &(*node)[p];
    } else if (node->is_array()) {
      std::size_t idx = 0;
      auto [ptr, ec] = std::from_chars(p.data(), p.data() + p.size(), idx);
      if (ec != std::errc() || ptr != p.data() + p.size() || idx >= node->size())
        return Error{"--set", key, "'" + p + "' is not an index in [0, " +
                                       std::to_string(node->size()) + ")"};
      node = &(*node)[idx];
    } else {
      return Error{"--set", key, "'" + parts[i - 1] + "' is a value, it has no field '" + p + "'"};
    }
  }
  json value = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (value.is_discarded()) {
    // A bare word is a string (4k_sky.hdr); a well-formed number JSON cannot hold (1e999) is an
    // error, not the string "1e999".
    static const std::regex kNumber(R"(-?[0-9]+(\.[0-9]+)?([eE][+-]?[0-9]+)?)");
    if (std::regex_match(text, kNumber)) {
      auto parsed = json_reader::parse_json_text(text, "--set");
      return Error{"--set", key, std::string("value '") + text + "' is not a valid number" +
                                     (parsed ? std::string() : ": " + parsed.error().message)};
    }
    value = text;
  }
  *node = value;
  return {};
}

// Reads `block` over entity e's component C with the scene file's reader for it (validated,
// the fields it does not name kept).
template <typename C, typename Read>
void reread(ecs::World& w, ecs::Entity e, const json& block, const std::string& where, Read read) {
  C c = w.get<C>(e);
  ObjectReader r(block, where);
  read(r, c);
  w.get<C>(e) = c;
}

// Whether the first part of `key` names a settings section or an entity of the document.
bool document_holds(const json& doc, const std::string& key) {
  const std::string first = key.substr(0, key.find('.'));
  if (doc.contains(first) && first != "entities" && first != "kaskad_scene") return true;
  if (doc.contains("entities") && doc["entities"].is_array())
    for (const auto& ent : doc["entities"])
      if (ent.is_object() && ent.contains("name") && ent["name"] == first) return true;
  return false;
}

// Entity e's sections as apply_entity_override() and a model's node blocks set them: transform
// without its parent (kept as it is), shadow with every field, the rest as scene files hold them.
json settable_sections(const Scene& scene, ecs::Entity e) {
  json ej = entity_to_json(scene, e, {});
  if (const auto* s = scene.world.try_get<ShadowSettings>(e))
    ej["shadow"] = write_shadow(*s, nullptr);
  ej.erase("name");
  if (ej.contains("transform")) ej["transform"].erase("parent");
  return ej;
}

// Reads `block` over entity e's `section` with the scene file's reader for it (validated, the
// fields it does not name kept). False for a section a loaded entity does not take.
bool read_section(ecs::World& w, ecs::Entity e, const std::string& section, const json& block,
                  const std::string& where) {
  if (section == "transform") {
    reread<Transform>(w, e, block, where, [](ObjectReader& r, Transform& t) {
      read_transform(r, t);
      r.finish();
    });
  } else if (section == "light" && w.has<Light>(e)) {
    reread<Light>(w, e, block, where, [](ObjectReader& r, Light& l) { read_light(r, l); });
  } else if (section == "shadow" && w.has<ShadowSettings>(e)) {
    reread<ShadowSettings>(w, e, block, where, read_shadow);
  } else if (section == "camera" && w.has<Camera>(e)) {
    reread<Camera>(w, e, block, where, read_camera);
  } else if (section == "renderer" && w.has<MeshRenderer>(e)) {
    reread<MeshRenderer>(w, e, block, where, read_renderer);
  } else if (section == "reflector" && w.has<Reflector>(e)) {
    reread<Reflector>(w, e, block, where, read_reflector);
  } else {
    return false;
  }
  return true;
}

// The sections a model's node block may hold (a glTF node has no reflector).
constexpr std::array<const char*, 5> kNodeSections = {"transform", "light", "shadow", "camera",
                                                      "renderer"};

// The field a node override records for a field set in `section`: any form of a rotation is
// saved as the rotation.
std::string recorded_field(const std::string& section, const std::string& field) {
  if (section == "transform" &&
      std::find(kRotationKeys.begin(), kRotationKeys.end(), field) != kRotationKeys.end())
    return "rotation";
  return field;
}

// Adds `field` of the override's section to the fields it records (once; any rotation form as
// the rotation).
void record_field(NodeOverride& o, const std::string& field) {
  const std::string f = recorded_field(o.section, field);
  if (std::find(o.fields.begin(), o.fields.end(), f) == o.fields.end()) o.fields.push_back(f);
}

// The entities imported for model entity `model` that are named `node`.
std::vector<ecs::Entity> nodes_named(const ecs::World& w, ecs::Entity model,
                                     const std::string& node) {
  std::vector<ecs::Entity> found;
  w.view<Imported>().each([&](ecs::Entity x, const Imported& imp) {
    if (imp.source != model) return;
    if (const auto* n = w.try_get<Name>(x); n && n->value == node) found.push_back(x);
  });
  std::sort(found.begin(), found.end(), entity_less);
  return found;
}

// A model's `nodes` block: node name -> section -> fields. Checked for shape here; the values
// are read when the model is imported, over what its file gives.
std::vector<NodeOverride> read_node_overrides(const json& nodes, const std::string& where) {
  if (!nodes.is_object()) fail(where, "expected an object of node names, got " + type_name(nodes));
  std::vector<NodeOverride> out;
  for (auto n = nodes.begin(); n != nodes.end(); ++n) {
    const std::string at = where + "/" + n.key();
    if (n.key().empty()) fail(at, "a node name may not be empty");
    if (!n.value().is_object())
      fail(at, "expected an object of sections, got " + type_name(n.value()));
    for (auto s = n.value().begin(); s != n.value().end(); ++s) {
      const std::string sat = at + "/" + s.key();
      if (std::find_if(kNodeSections.begin(), kNodeSections.end(),
                       [&](const char* k) { return s.key() == k; }) == kNodeSections.end())
        fail(sat, "unknown section '" + s.key() +
                      "'; a node takes transform, light, shadow, "
                      "camera and renderer");
      if (!s.value().is_object()) fail(sat, "expected an object, got " + type_name(s.value()));
      if (s.key() == "transform" && s.value().contains("parent"))
        fail(sat + "/parent", "an imported node keeps its parent from the model file");
      NodeOverride o{n.key(), s.key(), {}, s.value().dump(), sat};
      for (auto f = s.value().begin(); f != s.value().end(); ++f) record_field(o, f.key());
      out.push_back(std::move(o));
    }
  }
  return out;
}

// The `nodes` block written for model entity `model`: each set field's value as the node has it
// now, or the block as it was read while no node of the model has the name.
json write_node_overrides(const Scene& scene, ecs::Entity model) {
  json out = json::object();
  for (const NodeOverride& o : scene.world.get<ModelRef>(model).nodes) {
    const std::vector<ecs::Entity> found = nodes_named(scene.world, model, o.node);
    const json live = found.size() == 1 ? settable_sections(scene, found.front()) : json();
    json block = json::object();
    if (live.contains(o.section)) {
      for (const std::string& f : o.fields)
        if (live[o.section].contains(f)) block[f] = live[o.section][f];
    } else {
      block = json::parse(o.block, nullptr, /*allow_exceptions=*/false);
    }
    // An empty block says nothing (and a section the node lacks would not load).
    if (block.is_object() && !block.empty()) out[o.node][o.section] = block;
  }
  return out;
}

}  // namespace

ecs::Entity model_of(const ecs::World& w, ecs::Entity e) {
  const auto* imp = w.try_get<Imported>(e);
  if (!imp || !imp->source.valid() || !w.alive(imp->source) || !w.has<ModelRef>(imp->source))
    return ecs::kNullEntity;
  return imp->source;
}

void note_node_override(Scene& scene, ecs::Entity e, const std::string& section,
                        const std::vector<std::string>& fields) {
  ecs::World& w = scene.world;
  const ecs::Entity model = model_of(w, e);
  const auto* name = w.try_get<Name>(e);
  // A name two nodes of the model share could not be read back to one of them: not kept.
  if (!model.valid() || !name || nodes_named(w, model, name->value).size() != 1) return;
  std::vector<NodeOverride>& nodes = w.get<ModelRef>(model).nodes;
  auto it = std::find_if(nodes.begin(), nodes.end(), [&](const NodeOverride& o) {
    return o.node == name->value && o.section == section;
  });
  if (it == nodes.end())
    it = nodes.insert(nodes.end(), NodeOverride{name->value, section, {}, "{}", ""});
  for (const std::string& f : fields) record_field(*it, f);
}

json live_entity_sections(const Scene& scene, ecs::Entity e) {
  return settable_sections(scene, e);
}

Status apply_override(json& doc, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    return Error{"--set", assignment, "expected key=value, e.g. shadow.map_size=2048"};
  const std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  std::vector<std::string> parts = split_key(key);
  json* node = nullptr;
  if (doc.contains(parts[0]) && parts[0] != "entities" && parts[0] != "kaskad_scene") {
    node = &doc[parts[0]];
  } else {
    std::vector<std::string> names;
    for (auto& ent : doc["entities"]) {
      if (ent.contains("name") && ent["name"] == parts[0]) node = &ent;
      // An earlier override may have made a name anything (--set sun.name=5).
      if (ent.contains("name") && ent["name"].is_string()) names.push_back(ent["name"].get<std::string>());
    }
    if (!node)
      return Error{"--set", key, "no setting section or entity named '" + parts[0] +
                                     "'; sections: render, shadow; entities: " + join(names)};
  }
  parts.erase(parts.begin());
  return set_field(node, parts, key, text);
}

Status apply_live_override(Scene& scene, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    return Error{"--set", assignment, "expected key=value, e.g. shadow.map_size=2048"};
  const std::string section = assignment.substr(0, assignment.find('.'));
  if (section != "render" && section != "shadow") return apply_entity_override(scene, assignment);
  json doc = scene_to_json(scene);
  KASKAD_TRY(apply_override(doc, assignment));
  try {
    if (section == "render") {
      RenderSettings r = scene.render;
      ObjectReader rr(doc["render"], "/render");
      read_render(rr, r);
      std::swap(scene.render, r);
      if (Status st = load_environment(scene); !st) {
        scene.render = r;  // unchanged on error
        return st;
      }
      return {};
    }
    // Scene-wide shadow defaults: every light takes the new value unless it overrides that
    // field itself, as when the file is loaded.
    ShadowSettings defaults;
    ObjectReader sr(doc["shadow"], "/shadow");
    read_shadow(sr, defaults);
    std::vector<std::pair<ecs::Entity, ShadowSettings>> lights;
    scene.world.view<ShadowSettings>().each([&](ecs::Entity e, const ShadowSettings& own) {
      ShadowSettings s = defaults;
      const json own_fields = write_shadow(own, &scene.shadow_defaults);  // outlives the reader
      ObjectReader lr(own_fields, "/shadow");
      read_shadow(lr, s);
      lights.emplace_back(e, s);
    });
    for (auto& [e, s] : lights) scene.world.get<ShadowSettings>(e) = s;
    scene.shadow_defaults = defaults;
  } catch (const ContentError& err) {
    return Error{"--set", err.where, err.message};
  }
  return {};
}

Result<ecs::Entity> entity_for_key(const Scene& scene, const std::string& key) {
  const ecs::World& w = scene.world;
  // The longest entity name followed by '.' that starts the key: glTF names may hold dots.
  std::vector<std::pair<ecs::Entity, std::string>> named;
  w.view<Name>().each([&](ecs::Entity e, const Name& n) { named.emplace_back(e, n.value); });
  std::sort(named.begin(), named.end(),
            [](const auto& a, const auto& b) { return a.first.index < b.first.index; });
  std::vector<ecs::Entity> matches;
  std::size_t best = 0;
  for (const auto& [e, n] : named) {
    if (n.empty() || key.size() <= n.size() + 1 || key.compare(0, n.size(), n) != 0 ||
        key[n.size()] != '.')
      continue;
    if (n.size() > best) {
      best = n.size();
      matches.clear();
    }
    if (n.size() == best) matches.push_back(e);
  }
  if (matches.empty()) {
    std::vector<std::string> names;
    for (const auto& [e, n] : named)
      if (names.size() < 40) names.push_back(n);
    if (named.size() > names.size()) names.push_back("... (" + std::to_string(named.size()) +
                                                     " in all; `kaskad info SCENE` lists them)");
    return Error{"--set", key, "no setting section or entity named '" + key.substr(0, key.find('.')) +
                                   "'; sections: render, shadow; entities: " + join(names)};
  }
  if (matches.size() > 1)
    return Error{"--set", key,
                 std::to_string(matches.size()) + " entities are named '" + key.substr(0, best) +
                     "'; only a unique name can be set"};
  return matches.front();
}

Status apply_entity_override(Scene& scene, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    return Error{"--set", assignment, "expected key=value, e.g. shadow.map_size=2048"};
  const std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  ecs::World& w = scene.world;
  auto found = entity_for_key(scene, key);
  if (!found) return found.error();
  const ecs::Entity e = found.value();
  const std::string name = w.get<Name>(e).value;
  const std::size_t best = name.size();
  json ej = settable_sections(scene, e);
  const std::vector<std::string> parts = split_key(key.substr(best + 1));
  KASKAD_TRY(set_field(&ej, parts, key, text));
  const std::string& section = parts[0];
  const std::string where = "/" + name + "/" + section;
  try {
    if (!read_section(w, e, section, ej[section], where))
      return Error{"--set", key,
                   "'" + section + "' of '" + name +
                       "' cannot be set on a loaded entity; it takes transform, "
                       "light, shadow, camera, renderer and reflector"};
  } catch (const ContentError& err) {
    return Error{"--set", err.where, err.message};
  }
  // A glTF node's edit is kept in its model's nodes block, so that a save holds it.
  std::vector<std::string> fields;
  if (parts.size() > 1) {
    fields.push_back(parts[1]);
  } else if (ej[section].is_object()) {
    for (auto f = ej[section].begin(); f != ej[section].end(); ++f) fields.push_back(f.key());
  }
  note_node_override(scene, e, section, fields);
  return {};
}

Result<Scene> parse_scene(const json& doc, const fs::path& file) {
  Scene scene;
  scene.file = file;
  try {
    ObjectReader root(doc, "");
    int version = kFormatVersion;
    if (root.has("kaskad_scene") && root.raw("kaskad_scene").is_number_integer()) {
      const long long written = root.raw("kaskad_scene").get<long long>();
      if (written > kFormatVersion)
        fail(root.at("kaskad_scene"),
             "format version " + std::to_string(written) + " is newer than this build reads (" +
                 std::to_string(kFormatVersion) + "): written by a later Kaskad?");
    }
    root.integer("kaskad_scene", version, 1, kFormatVersion);
    std::string schema;  // "$schema": the file's JSON Schema, for editors (`kaskad schema`)
    root.string("$schema", schema);
    if (root.has("render")) {
      ObjectReader r(root.raw("render"), "/render");
      read_render(r, scene.render);
    }
    if (root.has("shadow")) {
      ObjectReader r(root.raw("shadow"), "/shadow");
      read_shadow(r, scene.shadow_defaults);
    }
    std::map<std::string, ecs::Entity> by_name;
    std::vector<Pending> parents;
    FirstSun first_sun;
    if (root.has("entities")) {
      const json& ents = root.raw("entities");
      if (!ents.is_array()) fail("/entities", "expected an array, got " + type_name(ents));
      for (std::size_t i = 0; i < ents.size(); ++i)
        parse_entity(ents[i], "/entities/" + std::to_string(i), scene, by_name, parents,
                     first_sun);
    }
    // A scene's first directional light casts shadows unless its block says false: a new
    // scene shows shadows before its author has found the field.
    if (first_sun.entity.valid() && !first_sun.cast_shadows_given)
      scene.world.get<Light>(first_sun.entity).cast_shadows = true;
    root.finish();
    for (const Pending& p : parents) {
      auto it = by_name.find(p.parent);
      if (it == by_name.end()) fail(p.where, "no entity named '" + p.parent + "'");
      if (it->second == p.entity) fail(p.where, "an entity cannot be its own parent");
      scene.world.get<Transform>(p.entity).parent = it->second;
    }
    // Parent cycles (a -> b -> a) are content errors here, with the names, rather than a
    // warning from the transform system every frame.
    std::map<ecs::Entity, std::string, bool (*)(ecs::Entity, ecs::Entity)> names(entity_less);
    for (const auto& [n, e] : by_name) names[e] = n;
    for (const Pending& p : parents) {
      std::string chain = names[p.entity];
      ecs::Entity at = scene.world.get<Transform>(p.entity).parent;
      for (std::size_t steps = 0; at.valid() && steps <= parents.size(); ++steps) {
        chain += " -> " + names[at];
        if (at == p.entity) fail(p.where, "parent cycle: " + chain);
        const Transform* t = scene.world.try_get<Transform>(at);
        at = t ? t->parent : ecs::kNullEntity;
      }
    }
  } catch (const ContentError& e) {
    return Error{file.string(), e.where, e.message};
  } catch (const json::exception& e) {
    return Error{file.string(), "", e.what()};
  }
  return scene;
}

namespace {

// A model file's first import: the model entity and the entities imported under it
// (Imported{first}), in entity order.
struct FirstImport {
  ecs::Entity first;
  std::vector<ecs::Entity> made;
};

// Gives entity e a copy of `originals`, the entities an earlier import made under `first`: the
// same meshes, textures and materials, so N instances of one model load and upload it once and
// draw it instanced. Parents are remapped into the copy; copied cameras are not active. Returns
// the copies. (Scanning every Imported entity per copy made loading N instances O(N^2): 5 s for
// 33,000 copies of a one-node model.)
std::vector<ecs::Entity> copy_import(ecs::World& w, const FirstImport& from, ecs::Entity e) {
  const ecs::Entity first = from.first;
  const std::vector<ecs::Entity>& originals = from.made;
  auto key = [](ecs::Entity x) { return (std::uint64_t(x.generation) << 32) | x.index; };
  std::map<std::uint64_t, ecs::Entity> copy_of;  // every copy first, so any parent maps
  std::vector<ecs::Entity> copies;
  for (ecs::Entity original : originals) copies.push_back(copy_of[key(original)] = w.create());
  for (ecs::Entity original : originals) {
    const ecs::Entity c = copy_of[key(original)];
    w.emplace<Imported>(c, Imported{e});
    if (const auto* n = w.try_get<Name>(original)) w.emplace<Name>(c, *n);
    if (const auto* t = w.try_get<Transform>(original)) {
      Transform copy = *t;
      if (copy.parent == first) {
        copy.parent = e;
      } else if (auto it = copy_of.find(key(copy.parent)); it != copy_of.end()) {
        copy.parent = it->second;
      }
      w.emplace<Transform>(c, copy);
    }
    if (const auto* m = w.try_get<MeshRenderer>(original)) w.emplace<MeshRenderer>(c, *m);
    if (const auto* m = w.try_get<Material>(original)) w.emplace<Material>(c, *m);
    if (const auto* l = w.try_get<Light>(original)) w.emplace<Light>(c, *l);
    if (const auto* sh = w.try_get<ShadowSettings>(original)) w.emplace<ShadowSettings>(c, *sh);
    if (const auto* cam = w.try_get<Camera>(original)) {
      Camera copy = *cam;
      copy.active = false;
      w.emplace<Camera>(c, copy);
    }
  }
  return copies;
}

// Imports entity e's glTF model (ModelRef): the meshes take e's renderer flags and layer, the
// lights the scene's shadow settings. `imported` (file -> the first entity that imported it):
// a file imported before is copied from that entity's import instead of read again.
// Returns the entities it made.
// `blame` (file and place) is named first when the model cannot be imported; by default the
// scene file's entity.
Result<std::vector<ecs::Entity>> import_model(
    Scene& scene, ecs::Entity e, bool activate_first_camera,
    std::map<std::string, FirstImport>* imported = nullptr,
    const std::optional<Error>& blame = std::nullopt) {
  ecs::World& w = scene.world;
  const fs::path path = scene.file.parent_path() / w.get<ModelRef>(e).path;
  std::error_code ec;
  const std::string file_key = fs::weakly_canonical(path, ec).string();
  const auto earlier = imported ? imported->find(file_key) : std::map<std::string, FirstImport>::iterator{};
  std::vector<ecs::Entity> made;  // the entities imported under e
  if (imported && earlier != imported->end()) {
    made = copy_import(w, earlier->second, e);
  } else {
    auto report = import_gltf(path, w, scene.assets, e, e, activate_first_camera);
    if (!report) {
      if (blame) return Error{blame->file, blame->where, report.error().to_string()};
      // A scene file's model: the scene and the entity come first, then the model's own error.
      if (lowercase_extension(scene.file) != ".json")
        return report.error();  // a glTF opened directly: its own error says it all
      const std::string name = w.has<Name>(e) ? w.get<Name>(e).value : std::string("?");
      return Error{scene.file.string(), "/" + name + "/model/path", report.error().to_string()};
    }
    // Once each: the editor reloads the scene on every undo.
    for (const auto& warning : report->warnings)
      log::warn_once("%s: %s", path.string().c_str(), warning.c_str());
    w.view<Imported>().each([&](ecs::Entity x, const Imported& imp) {
      if (imp.source == e) made.push_back(x);
    });
    std::sort(made.begin(), made.end(), entity_less);
    if (imported) imported->emplace(file_key, FirstImport{e, made});
  }
  // The model entity's renderer flags apply to everything imported under it; the scene's shadow
  // settings to the model's own lights as to any other (a glTF has none of its own); --set
  // ENTITY.shadow.* on the imported light refines them afterwards.
  const MeshRenderer flags = w.get<MeshRenderer>(e);
  std::vector<ecs::Entity> lights;
  for (ecs::Entity x : made) {
    if (auto* mr = w.try_get<MeshRenderer>(x)) {
      mr->cast_shadows = flags.cast_shadows;
      mr->receive_shadows = flags.receive_shadows;
      mr->layer = flags.layer;
    }
    if (w.has<Light>(x)) lights.push_back(x);
  }
  for (ecs::Entity l : lights) {
    if (w.has<ShadowSettings>(l))
      w.get<ShadowSettings>(l) = scene.shadow_defaults;
    else
      w.emplace<ShadowSettings>(l, scene.shadow_defaults);
  }
  return made;
}

// The scene's own settings of model entity e's nodes (model.nodes; `made`: what its import
// made), over what the file gives. After every import of a load: a later instance of the file
// is copied from the first one's entities, which must not carry the first one's settings yet. A
// name no node has is kept as it is for saving: the file may have changed since.
Status apply_node_overrides(Scene& scene, ecs::Entity e, const std::vector<ecs::Entity>& made) {
  ecs::World& w = scene.world;
  const fs::path path = scene.file.parent_path() / w.get<ModelRef>(e).path;
  const std::string model_name = w.has<Name>(e) ? w.get<Name>(e).value : std::string();
  const std::vector<NodeOverride> overrides = w.get<ModelRef>(e).nodes;  // a copy: pools move
  for (const NodeOverride& o : overrides) {
    const std::string where =
        o.where.empty() ? "/" + model_name + "/model/nodes/" + o.node + "/" + o.section : o.where;
    std::vector<ecs::Entity> found;
    for (ecs::Entity x : made)
      if (const auto* n = w.try_get<Name>(x); n && n->value == o.node) found.push_back(x);
    if (found.empty()) {
      log::warn_once("%s: %s: %s has no node named '%s'; its settings are kept for saving",
                     scene.file.string().c_str(), where.c_str(), path.string().c_str(),
                     o.node.c_str());
      continue;
    }
    if (found.size() > 1)
      return Error{scene.file.string(), where,
                   std::to_string(found.size()) + " nodes of " + path.string() + " are named '" +
                       o.node + "'; only a unique name can be set"};
    const json block = json::parse(o.block, nullptr, /*allow_exceptions=*/false);
    try {
      if (!read_section(w, found.front(), o.section, block, where))
        return Error{scene.file.string(), where,
                     "node '" + o.node + "' has no " + o.section + " in " + path.string()};
    } catch (const ContentError& err) {
      return Error{scene.file.string(), err.where, err.message};
    }
  }
  return {};
}

}  // namespace

Status load_environment(Scene& scene) {
  const std::string& file = scene.render.environment;
  if (file == scene.environment_loaded && (file.empty() || scene.environment_map != Scene::kNoEnvironment))
    return {};
  static std::uint64_t serial = 0;
  if (file.empty()) {
    scene.environment_map = Scene::kNoEnvironment;
  } else {
    EnvLoadOptions options;
    options.face_size = kEnvironmentFaceSize;
    auto cube = load_cube_map(scene.file.parent_path() / file, options);
    if (!cube) return Error{scene.file.string(), "/render/environment", cube.error().to_string()};
    // A reloaded map reuses its slot (the store keeps earlier ids valid otherwise).
    if (scene.environment_map != Scene::kNoEnvironment &&
        scene.environment_map < scene.assets.env_maps.size()) {
      scene.assets.env_maps[scene.environment_map] = std::move(cube.value());
    } else {
      scene.assets.env_maps.push_back(std::move(cube.value()));
      scene.environment_map = std::uint32_t(scene.assets.env_maps.size() - 1);
    }
    scene.environment_sh = project_sh9(scene.assets.env_maps[scene.environment_map]);
  }
  scene.environment_loaded = file;
  scene.environment_serial = ++serial;
  return {};
}

Status instantiate_scene(Scene& scene, const render::FeatureManifest* manifest) {
  ecs::World& w = scene.world;
  std::vector<std::pair<ecs::Entity, MaterialRef>> material_refs;
  w.view<MaterialRef>().each([&](ecs::Entity e, MaterialRef& r) { material_refs.emplace_back(e, r); });
  // Each material file is read once: the entities that name it share its textures (and so
  // can share draws), where reading it per entity made a copy of every texture for each.
  std::map<std::filesystem::path, Material> loaded;
  for (auto& [e, ref] : material_refs) {
    if (!manifest)
      return Error{scene.file.string(), "", "material files need the feature manifest"};
    const std::filesystem::path file = scene.file.parent_path() / ref.path;
    std::error_code ec;
    const std::filesystem::path key = std::filesystem::weakly_canonical(file, ec);
    auto it = loaded.find(ec ? file : key);
    if (it == loaded.end()) {
      auto m = load_material_file(file, *manifest, scene.assets);
      if (!m) return m.error();
      it = loaded.emplace(ec ? file : key, *m).first;
    }
    w.emplace<Material>(e, it->second);
  }
  KASKAD_TRY(load_environment(scene));
  // Static reflection maps (S3 (a)): loaded once here; the probe system uploads them once.
  std::vector<std::pair<ecs::Entity, Reflector>> static_probes;
  w.view<Reflector>().each([&](ecs::Entity e, Reflector& r) {
    if (r.update == ProbeUpdate::static_file) static_probes.emplace_back(e, r);
  });
  for (auto& [e, r] : static_probes) {
    auto cube = load_static_env_map(scene.file.parent_path() / r.file, r);
    if (!cube) return cube.error();
    scene.assets.env_maps.push_back(std::move(cube.value()));
    w.emplace<StaticEnvMap>(e, StaticEnvMap{std::uint32_t(scene.assets.env_maps.size() - 1)});
  }
  std::vector<std::pair<ecs::Entity, PrimitiveMesh>> prims;
  std::vector<std::pair<ecs::Entity, ModelRef>> models;
  w.view<PrimitiveMesh>().each([&](ecs::Entity e, PrimitiveMesh& p) { prims.emplace_back(e, p); });
  w.view<ModelRef>().each([&](ecs::Entity e, ModelRef& m) { models.emplace_back(e, m); });
  // One mesh per distinct (shape, segments): instances share it.
  std::map<std::pair<int, int>, MeshId> shared;
  for (auto& [e, p] : prims) {
    if (p.tiles > 1) {
      // Tile (0, 0) on the entity itself, the others on imported children with its renderer
      // flags and material (not written back: the primitive recreates them).
      const MeshRenderer flags = w.get<MeshRenderer>(e);
      // A copy: emplacing into the Material pool may move the entity's own component.
      const std::optional<Material> material =
          w.has<Material>(e) ? std::optional<Material>(w.get<Material>(e)) : std::nullopt;
      for (int tz = 0; tz < p.tiles; ++tz)
        for (int tx = 0; tx < p.tiles; ++tx) {
          const MeshId mesh = scene.assets.add_mesh(make_terrain_tile(p.segments, p.tiles, tx, tz));
          if (tx == 0 && tz == 0) {
            w.get<MeshRenderer>(e).mesh = mesh;
            continue;
          }
          const ecs::Entity tile = w.create();
          Transform t;
          t.parent = e;
          w.emplace<Transform>(tile, t);
          MeshRenderer mr = flags;
          mr.mesh = mesh;
          w.emplace<MeshRenderer>(tile, mr);
          if (material) w.emplace<Material>(tile, *material);
          w.emplace<Imported>(tile, Imported{e});
        }
      continue;
    }
    auto key = std::make_pair(int(p.shape), p.segments);
    auto it = shared.find(key);
    if (it == shared.end())
      it = shared.emplace(key, scene.assets.add_mesh(make_primitive(p.shape, p.segments))).first;
    w.get<MeshRenderer>(e).mesh = it->second;
  }
  std::map<std::string, FirstImport> imported;  // each file is read once (copy_import)
  std::vector<std::vector<ecs::Entity>> made;
  for (auto& model : models) {
    auto m = import_model(scene, model.first, /*activate_first_camera=*/true, &imported);
    if (!m) return m.error();
    made.push_back(std::move(m.value()));
  }
  for (std::size_t i = 0; i < models.size(); ++i)
    KASKAD_TRY(apply_node_overrides(scene, models[i].first, made[i]));
  return {};
}

Aabb ground_extent(const Aabb& models, const glm::vec3& light_direction) {
  KASKAD_CHECK(!models.empty(), "needs non-empty bounds");
  const float y = models.min.y;
  const float size = std::max(glm::length(models.extent()), 1e-6f);
  // Where the corners' shadows land on the plane y = min.y; lights lower than about 14 degrees
  // above the horizon are taken as 14 degrees (a shadow 4x the model's height long).
  const glm::vec3 l = glm::length(light_direction) > 0.0f ? glm::normalize(light_direction)
                                                           : glm::vec3(0, -1, 0);
  const float down = std::max(-l.y, 0.25f);
  const glm::vec2 along = glm::length(glm::vec2(l.x, l.z)) > 0.0f
                              ? glm::normalize(glm::vec2(l.x, l.z)) * std::sqrt(1.0f - down * down)
                              : glm::vec2(0.0f);
  Aabb out;
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 c{(i & 1) ? models.max.x : models.min.x, (i & 2) ? models.max.y : models.min.y,
                      (i & 4) ? models.max.z : models.min.z};
    const glm::vec2 hit = glm::vec2(c.x, c.z) + along * ((c.y - y) / down);
    out.expand(glm::vec3(c.x, y, c.z));
    out.expand(glm::vec3(hit.x, y, hit.y));
  }
  // A margin of a quarter of the model's size around footprint and shadow.
  out.min -= glm::vec3(0.25f * size, 0.0f, 0.25f * size);
  out.max += glm::vec3(0.25f * size, 0.0f, 0.25f * size);
  // Just under the lowest point, so that a flat bottom does not fight with the ground.
  out.min.y = out.max.y = y - 1e-4f * size;
  return out;
}

ecs::Entity add_ground(Scene& scene, const Aabb& extent) {
  ecs::World& w = scene.world;
  bool taken = false;
  w.view<Name>().each([&](ecs::Entity, const Name& n) { taken = taken || n.value == "ground"; });
  const ecs::Entity e = w.create();
  w.emplace<Name>(e, Name{taken ? "kaskad_ground" : "ground"});
  Transform t;
  t.translation = extent.center();
  t.scale = {std::max(extent.max.x - extent.min.x, 1e-6f), 1.0f,
             std::max(extent.max.z - extent.min.z, 1e-6f)};
  w.emplace<Transform>(e, t);
  MeshRenderer mr;
  mr.mesh = scene.assets.add_mesh(make_primitive(PrimitiveShape::plane, PrimitiveMesh{}.segments));
  mr.cast_shadows = false;  // nothing lies below it
  mr.receive_shadows = true;
  w.emplace<MeshRenderer>(e, mr);
  Material m;
  // Neutral grey, dark enough that the default glTF sun (2.5) does not clip it to white.
  m.base_color = glm::vec4(0.25f, 0.25f, 0.25f, 1.0f);
  m.roughness = 0.9f;
  w.emplace<Material>(e, m);
  w.emplace<Imported>(e, Imported{ecs::kNullEntity});  // made by the load, not saved
  return e;
}

Result<ecs::Entity> add_entity(Scene& scene, const json& given, const std::string& where,
                               const fs::path& source_file) {
  ecs::World& w = scene.world;
  const fs::path source = source_file.empty() ? scene.file : source_file;
  // A model path is relative to the file the block comes from; the entity keeps it relative
  // to the scene's folder, as a scene file's own models are.
  json block = given;
  if (source != scene.file && block.is_object() && block.contains("model") &&
      block["model"].is_object() && block["model"].contains("path") &&
      block["model"]["path"].is_string()) {
    const fs::path model =
        fs::absolute(source.parent_path() / block["model"]["path"].get<std::string>());
    const fs::path rel =
        model.lexically_normal().lexically_relative(fs::absolute(scene.file.parent_path()));
    block["model"]["path"] = (rel.empty() ? model.lexically_normal() : rel).generic_string();
  }
  std::map<std::string, ecs::Entity> by_name;
  w.view<Name>().each([&](ecs::Entity e, const Name& n) { by_name.emplace(n.value, e); });
  try {
    // Checked on a scratch scene first, so a bad block leaves the live one untouched.
    Scene scratch;
    scratch.file = scene.file;
    scratch.shadow_defaults = scene.shadow_defaults;
    std::map<std::string, ecs::Entity> scratch_names = by_name;
    std::vector<Pending> parents;
    FirstSun sun;
    parse_entity(block, where, scratch, scratch_names, parents, sun);
    for (const Pending& p : parents)
      if (!by_name.count(p.parent)) fail(p.where, "no entity named '" + p.parent + "'");
    if (!block.is_object() || !block.contains("name") || !block["name"].is_string())
      fail(where + "/name", "an added entity needs a name");
    bool material_file = false;
    scratch.world.view<MaterialRef>().each([&](ecs::Entity, const MaterialRef&) { material_file = true; });
    if (material_file)
      fail(where + "/material", "an added entity takes an inline material, not a material file");
    bool tiled = false;
    scratch.world.view<PrimitiveMesh>().each(
        [&](ecs::Entity, const PrimitiveMesh& pm) { tiled = tiled || pm.tiles > 1; });
    if (tiled) fail(where + "/primitive/tiles", "an added terrain cannot be tiled");
  } catch (const ContentError& e) {
    return Error{source.string(), e.where, e.message};
  }
  std::vector<Pending> parents;
  FirstSun sun;
  parse_entity(block, where, scene, by_name, parents, sun);  // checked above: cannot fail
  const ecs::Entity e = by_name.at(block.at("name").get<std::string>());
  for (const Pending& p : parents) w.get<Transform>(p.entity).parent = by_name.at(p.parent);
  if (const auto* pm = w.try_get<PrimitiveMesh>(e))
    w.get<MeshRenderer>(e).mesh = scene.assets.add_mesh(make_primitive(pm->shape, pm->segments));
  if (w.has<ModelRef>(e)) {
    // A model that cannot be imported, or a nodes block its file refuses, leaves no entity.
    auto made = import_model(scene, e, /*activate_first_camera=*/false, nullptr,
                             Error{source.string(), where + "/model/path", ""});
    Status st = made ? apply_node_overrides(scene, e, made.value()) : Status(made.error());
    if (!st) {
      (void)remove_entity(scene, block.at("name").get<std::string>());
      return st.error();
    }
  }
  return e;
}

Status remove_entity(Scene& scene, const std::string& name) {
  ecs::World& w = scene.world;
  ecs::Entity target = ecs::kNullEntity;
  w.view<Name>().each([&](ecs::Entity e, const Name& n) {
    if (n.value == name && !target.valid()) target = e;
  });
  if (!target.valid()) return Error{scene.file.string(), "", "no entity named '" + name + "' to remove"};
  // The entity, everything parented below it and everything imported for it.
  std::vector<ecs::Entity> doomed{target};
  for (std::size_t i = 0; i < doomed.size(); ++i) {
    const ecs::Entity root = doomed[i];
    w.view<Transform>().each([&](ecs::Entity e, const Transform& t) {
      const auto* imp = w.try_get<Imported>(e);
      if ((t.parent == root || (imp && imp->source == root)) &&
          std::find(doomed.begin(), doomed.end(), e) == doomed.end())
        doomed.push_back(e);
    });
  }
  for (ecs::Entity e : doomed) w.destroy(e);
  return {};
}

json scene_to_json(const Scene& scene, const fs::path& base_dir) {
  json doc;
  doc["kaskad_scene"] = kFormatVersion;
  const RenderSettings& r = scene.render;
  doc["render"] = write_fields(r);
  doc["render"]["environment"] = rebase_path(scene, base_dir, r.environment);
  doc["shadow"] = write_shadow(scene.shadow_defaults, nullptr);
  std::vector<ecs::Entity> authored;
  scene.world.view<Transform>().each([&](ecs::Entity e, const Transform&) {
    if (!scene.world.has<Imported>(e)) authored.push_back(e);
  });
  std::sort(authored.begin(), authored.end(), entity_less);  // creation order
  json ents = json::array();
  for (ecs::Entity e : authored) ents.push_back(entity_to_json(scene, e, base_dir));
  doc["entities"] = ents;
  return doc;
}

Status save_scene(const fs::path& file, const Scene& scene) {
  KASKAD_TRY(check_output_path(file));  // before the work, and with a clear word for a folder
  const fs::path dir = folder_of(file);
  return write_file_atomic(file, scene_to_json(scene, dir).dump(2) + "\n");
}

Result<Scene> read_scene(const fs::path& file, const std::vector<std::string>& overrides,
                         std::vector<std::string>* deferred) {
  auto doc = read_scene_document(file);
  if (!doc) return doc.error();
  if (!overrides.empty()) {
    // Overrides act on the canonical form, where every field is present with its value.
    auto first = parse_scene(*doc, file);
    if (!first) return first.error();
    json canonical = scene_to_json(*first);
    for (const auto& o : overrides) {
      if (deferred && !document_holds(canonical, o.substr(0, o.find('='))))
        deferred->push_back(o);  // an imported entity, perhaps: apply_entity_override
      else
        KASKAD_TRY(apply_override(canonical, o));
    }
    doc = std::move(canonical);
  }
  auto scene = parse_scene(*doc, file);
  if (!scene) {
    Error e = scene.error();
    if (!overrides.empty()) e.message += " (after --set overrides)";
    return e;
  }
  return scene;
}

}  // namespace kaskad
