// glTF import: geometry. Accessors are read after every byte range is checked, Draco
// primitives (KHR_draco_mesh_compression) are decoded with libdraco, and primitives become
// triangle meshes (strips and fans unrolled, flat normals where the file has none).
#include <draco/compression/decode.h>
#include <draco/core/draco_types.h>
#include <draco/mesh/mesh.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>

#include "runtime/assets/gltf_internal.h"
#include "runtime/assets/mesh_tangents.h"

namespace kaskad::gltf_detail {
namespace {

// ---- Accessors ------------------------------------------------------------------------------

int component_size(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
    default:
      return 0;  // INT and DOUBLE are not glTF 2.0 component types
  }
}

bool is_unsigned_index_type(int type) {
  return type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
         type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
         type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
}

/// One component as a double; normalized integers map to [0,1] or [-1,1] (glTF 2.0, 3.11:
/// f = max(c / 127, -1) for signed bytes, c / 255 for unsigned bytes, likewise for shorts).
double read_component(const std::uint8_t* p, int type, bool normalized) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      std::int8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? std::max(v / 127.0, -1.0) : double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
      std::uint8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? v / 255.0 : double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      std::int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      std::uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0 : double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      std::uint32_t v;
      std::memcpy(&v, p, 4);
      return double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float v;
      std::memcpy(&v, p, 4);
      return double(v);
    }
    default:
      return 0.0;  // unreachable: component types are checked before reading
  }
}

/// What a caller expects of an accessor.
struct AccessorUse {
  int components;  ///< 1 for SCALAR, 2 for VEC2, ...
  bool indices;    ///< unsigned integer, not normalized (index buffers)
};

/// Reads accessor `index` into `count * components` values of T (float or uint32), applying
/// glTF normalization and sparse substitution; validates every index and byte range.
template <class T>
Result<std::vector<T>> read_accessor(const tinygltf::Model& model, const std::string& file,
                                     int index, AccessorUse use, const std::string& where_in) {
  const std::string where = where_in + " (" + label("accessors", index) + ")";
  if (index < 0 || std::size_t(index) >= model.accessors.size()) {
    return Error{file, where_in,
                 "accessor " + std::to_string(index) + " out of range (" +
                     std::to_string(model.accessors.size()) + " accessors)"};
  }
  const tinygltf::Accessor& a = model.accessors[std::size_t(index)];
  const int n = use.components;
  if (tinygltf::GetNumComponentsInType(std::uint32_t(a.type)) != n) {
    return Error{file, where, "expected " + std::to_string(n) + " components per element"};
  }
  const int csize = component_size(a.componentType);
  if (csize == 0) {
    return Error{file, where, "invalid componentType " + std::to_string(a.componentType)};
  }
  if (use.indices && !is_unsigned_index_type(a.componentType)) {
    return Error{file, where, "indices must be unsigned byte, short or int"};
  }
  if (a.normalized && (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                       a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)) {
    return Error{file, where, "normalized is not allowed with FLOAT or UNSIGNED_INT components"};
  }
  if (a.count > kMaxAccessorElements) {
    return Error{file, where,
                 "count " + std::to_string(a.count) + " exceeds the limit of " +
                     std::to_string(kMaxAccessorElements)};
  }
  if (a.bufferView < 0 && a.count > kMaxImplicitElements) {
    return Error{file, where,
                 "count " + std::to_string(a.count) + " without a bufferView " +
                     "exceeds the limit of " + std::to_string(kMaxImplicitElements)};
  }
  const bool normalized = a.normalized && !use.indices;
  const std::uint64_t element_size = std::uint64_t(csize) * std::uint64_t(n);

  std::vector<T> out(a.count * std::size_t(n), T(0));  // no bufferView: zeros (glTF 3.6.2.3)
  auto read_element = [&](const std::uint8_t* src, std::size_t element) {
    for (int c = 0; c < n; ++c)
      out[element * std::size_t(n) + std::size_t(c)] = static_cast<T>(
          read_component(src + std::size_t(c) * std::size_t(csize), a.componentType, normalized));
  };

  if (a.bufferView >= 0) {
    std::uint64_t stride = element_size;
    if (std::size_t(a.bufferView) < model.bufferViews.size()) {
      const std::size_t view_stride = model.bufferViews[std::size_t(a.bufferView)].byteStride;
      if (view_stride != 0) stride = view_stride;
    }
    if (stride < element_size) {
      return Error{file, where,
                   "byteStride " + std::to_string(stride) + " is smaller than an element (" +
                       std::to_string(element_size) + " bytes)"};
    }
    auto src =
        locate(model, file, a.bufferView, a.byteOffset, a.count, element_size, stride, where);
    if (!src) return src.error();
    for (std::size_t e = 0; e < a.count; ++e) read_element(src.value() + e * stride, e);
  }

  if (a.sparse.isSparse) {
    const auto& s = a.sparse;
    if (s.count < 1 || std::uint64_t(s.count) > a.count) {
      return Error{file, where,
                   "sparse count " + std::to_string(s.count) + " must be in [1, count]"};
    }
    const int isize = component_size(s.indices.componentType);
    if (!is_unsigned_index_type(s.indices.componentType)) {
      return Error{file, where, "sparse indices must be unsigned byte, short or int"};
    }
    if (s.indices.byteOffset < 0 || s.values.byteOffset < 0) {
      return Error{file, where, "negative sparse byteOffset"};
    }
    auto indices = locate(model, file, s.indices.bufferView, std::uint64_t(s.indices.byteOffset),
                          std::uint64_t(s.count), std::uint64_t(isize), std::uint64_t(isize),
                          where + " sparse indices");
    if (!indices) return indices.error();
    auto values =
        locate(model, file, s.values.bufferView, std::uint64_t(s.values.byteOffset),
               std::uint64_t(s.count), element_size, element_size, where + " sparse values");
    if (!values) return values.error();
    for (int k = 0; k < s.count; ++k) {
      const double target = read_component(indices.value() + std::size_t(k) * std::size_t(isize),
                                           s.indices.componentType, false);
      if (target >= double(a.count)) {
        return Error{file, where,
                     "sparse index " + std::to_string(std::uint64_t(target)) + " >= count " +
                         std::to_string(a.count)};
      }
      read_element(values.value() + std::size_t(k) * element_size, std::size_t(target));
    }
  }

  if constexpr (std::is_floating_point_v<T>) {
    for (std::size_t i = 0; i < out.size(); ++i) {
      if (!std::isfinite(out[i])) {
        return Error{
            file, where,
            "non-finite value (NaN or infinity) in element " + std::to_string(i / std::size_t(n))};
      }
    }
  }
  return out;
}

