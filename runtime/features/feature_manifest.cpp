#include "runtime/features/feature_manifest.h"

#include <algorithm>
#include <cctype>

#include "components/limits.h"
#include "components/shadow_technique.h"
#include "runtime/features/shader_interface.h"
#include "runtime/core/json_reader.h"

namespace kaskad::render {
namespace {

using json_reader::ContentError;
using json_reader::fail;
using json_reader::join;
using json_reader::ObjectReader;
using json_reader::type_name;

std::vector<double> numbers(const nlohmann::json& v, const std::string& where, std::size_t n) {
  std::vector<double> out;
  if (n == 1 && v.is_boolean()) return {v.get<bool>() ? 1.0 : 0.0};
  if (n == 1 && v.is_number()) return {v.get<double>()};
  if (!v.is_array() || v.size() != n)
    fail(where, "expected " + std::to_string(n) + " numbers, got " + type_name(v));
  for (const auto& x : v) {
    if (!x.is_number()) fail(where, "expected numbers, got " + type_name(x));
    out.push_back(x.get<double>());
  }
  return out;
}

}  // namespace

FeatureManifest::FeatureManifest() {
  for (const FeatureSpec& spec : kFeatureTable) {
    Feature f;
    f.name = spec.name;
    f.kind = spec.kind;
    f.define = spec.define;
    f.stages = spec.stages;
    for (std::string_view r : spec.requires_)
      if (!r.empty()) f.requires_.emplace_back(r);
    for (std::string_view x : spec.excludes)
      if (!x.empty()) f.excludes.emplace_back(x);
    for (std::string_view v : spec.values)
      if (!v.empty()) f.values.emplace_back(v);
    f.min = spec.min;
    f.max = spec.value_max();
    f.field = spec.field();
    f.key_bias = spec.min;
    features_.push_back(std::move(f));
  }
}

Result<FeatureManifest> FeatureManifest::load(const std::filesystem::path& file) {
  auto doc = json_reader::parse_json_file(file);
  if (!doc) return doc.error();
  FeatureManifest m;
  try {
    ObjectReader root(*doc, "");
    std::string comment;
    root.string("comment", comment);
    if (root.has("features"))
      fail("/features", "features are declared in kFeatureTable (runtime/features/variant_key.h), "
                        "not in the manifest");
    if (root.has("parameters")) {
      const auto& params = root.raw("parameters");
      if (!params.is_array()) fail("/parameters", "expected an array");
      for (std::size_t i = 0; i < params.size(); ++i) {
        ObjectReader r(params[i], "/parameters/" + std::to_string(i));
        MaterialParameter p;
        r.string("name", p.name);
        std::string type;
        r.string("type", type);
        std::size_t n = 1;
        if (type == "float") p.type = ParamType::float_;
        else if (type == "vec2") p.type = ParamType::vec2, n = 2;
        else if (type == "vec3") p.type = ParamType::vec3, n = 3;
        else if (type == "vec4") p.type = ParamType::vec4, n = 4;
        else if (type == "bool") p.type = ParamType::bool_;
        else fail(r.at("type"), "unknown type '" + type + "'; expected float, vec2, vec3, vec4 or bool");
        if (!r.has("default")) fail(r.at("default"), "missing");
        p.default_value = numbers(r.raw("default"), r.at("default"), n);
        if (p.type != ParamType::bool_) {
          float lo = 0, hi = 1;
          r.number("min", lo, -1e9f, 1e9f);
          r.number("max", hi, -1e9f, 1e9f);
          p.min = lo;
          p.max = hi;
        }
        r.string("feature", p.feature);
        r.finish();
        if (!p.feature.empty() && !m.find(p.feature))
          fail(r.at("feature"), "unknown feature '" + p.feature + "'");
        m.parameters_.push_back(std::move(p));
      }
    }
    if (root.has("textures")) {
      const auto& texs = root.raw("textures");
      if (!texs.is_array()) fail("/textures", "expected an array");
      for (std::size_t i = 0; i < texs.size(); ++i) {
        ObjectReader r(texs[i], "/textures/" + std::to_string(i));
        MaterialTextureSlot t;
        r.string("name", t.name);
        r.string("feature", t.feature);
        r.boolean("srgb", t.srgb);
        r.finish();
        if (!m.find(t.feature)) fail(r.at("feature"), "unknown feature '" + t.feature + "'");
        m.textures_.push_back(std::move(t));
      }
    }
    root.finish();
  } catch (const ContentError& e) {
    return Error{file.string(), e.where, e.message};
  }
  return m;
}

const Feature* FeatureManifest::find(const std::string& name) const {
  for (const auto& f : features_)
    if (f.name == name) return &f;
  return nullptr;
}
const MaterialParameter* FeatureManifest::find_parameter(const std::string& name) const {
  for (const auto& p : parameters_)
    if (p.name == name) return &p;
  return nullptr;
}
const MaterialTextureSlot* FeatureManifest::find_texture(const std::string& name) const {
  for (const auto& t : textures_)
    if (t.name == name) return &t;
  return nullptr;
}

int FeatureManifest::value(const Feature& f, VariantKey key) const {
  return int(key.get(f.field)) + f.key_bias;
}

VariantKey FeatureManifest::with(VariantKey key, const Feature& f, int v) const {
  KASKAD_CHECK(v >= f.min && v <= f.max, f.name + " must be in [" + std::to_string(f.min) + ", " +
                                             std::to_string(f.max) + "], was " + std::to_string(v));
  return key.set(f.field, std::uint32_t(v - f.key_bias));
}

std::string FeatureManifest::check(VariantKey key) const {
  const BrokenRule broken = key.broken_rule();
  if (broken.kind == BrokenRule::none) return {};
  if (broken.kind == BrokenRule::unused_bits) return "key has bits no feature describes";
  const Feature& f = features_[std::size_t(broken.feature)];
  if (broken.kind == BrokenRule::range)
    return f.name + " must be in [" + std::to_string(f.min) + ", " + std::to_string(f.max) +
           "], was " + std::to_string(value(f, key));
  const std::string& other = features_[std::size_t(broken.other)].name;
  return f.name + (broken.kind == BrokenRule::requires_ ? " requires " : " excludes ") + other;
}

std::vector<std::pair<std::string, std::string>> FeatureManifest::defines(VariantKey key,
                                                                          ShaderStage stage) const {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& f : features_) {
    if (!(f.stages & std::uint8_t(stage))) continue;
    for (std::size_t i = 0; i < f.values.size(); ++i) {
      std::string upper = f.values[i];
      for (auto& c : upper) c = char(std::toupper(static_cast<unsigned char>(c)));
      out.emplace_back(f.define + "_" + upper, std::to_string(i));
    }
    out.emplace_back(f.define, std::to_string(value(f, key)));
  }
  // Material feature bit numbers for ENABLED(BIT_*) (features.glsl), in every stage.
  for (const auto& f : features_) {
    if (f.kind != FeatureKind::material) continue;
    std::string upper = f.name;
    for (auto& c : upper) c = char(std::toupper(static_cast<unsigned char>(c)));
    out.emplace_back("BIT_" + upper, std::to_string(f.field.offset));
  }
  // What the shadow technique's lookup files switch on (shadow_filter.glsl), from its row of
  // the technique table, so that no shader lists techniques by name.
  const std::uint32_t t = key.get(VariantKey::kShadowTechnique);
  const ShadowTechniqueTraits& technique =
      traits(t < kShadowTechniqueCount ? ShadowTechnique(t) : ShadowTechnique::pcf);
  out.emplace_back("TECHNIQUE_NEEDS_LIGHT_SIZE", technique.needs_light_size ? "1" : "0");
  out.emplace_back("TECHNIQUE_MOMENT_CHANNELS", std::to_string(technique.moment_channels));
  // The limits that size the frame block (common.glsl), from their one definition.
  out.emplace_back("MAX_LIGHTS", std::to_string(kMaxLights));
  out.emplace_back("MAX_CASCADES", std::to_string(kMaxCascades));
  out.emplace_back("MAX_SHADOW_VIEWS", std::to_string(kMaxShadowedLights));
  out.emplace_back("PCSS_MAX_RADIUS", std::to_string(kPcssMaxRadiusTexels) + ".0");
  // Attribute and uniform locations and texture units, from runtime/features/shader_interface.h.
  for (const auto& [name, value] : shader_interface_defines()) out.emplace_back(name, std::to_string(value));
  return out;
}

std::string FeatureManifest::describe(VariantKey key) const {
  std::string s;
  for (const auto& f : features_) {
    if (key.get(f.field) == 0) continue;
    // Appended piecewise: `s += "=" + x` trips GCC 12's false -Wrestrict (PR 105651).
    if (!s.empty()) s += ' ';
    s += f.name;
    if (!f.values.empty() || f.max > 1) s += '=';
    if (!f.values.empty()) s += f.values[std::size_t(value(f, key))];
    else if (f.max > 1) s += std::to_string(value(f, key));
  }
  return s.empty() ? "(none)" : s;
}

}  // namespace kaskad::render
