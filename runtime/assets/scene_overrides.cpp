// `--set` overrides: on the canonical document before a load, on a loaded scene between frames,
// on imported glTF nodes; and a model's `nodes` block, which keeps those edits in the file.
#include "runtime/assets/scene_io.h"

#include <algorithm>
#include <charconv>
#include <regex>

#include "components/name.h"
#include "components/reflector.h"
#include "runtime/assets/env_lighting.h"
#include "runtime/assets/reflector_io.h"
#include "runtime/assets/scene_blocks.h"
#include "runtime/core/field_io.h"

namespace kaskad {

using namespace scene_blocks;

namespace {

using json = nlohmann::json;
using json_reader::ContentError;
using json_reader::fail;
using json_reader::join;
using json_reader::type_name;

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
  if (auto depth = json_reader::check_depth(text, "--set"); !depth)
    return Error{"--set", key, "value " + json_reader::quote(text) + ": " + depth.error().message};
  json value = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (value.is_discarded()) {
    // A bare word is a string (4k_sky.hdr); a well-formed number JSON cannot hold (1e999) is an
    // error, not the string "1e999".
    static const std::regex kNumber(R"(-?[0-9]+(\.[0-9]+)?([eE][+-]?[0-9]+)?)");
    if (std::regex_match(text, kNumber)) {
      auto parsed = json_reader::parse_json_text(text, "--set");
      return Error{"--set", key, "value " + json_reader::quote(text) + " is not a valid number" +
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

// Entity e's sections as apply_entity_override() and a model's node blocks set them: transform
// without its parent (kept as it is), shadow with every field, the rest as scene files hold them.
json settable_sections(const Scene& scene, ecs::Entity e) {
  json ej = entity_to_json(scene, e, {});
  if (const auto* s = scene.world.try_get<ShadowSettings>(e))
    ej["shadow"] = write_shadow(*s, nullptr);
  ej.erase("name");
  if (ej.contains("transform")) ej["transform"].erase("parent");
  // Clips as they play now: a --set of one field keeps the others where the clock has them.
  if (const auto* a = scene.world.try_get<Animator>(e))
    ej["animation"] = write_animation(*a, ClipTime::now);
  return ej;
}

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

}  // namespace

namespace scene_blocks {

// Whether the first part of `key` names a settings section or an entity of the document.
bool document_holds(const json& doc, const std::string& key) {
  const std::string first = key.substr(0, key.find('.'));
  if (doc.contains(first) && first != "entities" && first != "kaskad_scene") return true;
  if (doc.contains("entities") && doc["entities"].is_array())
    for (const auto& ent : doc["entities"])
      if (ent.is_object() && ent.contains("name") && ent["name"] == first) return true;
  return false;
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
  } else if (section == "animation" && w.has<Animator>(e)) {
    reread<Animator>(w, e, block, where, read_animation);
  } else {
    return false;
  }
  return true;
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

}  // namespace scene_blocks

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
                                     "'; sections: " + join({kSettingSections.begin(), kSettingSections.end()}) + "; entities: " + join(names)};
  }
  parts.erase(parts.begin());
  // A model's clips are known once it is imported: ENTITY.animation.CLIP.FIELD makes its block
  // for any clip and field name, which the import then checks (read_animation() names the
  // model's clips, read_fields() the valid fields).
  if (parts.size() == 3 && parts[0] == "animation" && node->is_object() && node->contains("model") &&
      (!node->contains("animation") || (*node)["animation"].is_object())) {
    json& clip = (*node)["animation"][parts[1]];
    if (clip.is_null()) clip = json::object();
    if (clip.is_object() && !clip.contains(parts[2])) clip[parts[2]] = nullptr;
  }
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
                                   "'; sections: " + join({kSettingSections.begin(), kSettingSections.end()}) + "; entities: " + join(names)};
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
                       "light, shadow, camera, renderer, reflector and (a model with clips) "
                       "animation"};
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

}  // namespace kaskad