// ---- KHR_draco_mesh_compression -------------------------------------------------------------

/// A decoded Draco primitive and the glTF attribute names it provides (name -> Draco unique id).
struct DracoPrimitive {
  std::unique_ptr<draco::Mesh> mesh;
  std::map<std::string, int> attribute_ids;
};

/// Decodes the primitive's Draco buffer view. Every value the glTF gives (view, attribute ids)
/// and every count in the stream is checked before use; a corrupt stream is an Error.
Result<DracoPrimitive> decode_draco(const tinygltf::Model& model, const std::string& file,
                                    const tinygltf::Value& ext, const std::string& where_in) {
  const std::string where = where_in + " KHR_draco_mesh_compression";
  DracoPrimitive out;
  int view_index = -1;
  const tinygltf::Value* view_value = member(ext, "bufferView");
  if (view_value == nullptr || !as_index(*view_value, view_index)) {
    return Error{file, where, "bufferView missing or not a valid index"};
  }
  const tinygltf::Value* attributes = member(ext, "attributes");
  if (attributes == nullptr || !attributes->IsObject()) {
    return Error{file, where, "attributes missing or not an object"};
  }
  for (const std::string& key : attributes->Keys()) {
    int id = -1;
    if (!as_index(attributes->Get(key), id)) {
      return Error{file, where, "attribute " + key + " has no valid Draco id"};
    }
    out.attribute_ids[key] = id;
  }

  if (std::size_t(view_index) >= model.bufferViews.size()) {
    return Error{file, where,
                 "bufferView " + std::to_string(view_index) + " out of range (" +
                     std::to_string(model.bufferViews.size()) + " buffer views)"};
  }
  const std::size_t length = model.bufferViews[std::size_t(view_index)].byteLength;
  if (length == 0) return Error{file, where, "empty Draco buffer view"};
  auto bytes = locate(model, file, view_index, 0, 1, length, length, where);
  if (!bytes) return bytes.error();

  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(bytes.value()), length);
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok()) {
    return Error{file, where,
                 "corrupt Draco data in " + label("bufferViews", view_index) + ": " +
                     decoded.status().error_msg_string()};
  }
  out.mesh = std::move(decoded).value();
  if (!out.mesh) return Error{file, where, "Draco decoder returned no mesh"};
  if (out.mesh->num_points() > kMaxAccessorElements ||
      std::uint64_t(out.mesh->num_faces()) * 3 > kMaxAccessorElements) {
    return Error{file, where, "Draco mesh too large"};
  }
  return out;
}

