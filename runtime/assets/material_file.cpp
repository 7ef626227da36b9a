#include "runtime/assets/material_file.h"

#include <algorithm>

#include "runtime/assets/image_io.h"
#include "runtime/core/field_io.h"
#include "runtime/core/json_reader.h"

namespace kaskad {
namespace {

using json_reader::ContentError;
using json_reader::fail;
using json_reader::ObjectReader;
using json_reader::type_name;
using render::FeatureKind;
using render::ParamType;

Result<TextureId> load_texture(const std::filesystem::path& path, bool srgb, AssetStore& assets) {
  auto image = load_image(path);
  if (!image) return image.error();
  TextureData t;
  t.name = path.filename().string();
  t.width = image->width;
  t.height = image->height;
  t.srgb = srgb;
  t.rgba8 = to_rgba8(*image);
  return assets.add_texture(std::move(t));
}

}  // namespace

Result<Material> load_material_file(const std::filesystem::path& file,
                                    const render::FeatureManifest& manifest, AssetStore& assets) {
  auto doc = json_reader::parse_json_file(file);
  if (!doc) return doc.error();
  Material m;
  try {
    ObjectReader root(*doc, "");
    std::string description;
    root.string("description", description);
    std::string schema;  // "$schema": the file's JSON Schema, for editors (`kaskad schema`)
    root.string("$schema", schema);
    root.enumeration("reflection_model", m.reflection_model,
                     field_io::name_table<ReflectionModel>());
    // 1. Features: known, of material kind, listed once, consistent with each other.
    std::vector<std::string> features;
    if (root.has("features")) {
      const auto& list = root.raw("features");
      if (!list.is_array()) fail("/features", "expected an array of feature names, got " + type_name(list));
      for (std::size_t i = 0; i < list.size(); ++i) {
        const std::string at = "/features/" + std::to_string(i);
        if (!list[i].is_string()) fail(at, "expected a feature name, got " + type_name(list[i]));
        const std::string name = list[i].get<std::string>();
        const render::Feature* f = manifest.find(name);
        if (!f) {
          std::vector<std::string> valid;
          for (const auto& g : manifest.features())
            if (g.kind == FeatureKind::material && g.name != "receive_shadows") valid.push_back(g.name);
          fail(at, "unknown feature '" + name + "'; material features: " + json_reader::join(valid));
        }
        if (f->kind != FeatureKind::material || name == "receive_shadows")
          fail(at, "'" + name + "' is not a material feature (it is set by the frame or the object)");
        if (std::find(features.begin(), features.end(), name) != features.end())
          fail(at, "feature '" + name + "' is listed twice");
        features.push_back(name);
        m.features |= f->field.mask();
      }
      for (std::size_t i = 0; i < features.size(); ++i) {
        const render::Feature* f = manifest.find(features[i]);
        for (const auto& x : f->excludes)
          if (std::find(features.begin(), features.end(), x) != features.end())
            fail("/features/" + std::to_string(i), "'" + features[i] + "' and '" + x + "' exclude each other");
        for (const auto& r : f->requires_)
          if (std::find(features.begin(), features.end(), r) == features.end())
            fail("/features/" + std::to_string(i), "'" + features[i] + "' requires '" + r + "'");
      }
    }
    auto listed = [&](const std::string& feature) {
      return feature.empty() || std::find(features.begin(), features.end(), feature) != features.end();
    };
    // 2. Parameters: declared in the manifest, of the declared type and range, feature listed.
    if (root.has("parameters")) {
      const auto& params = root.raw("parameters");
      if (!params.is_object()) fail("/parameters", "expected an object, got " + type_name(params));
      ObjectReader pr(params, "/parameters");
      for (auto it = params.begin(); it != params.end(); ++it) {
        const render::MaterialParameter* p = manifest.find_parameter(it.key());
        if (!p) {
          std::vector<std::string> valid;
          for (const auto& q : manifest.parameters()) valid.push_back(q.name);
          fail(pr.at(it.key().c_str()), "unknown parameter '" + it.key() + "'; parameters: " + json_reader::join(valid));
        }
        if (!listed(p->feature))
          fail(pr.at(it.key().c_str()), "parameter '" + p->name + "' needs feature '" + p->feature + "' in /features");
      }
      for (const auto& p : manifest.parameters()) {
        const char* key = p.name.c_str();
        if (!pr.has(key)) continue;
        const float mn = float(p.min), mx = float(p.max);
        if (p.name == "base_color") pr.vector<4>(key, m.base_color, mn, mx);
        else if (p.name == "metallic") pr.number(key, m.metallic, mn, mx);
        else if (p.name == "roughness") pr.number(key, m.roughness, mn, mx);
        else if (p.name == "normal_scale") pr.number(key, m.normal_scale, mn, mx);
        else if (p.name == "emissive") pr.vector<3>(key, m.emissive, mn, mx);
        else if (p.name == "alpha_cutoff") pr.number(key, m.alpha_cutoff, mn, mx);
        else if (p.name == "double_sided") pr.boolean(key, m.double_sided);
        else if (p.name == "k_s") pr.number(key, m.k_s, mn, mx);
        else if (p.name == "occlusion_strength") pr.number(key, m.occlusion_strength, mn, mx);
        // A material file has one texture transform, for all its textures (glTF has one per slot).
        else if (p.name == "uv_offset") pr.vector<2>(key, m.base_color_transform.offset, mn, mx);
        else if (p.name == "uv_rotation") pr.number(key, m.base_color_transform.rotation, mn, mx);
        else if (p.name == "uv_scale") pr.vector<2>(key, m.base_color_transform.scale, mn, mx);
        else fail(pr.at(key), "parameter '" + p.name + "' is declared but the engine does not know it");
      }
    }
    m.normal_transform = m.occlusion_transform = m.emissive_transform =
        m.metallic_roughness_transform = m.base_color_transform;
    // The alpha mode follows the features (they exclude each other).
    if (std::find(features.begin(), features.end(), "alpha_mask") != features.end())
      m.alpha_mode = AlphaMode::mask;
    if (std::find(features.begin(), features.end(), "alpha_blend") != features.end())
      m.alpha_mode = AlphaMode::blend;
    // 3. Textures: declared slot, its feature listed; listed texture features need their texture.
    std::vector<std::string> given;
    if (root.has("textures")) {
      const auto& texs = root.raw("textures");
      if (!texs.is_object()) fail("/textures", "expected an object, got " + type_name(texs));
      ObjectReader tr(texs, "/textures");
      for (auto it = texs.begin(); it != texs.end(); ++it) {
        const std::string at = tr.at(it.key().c_str());
        const render::MaterialTextureSlot* slot = manifest.find_texture(it.key());
        if (!slot) fail(at, "unknown texture slot '" + it.key() + "'");
        if (!listed(slot->feature))
          fail(at, "texture '" + slot->name + "' needs feature '" + slot->feature + "' in /features");
        if (!it.value().is_string()) fail(at, "expected a file path, got " + type_name(it.value()));
        auto tex = load_texture(file.parent_path() / it.value().get<std::string>(), slot->srgb, assets);
        if (!tex) fail(at, tex.error().to_string());
        if (slot->name == "normal") m.normal_texture = *tex;
        else if (slot->name == "occlusion") m.occlusion_texture = *tex;
        else if (slot->name == "emissive") m.emissive_texture = *tex;
        else if (slot->name == "metallic_roughness") m.metallic_roughness_texture = *tex;
        else if (slot->name == "base_color") m.base_color_texture = *tex;
        else fail(at, "texture slot '" + slot->name + "' is declared but the engine does not know it");
        given.push_back(slot->name);
      }
    }
    for (const auto& slot : manifest.textures())
      if (listed(slot.feature) && std::find(given.begin(), given.end(), slot.name) == given.end())
        fail("/textures", "feature '" + slot.feature + "' needs texture '" + slot.name + "'");
    root.finish();
  } catch (const ContentError& e) {
    return Error{file.string(), e.where, e.message};
  }
  return m;
}

}  // namespace kaskad
