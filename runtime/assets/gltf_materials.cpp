// glTF import: materials and textures. The metallic-roughness material and the extensions
// Kaskad reads become a Material; textures are decoded once per (image, colour space).
#include <algorithm>
#include <cmath>

#include "runtime/assets/gltf_internal.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/material_file.h"

namespace kaskad::gltf_detail {
namespace {

Result<Image> decode_view_image(const Importer& im, int image_index) {
  const tinygltf::Image& image = im.model.images[std::size_t(image_index)];
  const std::string where = label("images", image_index, image.name);
  if (std::size_t(image.bufferView) >= im.model.bufferViews.size()) {
    return Error{im.file, where, "bufferView out of range"};
  }
  const std::size_t length = im.model.bufferViews[std::size_t(image.bufferView)].byteLength;
  auto bytes =
      locate(im.model, im.file, image.bufferView, 0, length > 0 ? 1 : 0, length, length, where);
  if (!bytes) return bytes.error();
  return load_image_from_memory(bytes.value(), length, where, image.mimeType);
}

/// The texture for a material slot; kNoTexture (with a warning) when its image is unusable.
Result<TextureId> texture_for(Importer& im, int texture_index, int tex_coord, bool srgb,
                              const std::string& where) {
  if (texture_index < 0) return kNoTexture;
  const auto& model = im.model;
  if (std::size_t(texture_index) >= model.textures.size()) {
    return Error{im.file, where,
                 "texture " + std::to_string(texture_index) + " out of range (" +
                     std::to_string(model.textures.size()) + " textures)"};
  }
  if (tex_coord > 1) {
    im.report.warnings.push_back(where + ": uses TEXCOORD_" + std::to_string(tex_coord) +
                                 "; only TEXCOORD_0 and TEXCOORD_1 are imported (reads TEXCOORD_0)");
  }
  // The image: EXT_texture_webp's (OpenImageIO reads WebP), else the texture's own source, which
  // is also the fallback of a texture with an EXT_texture_avif image (AVIF is not decoded).
  const tinygltf::Texture& gtex = model.textures[std::size_t(texture_index)];
  int source = gtex.source;
  if (auto webp = gtex.extensions.find("EXT_texture_webp"); webp != gtex.extensions.end()) {
    const tinygltf::Value* s = member(webp->second, "source");
    if (!s || !s->IsInt() || s->GetNumberAsInt() < 0)
      return Error{im.file, label("textures", texture_index) + " EXT_texture_webp",
                   "source must be an image index >= 0"};
    source = s->GetNumberAsInt();
  }
  if (source < 0) {
    const bool avif = gtex.extensions.count("EXT_texture_avif") != 0;
    im.report.warnings.push_back(
        where + ": " + label("textures", texture_index) +
        (avif ? " has only an EXT_texture_avif image, which is not decoded here, and no "
                "fallback source: drawn without it"
              : " has no source image"));
    return kNoTexture;
  }
  if (std::size_t(source) >= model.images.size()) {
    return Error{im.file, label("textures", texture_index),
                 "source image " + std::to_string(source) + " out of range"};
  }
  if (auto it = im.textures.find({source, srgb}); it != im.textures.end()) return it->second;
  if (im.failed_images.count(source)) return kNoTexture;

  const tinygltf::Image& image = model.images[std::size_t(source)];
  const std::string image_label =
      label("images", source, image.name.empty() ? image.uri : image.name);
  TextureData texture;
  texture.name = image.name.empty() ? (image.uri.empty() ? image_label : image.uri) : image.name;
  texture.srgb = srgb;
  if (!image.image.empty()) {  // decoded by load_image_callback
    texture.width = image.width;
    texture.height = image.height;
    texture.rgba8 = image.image;
  } else if (image.bufferView >= 0) {
    auto decoded = decode_view_image(im, source);
    if (decoded) {
      texture.width = decoded->width;
      texture.height = decoded->height;
      texture.rgba8 = to_rgba8(decoded.value());
    } else {
      im.images.failures[source] = decoded.error().message;
    }
  } else if (!im.images.failures.count(source)) {
    im.images.failures[source] = "image file not loaded";  // tinygltf warned why
  }
  if (texture.rgba8.empty()) {
    im.failed_images.insert(source);
    im.report.warnings.push_back(image_label + ": " + im.images.failures[source] +
                                 "; materials using it are drawn without it");
    return kNoTexture;
  }
  const TextureId id = im.assets.add_texture(std::move(texture));
  im.textures[{source, srgb}] = id;
  return id;
}

float clamp01(double v) {
  return float(std::clamp(v, 0.0, 1.0));
}

/// `count` finite numbers from a JSON array member of an extension object.
bool finite_numbers(const tinygltf::Value& array, std::size_t count, float* out) {
  if (!array.IsArray() || array.ArrayLen() != count) return false;
  for (std::size_t i = 0; i < count; ++i) {
    const tinygltf::Value& x = array.Get(int(i));
    if (!x.IsNumber() || !std::isfinite(x.GetNumberAsDouble())) return false;
    out[i] = float(x.GetNumberAsDouble());
  }
  return true;
}

/// A texture reference's KHR_texture_transform (offset, rotation, scale; identity without the
/// extension). Its texCoord, when given, overrides the reference's `tex_coord`.
Result<TextureTransform> read_texture_transform(const Importer& im,
                                                const tinygltf::ExtensionMap& extensions,
                                                int& tex_coord, const std::string& where_in) {
  TextureTransform t;
  const auto ext = extensions.find("KHR_texture_transform");
  if (ext == extensions.end()) return t;
  const std::string where = where_in + " KHR_texture_transform";
  if (!ext->second.IsObject()) return Error{im.file, where, "must be an object"};
  const tinygltf::Value* offset = member(ext->second, "offset");
  if (offset && !finite_numbers(*offset, 2, &t.offset[0]))
    return Error{im.file, where, "offset must be 2 finite numbers"};
  if (const tinygltf::Value* v = member(ext->second, "rotation")) {
    if (!v->IsNumber() || !std::isfinite(v->GetNumberAsDouble()))
      return Error{im.file, where, "rotation must be a finite number (radians)"};
    t.rotation = float(v->GetNumberAsDouble());
  }
  const tinygltf::Value* scale = member(ext->second, "scale");
  if (scale && !finite_numbers(*scale, 2, &t.scale[0]))
    return Error{im.file, where, "scale must be 2 finite numbers"};
  if (const tinygltf::Value* v = member(ext->second, "texCoord")) {
    if (!v->IsInt() || v->GetNumberAsInt() < 0)
      return Error{im.file, where, "texCoord must be an integer >= 0"};
    tex_coord = v->GetNumberAsInt();
  }
  return t;
}

/// One texture slot of a material: the texture (kNoTexture when absent or unusable) and its
/// KHR_texture_transform.
struct TextureSlot {
  TextureId texture = kNoTexture;
  TextureTransform transform;
};
Result<TextureSlot> read_slot(Importer& im, int index, int tex_coord,
                              const tinygltf::ExtensionMap& extensions, bool srgb,
                              const std::string& where) {
  TextureSlot slot;
  if (index < 0) return slot;
  auto transform = read_texture_transform(im, extensions, tex_coord, where);
  if (!transform) return transform.error();
  slot.transform = transform.value();
  slot.transform.tex_coord = tex_coord == 1 ? 1 : 0;
  auto texture = texture_for(im, index, tex_coord, srgb, where);
  if (!texture) return texture.error();
  slot.texture = texture.value();
  return slot;
}

/// A node's matrix as TRS (components/transform.h decompose(); glTF requires matrices to be
/// TRS-decomposable, 5.25), with warnings for what that loses: a projective part, shear.

}  // namespace

Result<Material> read_material(Importer& im, int index) {
  if (auto it = im.materials.find(index); it != im.materials.end()) return it->second;
  const tinygltf::Material default_material;
  if (index >= 0 && std::size_t(index) >= im.model.materials.size()) {
    return Error{im.file, "",
                 "material " + std::to_string(index) + " out of range (" +
                     std::to_string(im.model.materials.size()) + " materials)"};
  }
  const tinygltf::Material& g =
      index >= 0 ? im.model.materials[std::size_t(index)] : default_material;
  const std::string where = index >= 0 ? label("materials", index, g.name) : "default material";
  const auto& pbr = g.pbrMetallicRoughness;

  const std::vector<double>& base = pbr.baseColorFactor;
  if (!(base.empty() || base.size() == 4) || !all_finite(base)) {
    return Error{im.file, where, "baseColorFactor must be 4 finite numbers"};
  }
  const std::vector<double>& emissive = g.emissiveFactor;
  if (!(emissive.empty() || emissive.size() == 3) || !all_finite(emissive)) {
    return Error{im.file, where, "emissiveFactor must be 3 finite numbers"};
  }
  if (!std::isfinite(pbr.metallicFactor) || !std::isfinite(pbr.roughnessFactor) ||
      !std::isfinite(g.normalTexture.scale)) {
    return Error{im.file, where, "non-finite metallic, roughness or normal scale factor"};
  }
  if (!(g.occlusionTexture.strength >= 0.0 && g.occlusionTexture.strength <= 1.0)) {
    return Error{im.file, where + " occlusionTexture",
                 "strength must be a number in [0, 1], was " +
                     std::to_string(g.occlusionTexture.strength)};
  }

  Material m;
  if (base.size() == 4) {
    m.base_color = {clamp01(base[0]), clamp01(base[1]), clamp01(base[2]), clamp01(base[3])};
    if (std::any_of(base.begin(), base.end(), [](double v) { return v < 0.0 || v > 1.0; }))
      im.report.warnings.push_back(where + ": baseColorFactor outside [0, 1], clamped to it");
  }
  m.metallic = clamp01(pbr.metallicFactor);
  m.roughness = clamp01(pbr.roughnessFactor);
  m.normal_scale = float(g.normalTexture.scale);
  m.double_sided = g.doubleSided;
  if (emissive.size() == 3) {
    m.emissive = {std::max(0.0, emissive[0]), std::max(0.0, emissive[1]),
                  std::max(0.0, emissive[2])};
  }
  if (auto ext = g.extensions.find("KHR_materials_emissive_strength"); ext != g.extensions.end()) {
    const tinygltf::Value* strength = member(ext->second, "emissiveStrength");
    if (strength != nullptr && !strength->IsNumber()) {
      return Error{im.file, where + " KHR_materials_emissive_strength",
                   "emissiveStrength must be a number"};
    }
    if (strength != nullptr) {
      const double s = strength->GetNumberAsDouble();
      if (!std::isfinite(s) || s < 0.0) {
        return Error{im.file, where, "emissiveStrength must be a finite number >= 0"};
      }
      m.emissive *= float(s);
    }
  }

  // Each slot: its texture and KHR_texture_transform (sRGB for colours, linear for data).
  auto base_slot = read_slot(im, pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord,
                             pbr.baseColorTexture.extensions, true, where + " baseColorTexture");
  if (!base_slot) return base_slot.error();
  m.base_color_texture = base_slot->texture;
  m.base_color_transform = base_slot->transform;
  auto normal_slot = read_slot(im, g.normalTexture.index, g.normalTexture.texCoord,
                               g.normalTexture.extensions, false, where + " normalTexture");
  if (!normal_slot) return normal_slot.error();
  m.normal_texture = normal_slot->texture;
  m.normal_transform = normal_slot->transform;
  // Occlusion: the R channel scales the ambient light, by 1 + strength * (R - 1) (glTF 3.9.3).
  auto occlusion_slot =
      read_slot(im, g.occlusionTexture.index, g.occlusionTexture.texCoord,
                g.occlusionTexture.extensions, false, where + " occlusionTexture");
  if (!occlusion_slot) return occlusion_slot.error();
  m.occlusion_texture = occlusion_slot->texture;
  m.occlusion_transform = occlusion_slot->transform;
  m.occlusion_strength = float(g.occlusionTexture.strength);
  // Emissive: texture * emissiveFactor (* strength); without emission it has no effect.
  auto emissive_slot = read_slot(im, g.emissiveTexture.index, g.emissiveTexture.texCoord,
                                 g.emissiveTexture.extensions, true, where + " emissiveTexture");
  if (!emissive_slot) return emissive_slot.error();
  m.emissive_texture = emissive_slot->texture;
  m.emissive_transform = emissive_slot->transform;
  // Metallic-roughness: linear, B times metallicFactor, G times roughnessFactor (glTF 3.9.2).
  auto mr_slot = read_slot(im, pbr.metallicRoughnessTexture.index,
                           pbr.metallicRoughnessTexture.texCoord,
                           pbr.metallicRoughnessTexture.extensions, false,
                           where + " metallicRoughnessTexture");
  if (!mr_slot) return mr_slot.error();
  m.metallic_roughness_texture = mr_slot->texture;
  m.metallic_roughness_transform = mr_slot->transform;

  if (g.alphaMode == "MASK") {
    m.alpha_mode = AlphaMode::mask;
    m.alpha_cutoff = float(std::clamp(g.alphaCutoff, 0.0, 1.0));
    if (!(g.alphaCutoff >= 0.0 && g.alphaCutoff <= 1.0))
      im.report.warnings.push_back(where + ": alphaCutoff " + std::to_string(g.alphaCutoff) +
                                   " outside [0, 1], clamped to it");
  } else if (g.alphaMode == "BLEND") {
    m.alpha_mode = AlphaMode::blend;  // alphaCutoff is ignored (glTF 3.9.4): 0.5 for shadows
  } else if (g.alphaMode != "OPAQUE" && !g.alphaMode.empty()) {
    im.report.warnings.push_back(where + ": unknown alphaMode '" + g.alphaMode +
                                 "' (OPAQUE, MASK or BLEND); drawn opaque");
  }
  // KHR_materials_transmission: no refraction; a transmissive surface is blended, its opacity
  // transmission_opacity() of its alpha (components/material.h). A MASK material stays a
  // cut-out without transmission (its alpha is the mask's; a warning says so).
  if (auto ext = g.extensions.find("KHR_materials_transmission"); ext != g.extensions.end()) {
    const std::string ext_where = where + " KHR_materials_transmission";
    if (!ext->second.IsObject()) return Error{im.file, ext_where, "must be an object"};
    double t = 0.0;
    if (const tinygltf::Value* v = member(ext->second, "transmissionFactor")) {
      if (!v->IsNumber() || !(v->GetNumberAsDouble() >= 0.0 && v->GetNumberAsDouble() <= 1.0))
        return Error{im.file, ext_where, "transmissionFactor must be a number in [0, 1]"};
      t = v->GetNumberAsDouble();
    }
    if (member(ext->second, "transmissionTexture"))
      im.report.warnings.push_back(ext_where + ": transmissionTexture not imported (the factor "
                                               "applies everywhere)");
    if (t > 0.0) {
      if (m.alpha_mode == AlphaMode::mask) {
        im.report.warnings.push_back(ext_where + ": on an alphaMode MASK material; drawn as a "
                                                 "cut-out without transmission");
      } else {
        m.alpha_mode = AlphaMode::blend;
        m.base_color.a = transmission_opacity(m.base_color.a, float(t));
      }
    }
  }
  // glTF materials map onto the same feature model as material files.
  m.features = derive_material_features(m);

  im.materials[index] = m;
  return m;
}

}  // namespace kaskad::gltf_detail