/// One attribute of a decoded Draco mesh as `components` floats per point.
Result<std::vector<float>> draco_attribute(const draco::Mesh& mesh, int unique_id, int components,
                                           const std::string& file, const std::string& where) {
  const draco::PointAttribute* a = mesh.GetAttributeByUniqueId(std::uint32_t(unique_id));
  if (a == nullptr) {
    return Error{file, where,
                 "the Draco stream has no attribute with id " + std::to_string(unique_id)};
  }
  if (a->num_components() != components) {
    return Error{file, where,
                 "Draco attribute has " + std::to_string(a->num_components()) +
                     " components, expected " + std::to_string(components)};
  }
  const std::uint32_t points = mesh.num_points();
  const std::int64_t value_bytes = std::int64_t(components) * draco::DataTypeLength(a->data_type());
  if (a->buffer() == nullptr || value_bytes <= 0 ||
      (!a->is_mapping_identity() && a->indices_map_size() < points)) {
    return Error{file, where, "inconsistent Draco attribute"};
  }
  std::vector<float> out(std::size_t(points) * std::size_t(components));
  for (std::uint32_t p = 0; p < points; ++p) {
    const draco::AttributeValueIndex v = a->mapped_index(draco::PointIndex(p));
    const std::int64_t pos = a->GetBytePos(v);
    if (v.value() >= a->size() || pos < 0 ||
        pos + value_bytes > std::int64_t(a->buffer()->data_size()) ||
        !a->ConvertValue<float>(v, std::int8_t(components), &out[std::size_t(p) * components])) {
      return Error{file, where,
                   "Draco attribute value " + std::to_string(v.value()) + " of point " +
                       std::to_string(p) + " is out of range"};
    }
  }
  for (float f : out) {
    if (!std::isfinite(f)) return Error{file, where, "non-finite value (NaN or infinity)"};
  }
  return out;
}

// ---- Meshes ---------------------------------------------------------------------------------

/// Triangle list from an index list in glTF primitive mode (strip and fan winding per 3.7.2.1).
std::vector<std::uint32_t> to_triangle_list(const std::vector<std::uint32_t>& idx, int mode) {
  if (mode == TINYGLTF_MODE_TRIANGLES) return idx;
  std::vector<std::uint32_t> out;
  if (idx.size() < 3) return out;
  out.reserve((idx.size() - 2) * 3);
  for (std::size_t i = 0; i + 2 < idx.size(); ++i) {
    if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      const bool odd = i % 2 == 1;
      out.insert(out.end(), {idx[i], idx[i + (odd ? 2 : 1)], idx[i + (odd ? 1 : 2)]});
    } else {  // fan
      out.insert(out.end(), {idx[i + 1], idx[i + 2], idx[0]});
    }
  }
  return out;
}

