#include "runtime/assets/scene_schema.h"

#include "components/animation.h"
#include "components/camera.h"
#include "components/light.h"
#include "components/limits.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/reflector.h"
#include "components/shadow_settings.h"
#include "runtime/assets/scene.h"
#include "runtime/core/field_io.h"

namespace kaskad {
namespace {

using json = nlohmann::json;

constexpr const char* kDraft = "https://json-schema.org/draft/2020-12/schema";

/// A closed object: only `props` (the reader refuses other keys, with a suggestion).
json object(json props, const std::string& description = {}) {
  json j = {{"type", "object"}, {"properties", std::move(props)}, {"additionalProperties", false}};
  if (!description.empty()) j["description"] = description;
  return j;
}

/// The object of struct S's table, plus hand-written `more` properties.
template <class S>
json table_object(const std::string& description, json more = json::object()) {
  json props = field_io::schema_properties<S>();
  props.update(more);
  return object(std::move(props), description);
}

json numbers(int n, double lo, double hi, const std::string& description) {
  return {{"type", "array"},
          {"minItems", n},
          {"maxItems", n},
          {"items", {{"type", "number"}, {"minimum", lo}, {"maximum", hi}}},
          {"description", description}};
}

json text(const std::string& description) {
  return {{"type", "string"}, {"description", description}};
}

json transform_schema(bool with_parent) {
  const double big = kMaxCoordinate;
  json props = {
      {"translation", numbers(3, -big, big, "Position in the parent's space")},
      {"scale", numbers(3, -big, big, "Scale along the local axes")},
      {"rotation", numbers(4, -2, 2, "Quaternion x, y, z, w (glTF's order); one rotation form only")},
      {"euler_deg", numbers(3, -36000, 36000, "Rotation as XYZ Euler angles, degrees")},
      {"look_at", numbers(3, -big, big, "A world point the -Z axis turns to")},
      {"direction", numbers(3, -big, big, "The world direction of the -Z axis")},
  };
  if (with_parent) props["parent"] = text("Name of the parent entity");
  json j = object(std::move(props), "Where the entity is: translation, one rotation form, scale");
  // Exactly one rotation form at most, as the reader requires.
  json forms = json::array();
  for (const char* k : {"rotation", "euler_deg", "look_at", "direction"}) forms.push_back(k);
  j["not"] = {{"anyOf", json::array()}};
  for (std::size_t a = 0; a < forms.size(); ++a)
    for (std::size_t b = a + 1; b < forms.size(); ++b)
      j["not"]["anyOf"].push_back({{"required", {forms[a], forms[b]}}});
  return j;
}

json reflector_schema() {
  const double big = kMaxCoordinate;
  json vec3 = numbers(3, -big, big, "");
  json more = {
      {"center",
       {{"description", "Capture point: [x, y, z] in world space, or auto (the bounds' centre)"},
        {"anyOf", {vec3, {{"const", "auto"}}}}}},
      {"box",
       {{"description", "Box projection (parallax-corrected lookups), or none"},
        {"anyOf",
         {{{"const", "none"}},
          {{"type", "object"},
           {"required", {"min", "max"}},
           {"additionalProperties", false},
           {"properties", {{"min", vec3}, {"max", vec3}}}}}}}},
      {"exclude_layers",
       {{"type", "array"},
        {"items", {{"type", "integer"}, {"minimum", 0}, {"maximum", 31}}},
        {"description", "Renderer layers the capture leaves out"}}},
  };
  return table_object<Reflector>("A reflection probe captured at the entity", more);
}

/// The sections an entity (or a model's node block) may hold.
json entity_sections(bool node) {
  json props = {
      {"transform", transform_schema(!node)},
      {"renderer", table_object<MeshRenderer>("How the mesh is drawn")},
      {"light", table_object<Light>("A light source at the entity")},
      {"shadow", table_object<ShadowSettings>("This light's own shadow settings (over /shadow)")},
      {"camera", table_object<Camera>("A camera at the entity")},
  };
  return props;
}

json entity_schema() {
  json props = entity_sections(false);
  props["name"] = {{"type", "string"},
                   {"pattern", "^[^.=]*$"},
                   {"description", "Unique name; --set and parents address the entity by it"}};
  props["primitive"] = table_object<PrimitiveMesh>("A built-in mesh");
  json node = object(entity_sections(true), "Fields set on the imported node of that name");
  props["model"] = object({{"path", text("glTF file (.gltf or .glb), relative to the scene")},
                           {"nodes", {{"type", "object"},
                                      {"additionalProperties", node},
                                      {"description", "Overrides of imported nodes, by name"}}}},
                          "A glTF model");
  props["model"]["required"] = {"path"};
  props["animation"] = {{"type", "object"},
                        {"additionalProperties", table_object<AnimationState>("One clip of the model")},
                        {"description", "The model's clips by name: how each plays"}};
  props["material"] = {
      {"description", "A material file, or the built-in parameters inline"},
      {"anyOf",
       {object({{"file", text("Material file, relative to the scene")}}),
        table_object<Material>("")}}};
  props["material"]["anyOf"][0]["required"] = {"file"};
  props["reflector"] = reflector_schema();
  json j = object(std::move(props), "One entity: a name and its components");
  j["not"] = {{"required", {"primitive", "model"}}};
  return j;
}

}  // namespace

json scene_schema() {
  json render = table_object<RenderSettings>(
      "Output size, exposure, tone mapping, environment and frame options",
      {{"exposure_ev",
        {{"type", "number"},
         {"minimum", kMinExposureEv},
         {"maximum", kMaxExposureEv},
         {"description", "Exposure in stops (2^EV); instead of exposure"}}}});
  render["not"] = {{"required", {"exposure", "exposure_ev"}}};
  json j = object(
      {{"$schema", text("This schema's address, for editors")},
       {"kaskad_scene", {{"type", "integer"}, {"minimum", 1}, {"maximum", 1},
                         {"description", "Format version"}}},
       {"render", render},
       {"shadow", table_object<ShadowSettings>("Shadow settings of every shadowed light")},
       {"entities", {{"type", "array"}, {"items", entity_schema()}}}},
      "A Kaskad scene file");
  j["$schema"] = kDraft;
  j["title"] = "Kaskad scene";
  return j;
}

json material_schema(const render::FeatureManifest& manifest) {
  json features = json::array();
  for (const auto& f : manifest.features())
    if (f.kind == render::FeatureKind::material && f.name != "receive_shadows") features.push_back(f.name);
  json params = json::object();
  for (const auto& p : manifest.parameters()) {
    json s;
    switch (p.type) {
      case render::ParamType::bool_: s = {{"type", "boolean"}}; break;
      case render::ParamType::float_:
        s = {{"type", "number"}, {"minimum", p.min}, {"maximum", p.max}};
        break;
      case render::ParamType::vec2: s = numbers(2, p.min, p.max, ""); break;
      case render::ParamType::vec3: s = numbers(3, p.min, p.max, ""); break;
      case render::ParamType::vec4: s = numbers(4, p.min, p.max, ""); break;
    }
    s["description"] = p.feature.empty() ? std::string("Any material")
                                          : "Needs feature " + p.feature;
    params[p.name] = s;
  }
  json textures = json::object();
  for (const auto& t : manifest.textures())
    textures[t.name] = text("Image file, relative to the material (turns on " + t.feature + ")");
  json j = object(
      {{"$schema", text("This schema's address, for editors")},
       {"description", text("What the material is for")},
       {"reflection_model", field_io::schema_properties<Material>()["reflection_model"]},
       {"features", {{"type", "array"},
                     {"uniqueItems", true},
                     {"items", {{"enum", features}}},
                     {"description", "Shader features the material turns on"}}},
       {"parameters", object(params, "Parameters the manifest declares")},
       {"textures", object(textures, "Texture slots the manifest declares")}},
      "A Kaskad material file");
  j["$schema"] = kDraft;
  j["title"] = "Kaskad material";
  return j;
}

std::string settings_reference() {
  std::string out =
      "# Settings reference\n\n"
      "Generated by `kaskad schema` from the field tables beside each struct "
      "(`runtime/fields/fields.h` explains them); do not edit by hand. A test fails when this "
      "page differs from what the tables produce. Scene files may name a JSON Schema for "
      "editors: `scene.schema.json` and `material.schema.json` in this folder (playback files, "
      "`playback.schema.json`).\n\n"
      "Every field can be set from the command line too, `--set SECTION.FIELD=VALUE` for the "
      "scene-wide blocks and `--set ENTITY.SECTION.FIELD=VALUE` for an entity's components "
      "(docs/guide/scenes.md).\n";
  auto section = [&](const std::string& title, const std::string& where, const std::string& rows) {
    out += "\n## " + title + "\n\n" + where + "\n\n";
    out += "| field | type | default | range or values | what it does | notes |\n";
    out += "|---|---|---|---|---|---|\n";
    out += rows;
  };
  section("render", "The scene file's `render` block (`RenderSettings`, runtime/assets/scene.h). "
          "`exposure_ev` (stops, in [" + fields::format_number(kMinExposureEv) + ", " +
          fields::format_number(kMaxExposureEv) + "]) may replace `exposure`.",
          field_io::reference_rows<RenderSettings>());
  section("shadow", "The scene file's `shadow` block, and a light entity's own `shadow` block "
          "over it (`ShadowSettings`, components/shadow_settings.h). Fields noted shared take "
          "the first shadowed light's value for every light (one texture array, one set of "
          "shader features); debug fields are views and toggles, off in shipped scenes.",
          field_io::reference_rows<ShadowSettings>());
  section("light", "An entity's `light` block (`Light`, components/light.h).",
          field_io::reference_rows<Light>());
  section("camera", "An entity's `camera` block (`Camera`, components/camera.h).",
          field_io::reference_rows<Camera>());
  section("renderer", "An entity's `renderer` block (`MeshRenderer`, components/mesh_renderer.h).",
          field_io::reference_rows<MeshRenderer>());
  section("primitive", "An entity's `primitive` block (`PrimitiveMesh`, components/model.h).",
          field_io::reference_rows<PrimitiveMesh>());
  section("material (inline)", "An entity's inline `material` block (`Material`, "
          "components/material.h); material files are described in docs/guide/materials.md.",
          field_io::reference_rows<Material>());
  section("reflector", "An entity's `reflector` block (`Reflector`, components/reflector.h). "
          "Also `center` ([x, y, z] or \"auto\"), `box` ({\"min\", \"max\"} or \"none\") and "
          "`exclude_layers` (renderer layers the capture leaves out).",
          field_io::reference_rows<Reflector>());
  return out;
}

std::vector<std::pair<std::string, std::string>> reference_files(
    const render::FeatureManifest& manifest) {
  return {{"scene.schema.json", scene_schema().dump(2) + "\n"},
          {"material.schema.json", material_schema(manifest).dump(2) + "\n"},
          {"settings.md", settings_reference()}};
}

}  // namespace kaskad
