#include "runtime/render/feature_manifest.h"

#include <algorithm>
#include <cctype>

#include "runtime/core/json_reader.h"

namespace kaskad::render {
namespace {

using json_reader::ContentError;
using json_reader::fail;
using json_reader::join;
using json_reader::ObjectReader;
using json_reader::type_name;

// Where each feature lives in the VariantKey. The manifest must name exactly these features.
struct LayoutEntry {
  const char* name;
  VariantKey::Field field;
  int bias;
};
constexpr LayoutEntry kLayout[] = {
    {"base_color_texture", VariantKey::kBaseColorTexture, 0},
    {"normal_map", VariantKey::kNormalMap, 0},
    {"alpha_mask", VariantKey::kAlphaMask, 0},
    {"emissive", VariantKey::kEmissive, 0},
    {"reflection_cube", VariantKey::kReflectionCube, 0},
    {"reflection_sphere", VariantKey::kReflectionSphere, 0},
    {"receive_shadows", VariantKey::kReceiveShadows, 0},
    {"reflection_box", VariantKey::kReflectionBox, 0},
    {"shadow", VariantKey::kShadow, 0},
    {"shadow_filter", VariantKey::kShadowFilter, 0},
    {"cascade_count", VariantKey::kCascadeCountMinus1, 1},
    {"aovs", VariantKey::kAovs, 0},
    {"cascade_selection", VariantKey::kCascadeSelection, 0},
    {"debug_cascades", VariantKey::kDebugCascades, 0},
    {"shadow_projection", VariantKey::kShadowProjection, 0},
    {"shadow_layered", VariantKey::kShadowLayered, 0},
    {"shadow_lights", VariantKey::kShadowLightsMinus1, 1},
};

std::vector<std::string> string_list(ObjectReader& r, const char* key) {
  std::vector<std::string> out;
  if (!r.has(key)) return out;
  const auto& v = r.raw(key);
  if (!v.is_array()) fail(r.at(key), "expected an array of strings, got " + type_name(v));
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!v[i].is_string())
      fail(r.at(key) + "/" + std::to_string(i), "expected a string, got " + type_name(v[i]));
    out.push_back(v[i].get<std::string>());
  }
  return out;
}

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

Result<FeatureManifest> FeatureManifest::load(const std::filesystem::path& file) {
  auto doc = json_reader::parse_json_file(file);
  if (!doc) return doc.error();
  FeatureManifest m;
  try {
    ObjectReader root(*doc, "");
    std::string comment;
    root.string("comment", comment);
    if (!root.has("features")) fail("/features", "missing");
    const auto& feats = root.raw("features");
    if (!feats.is_array()) fail("/features", "expected an array, got " + type_name(feats));
    for (std::size_t i = 0; i < feats.size(); ++i) {
      const std::string at = "/features/" + std::to_string(i);
      ObjectReader r(feats[i], at);
      Feature f;
      r.string("name", f.name);
      std::string kind = "material";
      r.string("kind", kind);
      if (kind != "material" && kind != "frame")
        fail(r.at("kind"), "expected material or frame, was '" + kind + "'");
      f.kind = kind == "material" ? FeatureKind::material : FeatureKind::frame;
      r.string("define", f.define);
      const std::string prefix = f.kind == FeatureKind::material ? "MATERIAL_" : "VARIANT_";
      if (f.define.rfind(prefix, 0) != 0)
        fail(r.at("define"), kind + " feature defines start with " + prefix + ", was '" + f.define + "'");
      for (const auto& s : string_list(r, "stages")) {
        if (s == "vertex") f.stages |= std::uint8_t(ShaderStage::vertex);
        else if (s == "fragment") f.stages |= std::uint8_t(ShaderStage::fragment);
        else fail(r.at("stages"), "unknown stage '" + s + "'; expected vertex or fragment");
      }
      if (f.stages == 0) fail(r.at("stages"), "a feature needs at least one stage");
      f.requires_ = string_list(r, "requires");
      f.excludes = string_list(r, "excludes");
      f.values = string_list(r, "values");
      if (!f.values.empty()) f.max = int(f.values.size()) - 1;
      if (r.has("range")) {
        auto range = numbers(r.raw("range"), r.at("range"), 2);
        f.min = int(range[0]);
        f.max = int(range[1]);
        if (f.min > f.max) fail(r.at("range"), "min exceeds max");
      }
      r.finish();
      const auto* layout = std::find_if(std::begin(kLayout), std::end(kLayout),
                                        [&](const LayoutEntry& e) { return f.name == e.name; });
      if (layout == std::end(kLayout))
        fail(at + "/name", "feature '" + f.name + "' has no place in the variant key "
                           "(runtime/render/variant_key.h)");
      f.field = layout->field;
      f.key_bias = layout->bias;
      if (f.min - f.key_bias < 0 || std::uint32_t(f.max - f.key_bias) > f.field.max())
        fail(at, "value range [" + std::to_string(f.min) + ", " + std::to_string(f.max) +
                     "] does not fit its " + std::to_string(f.field.width) + "-bit key field");
      if (m.find(f.name)) fail(at + "/name", "duplicate feature '" + f.name + "'");
      m.features_.push_back(std::move(f));
    }
    for (const LayoutEntry& e : kLayout)
      if (!m.find(e.name)) fail("/features", std::string("the variant key has feature '") + e.name +
                                                 "', which the manifest does not describe");
    for (std::size_t i = 0; i < m.features_.size(); ++i)
      for (const auto* list : {&m.features_[i].requires_, &m.features_[i].excludes})
        for (const auto& other : *list)
          if (!m.find(other))
            fail("/features/" + std::to_string(i), "refers to unknown feature '" + other + "'");

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
        else if (type == "vec3") p.type = ParamType::vec3, n = 3;
        else if (type == "vec4") p.type = ParamType::vec4, n = 4;
        else if (type == "bool") p.type = ParamType::bool_;
        else fail(r.at("type"), "unknown type '" + type + "'; expected float, vec3, vec4 or bool");
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
  std::uint32_t described = 0;
  for (const auto& f : features_) described |= f.field.mask();
  if (key.bits() & ~described) return "key has bits no feature describes";
  auto on = [&](const Feature& f) { return key.get(f.field) != 0; };
  for (const auto& f : features_) {
    const int v = value(f, key);
    if (v < f.min || v > f.max)
      return f.name + " must be in [" + std::to_string(f.min) + ", " + std::to_string(f.max) +
             "], was " + std::to_string(v);
    if (!on(f)) continue;
    for (const auto& r : f.requires_)
      if (!on(*find(r))) return f.name + " requires " + r;
    for (const auto& x : f.excludes)
      if (on(*find(x))) return f.name + " excludes " + x;
  }
  return {};
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