/// glTF 3.7.2.1: "When normals are not specified, client implementations MUST calculate flat
/// normals" (and ignore tangents). Un-indexes the mesh so each triangle has its own vertices.
/// JOINTS_n / WEIGHTS_n (4 or 8 influences, weights normalised to sum 1) and morph targets
/// (POSITION, NORMAL, TANGENT displacements; glTF 2.0, 3.7.2.2) of a primitive. `attribute`
/// reads a named attribute as floats (from the Draco stream where it has it).
template <typename Attribute>
Status read_deform(const tinygltf::Model& model, const std::string& file,
                   const tinygltf::Primitive& prim, const tinygltf::Mesh& mesh,
                   const std::string& where, std::size_t vertex_count, Attribute& attribute,
                   MeshDeform& out, std::vector<std::string>& warnings) {
  for (int set = 0; set < 2; ++set) {
    const std::string jn = "JOINTS_" + std::to_string(set), wn = "WEIGHTS_" + std::to_string(set);
    // glTF 3.7.3.3: joints are unsigned bytes or shorts, weights floats or normalized unsigned
    // bytes or shorts. Other types are read as they come, with a warning.
    const auto accessor = [&](const std::string& name) -> const tinygltf::Accessor* {
      const auto it = prim.attributes.find(name);
      return it == prim.attributes.end() || it->second < 0 ||
                     std::size_t(it->second) >= model.accessors.size()
                 ? nullptr
                 : &model.accessors[std::size_t(it->second)];
    };
    if (const auto* a = accessor(jn); a && a->componentType == TINYGLTF_COMPONENT_TYPE_FLOAT)
      warnings.push_back(where + ": " + jn + " are floats (glTF: unsigned byte or short); read as "
                                            "whole joint numbers");
    if (const auto* a = accessor(wn); a && a->componentType != TINYGLTF_COMPONENT_TYPE_FLOAT &&
                                      !a->normalized)
      warnings.push_back(where + ": " + wn + " are integers without normalized: true (glTF: floats "
                                            "or normalized integers); read as fractions of their range");
    auto joints = attribute(jn, 4);
    if (!joints) return joints.error();
    auto weights = attribute(wn, 4);
    if (!weights) return weights.error();
    if (joints->empty() && weights->empty()) break;
    if (joints->size() != vertex_count * 4 || weights->size() != vertex_count * 4)
      return Error{file, where,
                   jn + " has " + std::to_string(joints->size() / 4) + " and " + wn + " " +
                       std::to_string(weights->size() / 4) +
                       " elements; both must be given, one per vertex (" +
                       std::to_string(vertex_count) + ")"};
    if (set == 1) {  // interleave the second set after the first, 8 per vertex
      std::vector<std::uint32_t> j8(vertex_count * 8);
      std::vector<float> w8(vertex_count * 8);
      for (std::size_t v = 0; v < vertex_count; ++v)
        for (int k = 0; k < 4; ++k) {
          j8[v * 8 + k] = out.joints[v * 4 + k];
          w8[v * 8 + k] = out.weights[v * 4 + k];
          j8[v * 8 + 4 + k] = std::uint32_t((*joints)[v * 4 + k]);
          w8[v * 8 + 4 + k] = (*weights)[v * 4 + k];
        }
      out.joints = std::move(j8);
      out.weights = std::move(w8);
    } else {
      out.joints.resize(joints->size());
      for (std::size_t i = 0; i < joints->size(); ++i) out.joints[i] = std::uint32_t((*joints)[i]);
      out.weights = std::move(weights.value());
    }
    out.influences = 4 * (set + 1);
  }
  if (out.skinned()) {
    const std::size_t n = std::size_t(out.influences);
    for (std::size_t v = 0; v < vertex_count; ++v) {
      float sum = 0.0f;
      for (std::size_t k = 0; k < n; ++k) {
        const float w = out.weights[v * n + k];
        if (!(std::isfinite(w) && w >= 0.0f))
          return Error{file, where + " WEIGHTS",
                       "vertex " + std::to_string(v) + " has a weight that is negative or not finite"};
        sum += w;
      }
      // glTF asks for weights that sum to 1; quantised ones only approximately do. A vertex
      // with no weight at all follows its first joint.
      for (std::size_t k = 0; k < n; ++k)
        out.weights[v * n + k] = sum > 0.0f ? out.weights[v * n + k] / sum : (k == 0 ? 1.0f : 0.0f);
    }
  }
  for (std::size_t t = 0; t < prim.targets.size(); ++t) {
    const std::string tw = where + " targets[" + std::to_string(t) + "]";
    MeshDeform::Target target;
    auto read = [&](const char* name, int components,
                    std::vector<glm::vec3>& into) -> Status {
      auto it = prim.targets[t].find(name);
      into.assign(vertex_count, glm::vec3(0.0f));
      if (it == prim.targets[t].end()) return {};
      auto values = read_accessor<float>(model, file, it->second, {components, false},
                                         tw + " " + name);
      if (!values) return values.error();
      if (values->size() != vertex_count * std::size_t(components))
        return Error{file, tw + " " + name,
                     "has " + std::to_string(values->size() / std::size_t(components)) +
                         " elements but POSITION has " + std::to_string(vertex_count)};
      for (std::size_t v = 0; v < vertex_count; ++v)
        into[v] = glm::vec3((*values)[v * std::size_t(components)],
                            (*values)[v * std::size_t(components) + 1],
                            (*values)[v * std::size_t(components) + 2]);
      return {};
    };
    KASKAD_TRY(read("POSITION", 3, target.positions));
    KASKAD_TRY(read("NORMAL", 3, target.normals));
    // Target tangents are VEC3 (glTF 3.7.2.2: no handedness).
    KASKAD_TRY(read("TANGENT", 3, target.tangents));
    target.delta_bounds.expand(glm::vec3(0.0f));
    for (const auto* stream : {&target.positions, &target.normals, &target.tangents})
      for (const glm::vec3& d : *stream)
        if (!(std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z)))
          return Error{file, tw, "displacements must be finite"};
    for (const glm::vec3& d : target.positions) target.delta_bounds.expand(d);
    out.targets.push_back(std::move(target));
  }
  if (!out.targets.empty()) {
    out.default_weights.assign(out.targets.size(), 0.0f);
    if (!mesh.weights.empty() && mesh.weights.size() != out.targets.size())
      return Error{file, where, "mesh weights has " + std::to_string(mesh.weights.size()) +
                                    " values for " + std::to_string(out.targets.size()) +
                                    " morph targets"};
    for (std::size_t t = 0; t < mesh.weights.size(); ++t) {
      if (!std::isfinite(mesh.weights[t]))
        return Error{file, where, "mesh weights must be finite"};
      out.default_weights[t] = float(mesh.weights[t]);
    }
  }
  return {};
}

