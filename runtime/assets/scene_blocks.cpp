// The scene file's block readers and writers (render, shadow, transform, light, camera,
// renderer, material, entity), shared by scene files, `--set` and node overrides.
#include "runtime/assets/scene_blocks.h"

#include <algorithm>
#include <cmath>

#include <glm/gtx/euler_angles.hpp>

#include "components/name.h"
#include "components/reflector.h"
#include "runtime/assets/material_file.h"
#include "runtime/assets/reflector_io.h"
#include "runtime/core/field_io.h"

namespace kaskad::scene_blocks {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;
using field_io::read_fields;
using field_io::write_fields;
using json_reader::fail;
using json_reader::num;
using json_reader::vec;

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
      r.vector<3>("look_at", target, -kMaxCoordinate, kMaxCoordinate);
      dir = target - t.translation;
    } else {
      dir = glm::vec3(0.0f);
      r.vector<3>("direction", dir, -kMaxCoordinate, kMaxCoordinate);
    }
    const char* key = r.has("look_at") ? "look_at" : "direction";
    if (glm::length(dir) < 1e-6f) fail(r.at(key), "direction has zero length");
    t.rotation = look_rotation(glm::normalize(dir));
  }
}

}  // namespace

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
  tr.vector<3>("translation", t.translation, -kMaxCoordinate, kMaxCoordinate);
  tr.vector<3>("scale", t.scale, -kMaxCoordinate, kMaxCoordinate);
  read_rotation(tr, t);
}

void read_renderer(ObjectReader& rr, MeshRenderer& m) {
  read_fields(rr, m);
  rr.finish();
}

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
    if (std::any_of(name.begin(), name.end(),
                    [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; }))
      fail(r.at("name"), "names may not contain control characters (a newline, a tab, an escape)");
    if (name.front() == ' ' || name.back() == ' ')
      fail(r.at("name"), "names may not start or end with a space");
    for (const char* section : kSettingSections)
      if (name == section)
        fail(r.at("name"), "'" + name + "' names a setting section of --set; an entity may not take it");
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
    if (r.has("animation")) {
      if (!r.raw("animation").is_object())
        fail(r.at("animation"), "expected an object of clip names, got " +
                                    json_reader::type_name(r.raw("animation")));
      m.animation = r.raw("animation").dump();
      m.animation_where = r.at("animation");
    }
    w.emplace<ModelRef>(e, m);
  } else if (r.has("animation")) {
    fail(r.at("animation"), "animation needs a model (the clips are a glTF file's)");
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

std::string rebase_path(const Scene& scene, const fs::path& base, const std::string& path) {
  if (base.empty() || path.empty() || !fs::path(path).is_relative()) return path;
  const fs::path abs = fs::absolute(scene.file.parent_path() / path).lexically_normal();
  return abs.lexically_relative(fs::absolute(base).lexically_normal()).generic_string();
}

void read_animation(ObjectReader& r, Animator& a) {
  a.cues.resize(a.clips.size());
  for (auto it = r.raw_object().begin(); it != r.raw_object().end(); ++it) {
    const std::string& clip = it.key();
    const auto found = std::find(a.names.begin(), a.names.end(), clip);
    if (found == a.names.end()) {
      std::string names;
      for (const std::string& n : a.names) names += (names.empty() ? "" : ", ") + n;
      fail(r.at(clip.c_str()), "no clip named '" + clip + "'; the model's clips: " + names);
    }
    const std::size_t k = std::size_t(found - a.names.begin());
    ObjectReader cr(it.value(), r.at(clip.c_str()));
    read_fields(cr, a.clips[k]);
    cr.finish();
    a.cues[k] = {a.clips[k].time, true};
  }
}

json write_animation(const Animator& a, ClipTime time) {
  json j = json::object();
  for (std::size_t k = 0; k < a.clips.size() && k < a.names.size(); ++k) {
    AnimationState s = a.clips[k];
    if (time == ClipTime::as_set && s.playing && k < a.cues.size()) s.time = a.cues[k].time;
    j[a.names[k]] = write_fields(s);
  }
  return j;
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
  if (const auto* a = w.try_get<Animator>(e)) {
    j["animation"] = write_animation(*a, ClipTime::as_set);
  } else if (const auto* m = w.try_get<ModelRef>(e); m && !m->animation.empty()) {
    // A scene read but not loaded (kaskad save): the block as the file gave it.
    j["animation"] = json::parse(m->animation, nullptr, /*allow_exceptions=*/false);
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

}  // namespace kaskad::scene_blocks