void make_flat_normals(MeshData& m) {
  MeshData flat;
  flat.name = m.name;
  const bool has_uvs = !m.uvs.empty(), has_uvs1 = !m.uvs1.empty();
  std::vector<std::uint32_t> flat_sources;  // the vertex each flat vertex copies
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const std::uint32_t i[3] = {m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]};
    const glm::vec3 a = m.positions[i[0]], b = m.positions[i[1]], c = m.positions[i[2]];
    glm::vec3 n = glm::cross(b - a, c - a);
    const float len = glm::length(n);
    n = len > 0.0f && std::isfinite(len) ? n / len : glm::vec3(0, 1, 0);  // degenerate: any unit
    for (std::uint32_t k : i) {
      flat_sources.push_back(k);
      flat.indices.push_back(std::uint32_t(flat.positions.size()));
      flat.positions.push_back(m.positions[k]);
      flat.normals.push_back(n);
      if (has_uvs) flat.uvs.push_back(m.uvs[k]);
      if (has_uvs1) flat.uvs1.push_back(m.uvs1[k]);
      const std::size_t j = std::size_t(m.deform.influences);
      flat.deform.joints.insert(flat.deform.joints.end(), m.deform.joints.begin() + k * j,
                                m.deform.joints.begin() + (k + 1) * j);
      flat.deform.weights.insert(flat.deform.weights.end(), m.deform.weights.begin() + k * j,
                                 m.deform.weights.begin() + (k + 1) * j);
    }
  }
  // Skins and morph targets follow their vertices (a target's normals stay zero: flat normals
  // are not morphed).
  flat.deform.influences = m.deform.influences;
  flat.deform.default_weights = m.deform.default_weights;
  for (const MeshDeform::Target& t : m.deform.targets) {
    MeshDeform::Target& ft = flat.deform.targets.emplace_back();
    ft.delta_bounds = t.delta_bounds;
    for (std::uint32_t k : flat_sources) ft.positions.push_back(t.positions[k]);
    ft.normals.assign(ft.positions.size(), glm::vec3(0.0f));
  }
  m = std::move(flat);
}

}  // namespace

Result<std::vector<float>> read_float_accessor(const tinygltf::Model& model,
                                               const std::string& file, int index,
                                               int components, const std::string& where) {
  return read_accessor<float>(model, file, index, {components, false}, where);
}

Result<const std::uint8_t*> locate(const tinygltf::Model& model, const std::string& file,
                                   int view_index, std::uint64_t offset, std::uint64_t count,
                                   std::uint64_t element_size, std::uint64_t stride,
                                   const std::string& where) {
  if (view_index < 0 || std::size_t(view_index) >= model.bufferViews.size()) {
    return Error{file, where,
                 "bufferView " + std::to_string(view_index) + " out of range (" +
                     std::to_string(model.bufferViews.size()) + " buffer views)"};
  }
  const tinygltf::BufferView& view = model.bufferViews[std::size_t(view_index)];
  if (view.buffer < 0 || std::size_t(view.buffer) >= model.buffers.size()) {
    return Error{file, where,
                 label("bufferViews", view_index) + " refers to buffer " +
                     std::to_string(view.buffer) + ", out of range (" +
                     std::to_string(model.buffers.size()) + " buffers)"};
  }
  const std::vector<unsigned char>& data = model.buffers[std::size_t(view.buffer)].data;
  if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset) {
    return Error{file, where,
                 label("bufferViews", view_index) + " (offset " + std::to_string(view.byteOffset) +
                     ", length " + std::to_string(view.byteLength) + ") exceeds buffer " +
                     std::to_string(view.buffer) + " (" + std::to_string(data.size()) + " bytes)"};
  }
  if (count == 0) return static_cast<const std::uint8_t*>(nullptr);
  // count <= kMaxAccessorElements and stride, element_size < 2^16: no overflow below.
  if (offset > view.byteLength || stride * (count - 1) + element_size > view.byteLength - offset) {
    return Error{file, where,
                 std::to_string(count) + " elements of " + std::to_string(element_size) +
                     " bytes (stride " + std::to_string(stride) + ") from byte " +
                     std::to_string(offset) + " run past the end of " +
                     label("bufferViews", view_index) + " (" + std::to_string(view.byteLength) +
                     " bytes)"};
  }
  return data.data() + view.byteOffset + offset;
}

Result<std::optional<MeshData>> read_primitive(const tinygltf::Model& model,
                                               const std::string& file, int mesh_index,
                                               int prim_index, std::vector<std::string>& warnings) {
  const tinygltf::Mesh& mesh = model.meshes[std::size_t(mesh_index)];
  const tinygltf::Primitive& prim = mesh.primitives[std::size_t(prim_index)];
  const std::string where =
      label("meshes", mesh_index, mesh.name) + " primitives[" + std::to_string(prim_index) + "]";

  if (prim.mode >= TINYGLTF_MODE_POINTS && prim.mode <= TINYGLTF_MODE_LINE_STRIP) {
    warnings.push_back(where + ": points and lines are not imported");
    return std::optional<MeshData>();
  }
  if (prim.mode < TINYGLTF_MODE_TRIANGLES || prim.mode > TINYGLTF_MODE_TRIANGLE_FAN) {
    return Error{file, where, "invalid mode " + std::to_string(prim.mode)};
  }

  std::optional<DracoPrimitive> draco;
  if (auto ext = prim.extensions.find("KHR_draco_mesh_compression"); ext != prim.extensions.end()) {
    auto decoded = decode_draco(model, file, ext->second, where);
    if (!decoded) return decoded.error();
    draco = std::move(decoded.value());
  }

  // An attribute comes from the Draco stream when the extension lists it, else from its accessor;
  // absent attributes come back empty.
  auto attribute = [&](const std::string& name, int components) -> Result<std::vector<float>> {
    if (draco) {
      if (auto id = draco->attribute_ids.find(name); id != draco->attribute_ids.end())
        return draco_attribute(*draco->mesh, id->second, components, file, where + " " + name);
    }
    auto it = prim.attributes.find(name);
    if (it == prim.attributes.end()) return std::vector<float>();
    return read_accessor<float>(model, file, it->second, {components, false}, where + " " + name);
  };

  auto positions = attribute("POSITION", 3);
  if (!positions) return positions.error();
  if (!prim.attributes.count("POSITION") && !(draco && draco->attribute_ids.count("POSITION"))) {
    return Error{file, where, "no POSITION attribute"};
  }
  const std::size_t vertex_count = positions->size() / 3;
  auto normals = attribute("NORMAL", 3);
  if (!normals) return normals.error();
  auto uvs = attribute("TEXCOORD_0", 2);
  if (!uvs) return uvs.error();
  auto uvs1 = attribute("TEXCOORD_1", 2);
  if (!uvs1) return uvs1.error();
  auto tangents = attribute("TANGENT", 4);
  if (!tangents) return tangents.error();
  const std::pair<const char*, std::size_t> counts[] = {{"NORMAL", normals->size() / 3},
                                                        {"TEXCOORD_0", uvs->size() / 2},
                                                        {"TEXCOORD_1", uvs1->size() / 2},
                                                        {"TANGENT", tangents->size() / 4}};
  for (const auto& [name, count] : counts) {
    if (count != 0 && count != vertex_count) {
      return Error{file, where,
                   std::string(name) + " has " + std::to_string(count) +
                       " elements but POSITION has " + std::to_string(vertex_count)};
    }
  }

  std::vector<std::uint32_t> indices;
  if (draco) {
    if (prim.mode != TINYGLTF_MODE_TRIANGLES) {
      return Error{file, where, "a Draco primitive must use mode TRIANGLES"};
    }
    const draco::Mesh& dm = *draco->mesh;
    indices.reserve(std::size_t(dm.num_faces()) * 3);
    for (draco::FaceIndex f(0); f < dm.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) indices.push_back(dm.face(f)[k].value());
  } else if (prim.indices >= 0) {
    auto read =
        read_accessor<std::uint32_t>(model, file, prim.indices, {1, true}, where + " indices");
    if (!read) return read.error();
    indices = std::move(read.value());
  } else {
    indices.resize(vertex_count);
    for (std::size_t i = 0; i < vertex_count; ++i) indices[i] = std::uint32_t(i);
  }
  for (std::size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] >= vertex_count) {
      return Error{file, where + " indices",
                   "index " + std::to_string(indices[i]) + " at position " + std::to_string(i) +
                       " is out of range (" + std::to_string(vertex_count) + " vertices)"};
    }
  }
  if (prim.mode == TINYGLTF_MODE_TRIANGLES && indices.size() % 3 != 0) {
    return Error{
        file, where,
        std::to_string(indices.size()) + " indices is not a multiple of 3 (mode TRIANGLES)"};
  }
  indices = to_triangle_list(indices, prim.mode);
  if (indices.empty()) {
    warnings.push_back(where + ": no triangles");
    return std::optional<MeshData>();
  }

  MeshData m;
  m.name = (mesh.name.empty() ? label("meshes", mesh_index) : mesh.name) +
           (mesh.primitives.size() > 1 ? "#" + std::to_string(prim_index) : "");
  m.positions.resize(vertex_count);
  std::memcpy(m.positions.data(), positions->data(), positions->size() * sizeof(float));
  if (!uvs->empty()) {
    m.uvs.resize(vertex_count);
    std::memcpy(m.uvs.data(), uvs->data(), uvs->size() * sizeof(float));
  }
  if (!uvs1->empty()) {
    m.uvs1.resize(vertex_count);
    std::memcpy(m.uvs1.data(), uvs1->data(), uvs1->size() * sizeof(float));
  }
  m.indices = std::move(indices);
  KASKAD_TRY(read_deform(model, file, prim, mesh, where, vertex_count, attribute, m.deform, warnings));
  if (normals->empty()) {
    make_flat_normals(m);
  } else {
    m.normals.resize(vertex_count);
    for (std::size_t v = 0; v < vertex_count; ++v) {
      const glm::vec3 n{(*normals)[3 * v], (*normals)[3 * v + 1], (*normals)[3 * v + 2]};
      const float len = glm::length(n);
      // Quantised normals are only approximately unit length; zero ones stay zero.
      m.normals[v] = len > 0.0f ? n / len : n;
    }
    if (!tangents->empty()) {
      m.tangents.resize(vertex_count);
      std::memcpy(m.tangents.data(), tangents->data(), tangents->size() * sizeof(float));
    }
  }
  m.compute_bounds();  // from positions: Draco data may lie outside the accessor min/max
  return std::optional<MeshData>(std::move(m));
}

}  // namespace kaskad::gltf_detail
