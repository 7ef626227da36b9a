// glTF 2.0 import: tinygltf parses the JSON and loads buffers; this file validates everything it
// uses (indices, byte ranges, counts, numbers) before touching data, decodes
// KHR_draco_mesh_compression itself with libdraco (see tinygltf_config.h for why), and turns the
// default scene into entities. Content errors come back as Error and never abort (STYLE.md 10).
//
// The import, step by step (import_gltf):
//   1. read the file and refuse what tinygltf cannot parse safely (size, JSON nesting);
//   2. parse with tinygltf; URI images are decoded by our callback through OIIO, images stored in
//      buffer views later, once their view is range-checked;
//   3. refuse files that require extensions we do not implement;
//   4. validate the node hierarchy (indices, single parent) and pick the root nodes;
//   5. walk the hierarchy parents-first, creating node entities, primitive child entities (meshes
//      and materials are converted once, on first use) and lights and cameras.
#include "runtime/assets/gltf_loader.h"

#include <draco/compression/decode.h>
#include <draco/core/draco_types.h>
#include <draco/mesh/mesh.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <glm/gtc/quaternion.hpp>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <utility>
#include <vector>

#include "components/camera.h"
#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/name.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "runtime/assets/image_io.h"
#include "runtime/assets/material_file.h"
#include "runtime/assets/tinygltf_config.h"
#include "runtime/core/file_io.h"
#include "runtime/core/json_reader.h"

namespace kaskad {
namespace {

// ---- Limits on what a file may ask for (guards against absurd or hostile values) ----------

/// tinygltf takes sizes as unsigned int; 1 GiB is far above any model we expect.
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t(1) << 30;
/// tinygltf converts "extras"/"extensions" JSON recursively: bound the depth so a crafted file
/// cannot overflow the stack. Real files nest fewer than 10 levels.
constexpr int kMaxJsonDepth = 256;
/// Elements per accessor (vertices or indices): 2^26 = 67M; a buffer view also has to hold them.
constexpr std::uint64_t kMaxAccessorElements = std::uint64_t(1) << 26;
/// Accessors without a buffer view are implicitly zero (plus sparse values): nothing in the file
/// backs their count, so a few bytes of JSON could ask for gigabytes. 2^20 elements.
constexpr std::uint64_t kMaxImplicitElements = std::uint64_t(1) << 20;
/// glTF's infinite perspective projection (zfar absent) becomes far = near * this ratio, which
/// keeps depth precision usable and gives cascaded shadows a finite range to split.
constexpr float kInfiniteFarOverNear = 1000.0f;

/// Extensions we implement; a file that *requires* any other one is refused.
constexpr std::string_view kSupportedExtensions[] = {"KHR_draco_mesh_compression",
                                                     "KHR_lights_punctual", "KHR_mesh_quantization",
                                                     "KHR_materials_emissive_strength",
                                                     "KHR_texture_transform"};

bool supported_extension(std::string_view name) {
  return std::find(std::begin(kSupportedExtensions), std::end(kSupportedExtensions), name) !=
         std::end(kSupportedExtensions);
}

// ---- Naming places in the file for messages -------------------------------------------------

std::string label(const char* array, int index, const std::string& name = {}) {
  std::string s = std::string(array) + "[" + std::to_string(index) + "]";
  if (!name.empty()) s += " \"" + name + "\"";
  return s;
}

/// tinygltf messages end in newlines and may hold several lines; keep one line per message.
std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    if (end > pos) lines.push_back(text.substr(pos, end - pos));
    pos = end + 1;
  }
  return lines;
}

std::string join_lines(const std::string& text) {
  std::string out;
  for (const auto& line : split_lines(text)) out += (out.empty() ? "" : "; ") + line;
  return out.empty() ? "unknown error" : out;
}

// ---- tinygltf Value helpers (tinygltf asserts on Get() of a wrongly typed Value) -------------

/// A non-negative integer that fits an int (JSON numbers may arrive as reals).
bool as_index(const tinygltf::Value& v, int& out) {
  if (v.IsInt()) {
    out = v.GetNumberAsInt();
    return out >= 0;
  }
  if (v.IsReal()) {
    const double d = v.GetNumberAsDouble();
    if (!(d >= 0.0 && d <= double(std::numeric_limits<int>::max()) && d == std::floor(d)))
      return false;
    out = int(d);
    return true;
  }
  return false;
}

const tinygltf::Value* member(const tinygltf::Value& object, const char* key) {
  if (!object.IsObject() || !object.Has(key)) return nullptr;
  return &object.Get(key);
}

bool all_finite(const std::vector<double>& values) {
  return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

// ---- Images ---------------------------------------------------------------------------------

/// Shared with tinygltf's image callback through its user pointer.
struct ImageLoadState {
  std::map<int, std::string> failures;  ///< image index -> why it has no pixels
};

/// tinygltf image callback: decodes images given by URI (external files, data URIs) through
/// OIIO. Failures are recorded, not returned: a missing texture should not fail the import.
bool load_image_callback(tinygltf::Image* image, const int index, std::string* /*err*/,
                         std::string* /*warn*/, int /*req_width*/, int /*req_height*/,
                         const unsigned char* bytes, int size, void* user_data) {
  // Images stored in buffer views are decoded later by decode_view_image(): tinygltf 2.7 passes
  // &buffer.data[view.byteOffset] and view.byteLength here without checking them against the
  // buffer, so these bytes must not be read.
  if (image->bufferView >= 0) return true;
  auto* state = static_cast<ImageLoadState*>(user_data);
  const std::string name = image->uri.empty() ? label("images", index, image->name) : image->uri;
  auto decoded =
      load_image_from_memory(bytes, size > 0 ? std::size_t(size) : 0, name, image->mimeType);
  if (!decoded) {
    state->failures[index] = decoded.error().message;
    return true;
  }
  image->width = decoded->width;
  image->height = decoded->height;
  image->component = 4;
  image->bits = 8;
  image->pixel_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
  image->image = to_rgba8(decoded.value());
  return true;
}

// ---- Reading and parsing the file -----------------------------------------------------------

/// Refuses JSON nested deeper than kMaxJsonDepth (brackets outside strings are counted).
Status check_json_depth(const std::uint8_t* json, std::size_t size, const std::string& file) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (std::size_t i = 0; i < size; ++i) {
    const char c = char(json[i]);
    if (in_string) {
      if (!escaped && c == '"') in_string = false;
      escaped = !escaped && c == '\\';
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      if (++depth > kMaxJsonDepth) {
        return Error{file, "",
                     "JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels"};
      }
    } else if (c == '}' || c == ']') {
      --depth;
    }
  }
  return {};
}

/// Without TINYGLTF_ENABLE_DRACO, tinygltf 2.7 rejects a primitive whose index accessor has no
/// buffer view ("accessor[i] invalid bufferView"), which is how KHR_draco_mesh_compression
/// primitives look: their indices live in the Draco stream. We take the indices from the decoded
/// Draco faces anyway, so this drops "indices" from Draco primitives before tinygltf sees the
/// JSON. Returns the rewritten JSON, or nullopt when nothing changes (or the JSON does not parse:
/// tinygltf then reports that).
std::optional<std::string> strip_draco_indices(const char* json_text, std::size_t size) {
  constexpr std::string_view kDraco = "KHR_draco_mesh_compression";
  if (std::string_view(json_text, size).find(kDraco) == std::string_view::npos) return std::nullopt;
  nlohmann::json doc = nlohmann::json::parse(json_text, json_text + size, nullptr,
                                             /*allow_exceptions=*/false);
  if (doc.is_discarded() || !doc.is_object()) return std::nullopt;
  bool changed = false;
  auto meshes = doc.find("meshes");
  if (meshes == doc.end() || !meshes->is_array()) return std::nullopt;
  for (auto& mesh : *meshes) {
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
      continue;
    for (auto& prim : mesh["primitives"]) {
      if (!prim.is_object() || !prim.contains("indices")) continue;
      const auto ext = prim.find("extensions");
      if (ext != prim.end() && ext->is_object() && ext->contains(kDraco)) {
        prim.erase("indices");
        changed = true;
      }
    }
  }
  if (!changed) return std::nullopt;
  return doc.dump();
}

/// A .glb with its JSON chunk replaced (padded with spaces to 4 bytes, as the spec asks) and the
/// rest copied verbatim. Only called on files whose header length matches their size.
std::vector<std::uint8_t> replace_glb_json(const std::vector<std::uint8_t>& glb,
                                           std::uint32_t old_json_length, std::string json_text) {
  while (json_text.size() % 4 != 0) json_text += ' ';
  const std::size_t rest = 20 + std::size_t(old_json_length);
  std::vector<std::uint8_t> out(glb.begin(), glb.begin() + 12);
  const std::uint32_t total = std::uint32_t(20 + json_text.size() + (glb.size() - rest));
  const std::uint32_t json_length = std::uint32_t(json_text.size());
  std::memcpy(out.data() + 8, &total, 4);
  out.resize(20);
  std::memcpy(out.data() + 12, &json_length, 4);
  std::memcpy(out.data() + 16, "JSON", 4);
  out.insert(out.end(), json_text.begin(), json_text.end());
  out.insert(out.end(), glb.begin() + std::ptrdiff_t(rest), glb.end());
  return out;
}

std::uint32_t read_u32(const std::vector<std::uint8_t>& d, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, d.data() + at, 4);
  return v;
}

/// The binary glTF container (glTF 2.0 spec, section 4.4 "GLB File Format Specification"),
/// checked before tinygltf so that a damaged file is reported with the byte offset and what is
/// wrong there (tinygltf says only "Invalid glTF binary.").
Status check_glb_container(const std::vector<std::uint8_t>& d, const std::string& file) {
  const std::size_t n = d.size();
  const std::string size = std::to_string(n) + " bytes";
  if (n < 12)
    return Error{file, "byte " + std::to_string(n),
                 "truncated: the file ends inside the 12-byte GLB header (" + size + ")"};
  if (const std::uint32_t version = read_u32(d, 4); version != 2)
    return Error{file, "byte 4", "GLB container version " + std::to_string(version) +
                                     "; only version 2 (glTF 2.0) is supported"};
  const std::uint64_t length = read_u32(d, 8);
  if (length > n)
    return Error{file, "byte " + std::to_string(n),
                 "truncated: the GLB header (byte 8) says the file is " + std::to_string(length) +
                     " bytes, but it ends after " + size};
  if (length < n)
    return Error{file, "byte " + std::to_string(length),
                 std::to_string(n - length) + " bytes after the end the GLB header gives (" +
                     std::to_string(length) + " bytes)"};
  // Chunks: 4-byte length, 4-byte type, data. The first is JSON, an optional second BIN.
  std::size_t at = 12;
  for (int chunk = 0; at < n; ++chunk) {
    const std::string where = "byte " + std::to_string(at);
    const char* what = chunk == 0 ? "JSON chunk" : chunk == 1 ? "BIN chunk" : "chunk";
    if (n - at < 8)
      return Error{file, where, std::string("truncated: the file ends inside the ") + what +
                                    " header (" + std::to_string(n - at) + " of 8 bytes)"};
    const std::uint64_t chunk_length = read_u32(d, at);
    const std::uint32_t type = read_u32(d, at + 4);
    if (chunk == 0 && type != 0x4E4F534Au) {
      char hex[16];
      std::snprintf(hex, sizeof hex, "0x%08X", type);
      return Error{file, "byte " + std::to_string(at + 4),
                   std::string("the first chunk must be JSON (type 0x4E4F534A), found type ") + hex};
    }
    if (chunk == 0 && chunk_length == 0)
      return Error{file, where, "the JSON chunk is empty"};
    if (at + 8 + chunk_length > n)
      return Error{file, where,
                   std::string("truncated: the ") + what + " says it holds " +
                       std::to_string(chunk_length) + " bytes from byte " + std::to_string(at + 8) +
                       ", but the file ends after " + size};
    at += 8 + std::size_t(chunk_length);
  }
  if (at == 12) return Error{file, "byte 12", "truncated: the GLB has no JSON chunk"};
  return {};
}

/// Parses .gltf or .glb (told apart by the "glTF" magic, not the extension).
Result<tinygltf::Model> parse_file(const std::filesystem::path& path, ImageLoadState& images,
                                   std::vector<std::string>& warnings) {
  const std::string file = path.string();
  auto bytes = read_file_bytes(path, kMaxFileBytes);
  if (!bytes) return bytes.error();
  std::vector<std::uint8_t>& data = bytes.value();

  const bool binary = data.size() >= 4 && std::memcmp(data.data(), "glTF", 4) == 0;
  if (!binary) {
    // Text glTF is JSON: an object, after optional whitespace (and a UTF-8 byte order mark).
    std::size_t first = data.size() >= 3 && data[0] == 0xEF && data[1] == 0xBB && data[2] == 0xBF ? 3 : 0;
    while (first < data.size() && std::isspace(data[first])) ++first;
    if (first == data.size() || data[first] != '{') {
      const std::string ext = lowercase_extension(path);
      return Error{file, "byte 0",
                   ext == ".glb" ? "not a binary glTF: it does not start with the magic 'glTF'"
                                 : "neither a binary glTF (magic 'glTF') nor glTF JSON (an object "
                                   "'{ ... }')"};
    }
  }
  if (binary) {
    KASKAD_TRY(check_glb_container(data, file));
    // Header: magic, version, total length, then the JSON chunk's length and type at byte 12
    // and its content from byte 20. tinygltf validates all of it; we only look when it fits.
    std::uint32_t total_length = 0, json_length = 0;
    if (data.size() >= 20) {
      std::memcpy(&total_length, data.data() + 8, 4);
      std::memcpy(&json_length, data.data() + 12, 4);
    }
    const std::size_t json_start = std::min<std::size_t>(20, data.size());
    const std::size_t available = data.size() - json_start;
    const std::size_t json_size = std::min<std::size_t>(json_length, available);
    KASKAD_TRY(check_json_depth(data.data() + json_start, json_size, file));
    if (total_length == data.size() && json_length <= available) {
      const auto* json_text = reinterpret_cast<const char*>(data.data() + json_start);
      if (auto rewritten = strip_draco_indices(json_text, json_size))
        data = replace_glb_json(data, json_length, std::move(*rewritten));
    }
  } else {
    KASKAD_TRY(check_json_depth(data.data(), data.size(), file));
    if (auto rewritten =
            strip_draco_indices(reinterpret_cast<const char*>(data.data()), data.size()))
      data.assign(rewritten->begin(), rewritten->end());
  }

  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&load_image_callback, &images);
  tinygltf::Model model;
  std::string err, warn;
  const std::string base_dir = path.parent_path().string();
  // For JSON errors, our own parse of the same text gives the line, column and reason (in the
  // JSON chunk for a .glb) instead of nlohmann's raw message.
  auto locate_json_error = [&](std::string raw) -> Error {
    const std::size_t start = binary ? std::min<std::size_t>(20, data.size()) : 0;
    std::size_t length = data.size() - start;
    if (binary && data.size() >= 16) length = std::min<std::size_t>(length, read_u32(data, 12));
    auto located = json_reader::parse_json_text(
        std::string(data.begin() + std::ptrdiff_t(start), data.begin() + std::ptrdiff_t(start + length)),
        file);
    if (located) {
      if (auto p = raw.find("] "); raw.rfind("[json.exception", 0) == 0 && p != std::string::npos)
        raw.erase(0, p + 2);
      return Error{file, "", "invalid glTF JSON: " + raw};
    }
    Error e = located.error();
    if (binary)
      e.where = e.where.empty() ? std::string("JSON chunk") : std::string("JSON chunk, ") + e.where;
    return e;
  };
  bool ok = false;
  try {
    ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, data.data(),
                                              unsigned(data.size()), base_dir)
                : loader.LoadASCIIFromString(&model, &err, &warn,
                                             reinterpret_cast<const char*>(data.data()),
                                             unsigned(data.size()), base_dir);
  } catch (const std::bad_alloc&) {
    return Error{file, "", "out of memory while parsing"};
  } catch (const std::exception& e) {
    // tinygltf 2.7 lets some std::vector::at() exceptions escape on malformed buffers.
    const std::string what = e.what();
    if (what.find("[json.exception") != std::string::npos) return locate_json_error(what);
    return Error{file, "", "invalid glTF: " + what};
  }
  // tinygltf catches nlohmann's exceptions (a number like 1e999) itself and passes their raw text on.
  if (!ok && err.find("[json.exception") != std::string::npos) return locate_json_error(join_lines(err));
  if (!ok) return Error{file, "", "invalid glTF: " + join_lines(err)};
  for (const auto& line : split_lines(warn)) warnings.push_back(line);
  // tinygltf reports some spec violations in `err` yet succeeds; keep them as warnings.
  for (const auto& line : split_lines(err)) warnings.push_back(line);
  return model;
}

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

/// Address of `count` elements of `element_size` bytes, `stride` bytes apart, starting `offset`
/// bytes into buffer view `view_index`, after checking the whole range lies inside the view and
/// the view inside its buffer. Null when count is 0.
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
void make_flat_normals(MeshData& m) {
  MeshData flat;
  flat.name = m.name;
  const bool has_uvs = !m.uvs.empty();
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const std::uint32_t i[3] = {m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]};
    const glm::vec3 a = m.positions[i[0]], b = m.positions[i[1]], c = m.positions[i[2]];
    glm::vec3 n = glm::cross(b - a, c - a);
    const float len = glm::length(n);
    n = len > 0.0f && std::isfinite(len) ? n / len : glm::vec3(0, 1, 0);  // degenerate: any unit
    for (std::uint32_t k : i) {
      flat.indices.push_back(std::uint32_t(flat.positions.size()));
      flat.positions.push_back(m.positions[k]);
      flat.normals.push_back(n);
      if (has_uvs) flat.uvs.push_back(m.uvs[k]);
    }
  }
  m = std::move(flat);
}

/// Converts one primitive. nullopt (with a warning) for primitives that are skipped: points,
/// lines, or no triangles at all.
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
  if (!prim.targets.empty()) warnings.push_back(where + ": morph targets ignored");

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
  auto tangents = attribute("TANGENT", 4);
  if (!tangents) return tangents.error();
  const std::pair<const char*, std::size_t> counts[] = {{"NORMAL", normals->size() / 3},
                                                        {"TEXCOORD_0", uvs->size() / 2},
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
  m.indices = std::move(indices);
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

// ---- Scene conversion -----------------------------------------------------------------------

/// A converted primitive: its mesh in the AssetStore and its glTF material index.
struct ImportedPrimitive {
  MeshId mesh = kNoMesh;
  int material = -1;
  int primitive = 0;
};

/// State of one import; meshes, materials and textures are converted once, on first use.
struct Importer {
  const tinygltf::Model& model;
  std::string file;
  ecs::World& world;
  AssetStore& assets;
  ecs::Entity source;
  bool activate_first_camera = false;
  GltfImportReport report;
  ImageLoadState images;

  std::map<int, std::vector<ImportedPrimitive>> meshes;
  std::map<int, Material> materials;
  std::map<std::pair<int, bool>, TextureId> textures;  ///< (image, srgb) -> texture
  std::set<int> failed_images;                         ///< warned about once
  bool camera_activated = false;
};

const std::vector<ImportedPrimitive>* find_or_import_mesh(Importer& im, int mesh_index,
                                                          Error& error) {
  if (auto it = im.meshes.find(mesh_index); it != im.meshes.end()) return &it->second;
  const tinygltf::Mesh& mesh = im.model.meshes[std::size_t(mesh_index)];
  std::vector<ImportedPrimitive> out;
  for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
    auto data = read_primitive(im.model, im.file, mesh_index, int(p), im.report.warnings);
    if (!data) {
      error = data.error();
      return nullptr;
    }
    if (!data->has_value()) continue;
    im.report.triangles += (*data)->triangle_count();
    out.push_back({im.assets.add_mesh(std::move(**data)), mesh.primitives[p].material, int(p)});
  }
  return &(im.meshes[mesh_index] = std::move(out));
}

/// Decodes an image stored in a buffer view (after range-checking the view).
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
  if (tex_coord != 0) {
    im.report.warnings.push_back(where + ": uses TEXCOORD_" + std::to_string(tex_coord) +
                                 "; only TEXCOORD_0 is imported");
  }
  const int source = model.textures[std::size_t(texture_index)].source;
  if (source < 0) {
    im.report.warnings.push_back(where + ": " + label("textures", texture_index) +
                                 " has no source image (extension images are not supported)");
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
  auto texture = texture_for(im, index, tex_coord, srgb, where);
  if (!texture) return texture.error();
  slot.texture = texture.value();
  return slot;
}

/// glTF metallic-roughness material -> Material. -1 gives glTF's default material (3.9.6).
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

  std::string ignored;
  if (g.alphaMode == "MASK") {
    m.alpha_mask = true;
    m.alpha_cutoff = float(std::clamp(g.alphaCutoff, 0.0, 1.0));
  } else if (g.alphaMode == "BLEND") {
    ignored += " alphaMode BLEND (drawn opaque)";
  }
  if (!ignored.empty()) im.report.warnings.push_back(where + ": not imported:" + ignored);
  // glTF materials map onto the same feature model as material files.
  m.features = derive_material_features(m);

  im.materials[index] = m;
  return m;
}

/// A node's matrix as TRS (components/transform.h decompose(); glTF requires matrices to be
/// TRS-decomposable, 5.25), with warnings for what that loses: a projective part, shear.
Transform decompose_node_matrix(const glm::mat4& matrix, std::vector<std::string>& warnings,
                                const std::string& where) {
  const Transform t = decompose(matrix);
  if (matrix[0][3] != 0.0f || matrix[1][3] != 0.0f || matrix[2][3] != 0.0f ||
      matrix[3][3] != 1.0f) {
    warnings.push_back(where + ": matrix is not affine; its projective part is ignored");
  }
  if (!(std::min({std::abs(t.scale.x), std::abs(t.scale.y), std::abs(t.scale.z)}) > 1e-12f))
    return t;  // a zero scale: no rotation recovered, no shear to speak of
  glm::vec3 axis[3] = {glm::vec3(matrix[0]), glm::vec3(matrix[1]), glm::vec3(matrix[2])};
  for (glm::vec3& a : axis) a = glm::normalize(a);
  const float shear =
      std::max({std::abs(glm::dot(axis[0], axis[1])), std::abs(glm::dot(axis[1], axis[2])),
                std::abs(glm::dot(axis[0], axis[2]))});
  if (shear > 1e-3f) warnings.push_back(where + ": matrix has shear; it is approximated");
  return t;
}

/// The node's local transform from TRS or matrix (parent is set by the caller).
Result<Transform> node_transform(const Importer& im, int index,
                                 std::vector<std::string>& warnings) {
  const tinygltf::Node& node = im.model.nodes[std::size_t(index)];
  const std::string where = label("nodes", index, node.name);
  const auto& t = node.translation;
  const auto& r = node.rotation;
  const auto& s = node.scale;
  const auto& m = node.matrix;
  if (!(t.empty() || t.size() == 3) || !(r.empty() || r.size() == 4) ||
      !(s.empty() || s.size() == 3) || !(m.empty() || m.size() == 16)) {
    return Error{im.file, where, "translation, rotation, scale or matrix has the wrong length"};
  }
  if (!all_finite(t) || !all_finite(r) || !all_finite(s) || !all_finite(m)) {
    return Error{im.file, where, "non-finite transform value"};
  }
  if (m.size() == 16) {
    glm::mat4 matrix;
    for (int c = 0; c < 4; ++c)
      for (int row = 0; row < 4; ++row) matrix[c][row] = float(m[std::size_t(c * 4 + row)]);
    return decompose_node_matrix(matrix, warnings, where);
  }
  Transform out;
  if (t.size() == 3) out.translation = {float(t[0]), float(t[1]), float(t[2])};
  if (s.size() == 3) out.scale = {float(s[0]), float(s[1]), float(s[2])};
  if (r.size() == 4) {
    const glm::quat q{float(r[3]), float(r[0]), float(r[1]), float(r[2])};  // glTF: x, y, z, w
    const float len = glm::length(q);
    if (!(len > 1e-6f)) return Error{im.file, where, "rotation quaternion has zero length"};
    out.rotation = q / len;
  }
  return out;
}

/// KHR_lights_punctual light -> Light (+ ShadowSettings for directional lights).
Status add_light(Importer& im, ecs::Entity entity, int node_index, const tinygltf::Value& ext) {
  const std::string node_where = label("nodes", node_index, im.model.nodes[node_index].name);
  int index = -1;
  const tinygltf::Value* light_value = member(ext, "light");
  if (light_value == nullptr || !as_index(*light_value, index) ||
      std::size_t(index) >= im.model.lights.size()) {
    return Error{im.file, node_where + " KHR_lights_punctual",
                 "light index missing or out of range (" + std::to_string(im.model.lights.size()) +
                     " lights)"};
  }
  const tinygltf::Light& g = im.model.lights[std::size_t(index)];
  const std::string where = "KHR_lights_punctual " + label("lights", index, g.name);

  Light light;
  if (g.type == "directional") {
    light.type = LightType::directional;
  } else if (g.type == "spot") {
    light.type = LightType::spot;
  } else if (g.type == "point") {
    light.type = LightType::point;
  } else {
    return Error{im.file, where, "unknown light type \"" + g.type + "\""};
  }
  if (!(g.color.empty() || g.color.size() == 3) || !all_finite(g.color) ||
      std::any_of(g.color.begin(), g.color.end(), [](double c) { return c < 0.0; })) {
    return Error{im.file, where, "color must be 3 finite numbers >= 0"};
  }
  if (g.color.size() == 3) light.color = {float(g.color[0]), float(g.color[1]), float(g.color[2])};
  if (!(std::isfinite(g.intensity) && g.intensity >= 0.0)) {
    return Error{im.file, where, "intensity must be a finite number >= 0"};
  }
  light.intensity = float(g.intensity);
  if (!(std::isfinite(g.range) && g.range >= 0.0)) {
    return Error{im.file, where, "range must be a finite number >= 0 (0: infinite)"};
  }
  light.range = light.type == LightType::directional ? 0.0f : float(g.range);
  if (light.type == LightType::spot) {
    const double inner = g.spot.innerConeAngle, outer = g.spot.outerConeAngle;
    if (!(inner >= 0.0 && inner <= outer && outer > 0.0 && outer <= std::numbers::pi / 2)) {
      return Error{im.file, where,
                   "spot cone angles must satisfy 0 <= inner <= outer <= pi/2, "
                   "were " +
                       std::to_string(inner) + " and " + std::to_string(outer)};
    }
    light.inner_cone_deg = float(inner * 180.0 / std::numbers::pi);
    light.outer_cone_deg = float(outer * 180.0 / std::numbers::pi);
  }
  if (light.type == LightType::directional) {
    light.cast_shadows = true;
    im.world.emplace<ShadowSettings>(entity, ShadowSettings{});
  }
  im.world.emplace<Light>(entity, light);
  ++im.report.lights;
  return {};
}

/// glTF camera -> Camera. An infinite perspective far plane becomes near * kInfiniteFarOverNear.
Status add_camera(Importer& im, ecs::Entity entity, int camera_index) {
  if (std::size_t(camera_index) >= im.model.cameras.size()) {
    return Error{im.file, "",
                 "camera " + std::to_string(camera_index) + " out of range (" +
                     std::to_string(im.model.cameras.size()) + " cameras)"};
  }
  const tinygltf::Camera& g = im.model.cameras[std::size_t(camera_index)];
  const std::string where = label("cameras", camera_index, g.name);
  Camera camera;
  if (g.type == "perspective") {
    const auto& p = g.perspective;
    if (!(std::isfinite(p.yfov) && p.yfov > 0.0 && p.yfov < std::numbers::pi)) {
      return Error{im.file, where,
                   "yfov must be in (0, pi) radians, was " + std::to_string(p.yfov)};
    }
    if (!(std::isfinite(p.znear) && p.znear > 0.0)) {
      return Error{im.file, where, "znear must be > 0, was " + std::to_string(p.znear)};
    }
    if (!(std::isfinite(p.zfar) && (p.zfar == 0.0 || p.zfar > p.znear))) {
      return Error{im.file, where, "zfar must be > znear, was " + std::to_string(p.zfar)};
    }
    if (!(std::isfinite(p.aspectRatio) && p.aspectRatio >= 0.0)) {
      return Error{im.file, where, "aspectRatio must be > 0"};
    }
    camera.projection = Projection::perspective;
    camera.fov_y_deg = float(p.yfov * 180.0 / std::numbers::pi);
    camera.near = float(p.znear);
    camera.far = p.zfar == 0.0 ? camera.near * kInfiniteFarOverNear : float(p.zfar);
    camera.aspect = float(p.aspectRatio);
  } else if (g.type == "orthographic") {
    const auto& o = g.orthographic;
    if (!(std::isfinite(o.xmag) && std::isfinite(o.ymag) && o.xmag != 0.0 && o.ymag != 0.0)) {
      return Error{im.file, where, "xmag and ymag must be finite and non-zero"};
    }
    if (!(std::isfinite(o.znear) && std::isfinite(o.zfar) && o.znear >= 0.0 && o.zfar > o.znear)) {
      return Error{im.file, where, "orthographic planes must satisfy 0 <= znear < zfar"};
    }
    camera.projection = Projection::orthographic;
    camera.ortho_height = float(2.0 * std::abs(o.ymag));
    camera.aspect = float(std::abs(o.xmag / o.ymag));
    // Camera requires near > 0; glTF allows 0 for orthographic views.
    camera.near = o.znear > 0.0 ? float(o.znear) : float(o.zfar * 1e-6);
    camera.far = float(o.zfar);
  } else {
    return Error{im.file, where, "unknown camera type \"" + g.type + "\""};
  }
  if (im.activate_first_camera && !im.camera_activated) {
    camera.active = true;
    im.camera_activated = true;
  }
  im.world.emplace<Camera>(entity, camera);
  ++im.report.cameras;
  return {};
}

/// Creates the entity of node `index` under `parent`, with its primitives, light and camera.
Result<ecs::Entity> import_node(Importer& im, int index, ecs::Entity parent) {
  const tinygltf::Node& node = im.model.nodes[std::size_t(index)];
  const std::string where = label("nodes", index, node.name);
  auto transform = node_transform(im, index, im.report.warnings);
  if (!transform) return transform.error();
  const std::string name = node.name.empty() ? "node_" + std::to_string(index) : node.name;

  const ecs::Entity entity = im.world.create();
  transform->parent = parent;
  im.world.emplace<Name>(entity, Name{name});
  im.world.emplace<Transform>(entity, transform.value());
  im.world.emplace<Imported>(entity, Imported{im.source});
  ++im.report.nodes;

  if (node.mesh >= 0) {
    if (std::size_t(node.mesh) >= im.model.meshes.size()) {
      return Error{im.file, where,
                   "mesh " + std::to_string(node.mesh) + " out of range (" +
                       std::to_string(im.model.meshes.size()) + " meshes)"};
    }
    Error error;
    const auto* primitives = find_or_import_mesh(im, node.mesh, error);
    if (primitives == nullptr) return error;
    for (const ImportedPrimitive& p : *primitives) {
      auto material = read_material(im, p.material);
      if (!material) {
        Error e = material.error();
        if (e.where.empty())
          e.where = label("meshes", node.mesh) + " primitives[" + std::to_string(p.primitive) + "]";
        return e;
      }
      const ecs::Entity child = im.world.create();
      Transform local;
      local.parent = entity;
      im.world.emplace<Name>(child, Name{name + "/prim" + std::to_string(p.primitive)});
      im.world.emplace<Transform>(child, local);
      MeshRenderer renderer;
      renderer.mesh = p.mesh;
      im.world.emplace<MeshRenderer>(child, renderer);
      im.world.emplace<Material>(child, material.value());
      im.world.emplace<Imported>(child, Imported{im.source});
      ++im.report.mesh_entities;
    }
  }
  if (node.skin >= 0) {
    im.report.warnings.push_back(where + ": skin ignored; the mesh is imported in its bind pose");
  }
  if (node.camera >= 0) KASKAD_TRY(add_camera(im, entity, node.camera));
  if (auto ext = node.extensions.find("KHR_lights_punctual"); ext != node.extensions.end())
    KASKAD_TRY(add_light(im, entity, index, ext->second));
  return entity;
}

/// Checks child indices and single parents; returns the nodes to import as roots.
Result<std::vector<int>> root_nodes(const tinygltf::Model& model, const std::string& file) {
  const std::size_t count = model.nodes.size();
  std::vector<int> parent(count, -1);
  for (std::size_t n = 0; n < count; ++n) {
    for (int child : model.nodes[n].children) {
      const std::string where = label("nodes", int(n), model.nodes[n].name);
      if (child < 0 || std::size_t(child) >= count) {
        return Error{file, where,
                     "child " + std::to_string(child) + " out of range (" + std::to_string(count) +
                         " nodes)"};
      }
      if (parent[std::size_t(child)] != -1 || std::size_t(child) == n) {
        return Error{file, where,
                     "node " + std::to_string(child) +
                         " has more than one parent (the hierarchy must be a tree)"};
      }
      parent[std::size_t(child)] = int(n);
    }
  }
  std::vector<int> roots;
  if (model.defaultScene >= 0) {
    if (std::size_t(model.defaultScene) >= model.scenes.size()) {
      return Error{file, "scene",
                   "default scene " + std::to_string(model.defaultScene) + " out of range (" +
                       std::to_string(model.scenes.size()) + " scenes)"};
    }
    const std::string where = label("scenes", model.defaultScene);
    std::set<int> seen;
    for (int n : model.scenes[std::size_t(model.defaultScene)].nodes) {
      if (n < 0 || std::size_t(n) >= count) {
        return Error{file, where, "node " + std::to_string(n) + " out of range"};
      }
      if (parent[std::size_t(n)] != -1 || !seen.insert(n).second) {
        return Error{file, where,
                     "node " + std::to_string(n) + " is not a root node or is listed twice"};
      }
      roots.push_back(n);
    }
  } else {
    for (std::size_t n = 0; n < count; ++n)
      if (parent[n] == -1) roots.push_back(int(n));
  }
  // Nodes in a parent cycle have a parent each, so they are never reached from a root: walking
  // down from the roots visits every node at most once.
  return roots;
}

Status check_extensions(const tinygltf::Model& model, const std::string& file,
                        std::vector<std::string>& warnings) {
  for (const std::string& ext : model.extensionsRequired) {
    if (!supported_extension(ext)) {
      return Error{file, "extensionsRequired", "unsupported required extension " + ext};
    }
  }
  std::string ignored;
  for (const std::string& ext : model.extensionsUsed)
    if (!supported_extension(ext)) ignored += " " + ext;
  if (!ignored.empty()) warnings.push_back("extensions ignored:" + ignored);
  if (!model.animations.empty()) {
    warnings.push_back(std::to_string(model.animations.size()) + " animation(s) ignored");
  }
  return {};
}

Result<GltfImportReport> import(const std::filesystem::path& path, ecs::World& world,
                                AssetStore& assets, ecs::Entity parent, ecs::Entity source,
                                bool activate_first_camera) {
  // 1-2. Read and parse.
  GltfImportReport report;
  ImageLoadState images;
  auto model = parse_file(path, images, report.warnings);
  if (!model) return model.error();

  Importer im{model.value(),
              path.string(),
              world,
              assets,
              source,
              activate_first_camera,
              std::move(report),
              std::move(images),
              {},
              {},
              {},
              {},
              false};
  // 3. Extensions.
  KASKAD_TRY(check_extensions(im.model, im.file, im.report.warnings));
  // 4. Hierarchy.
  auto roots = root_nodes(im.model, im.file);
  if (!roots) return roots.error();

  // 5. Parents before children (depth-first, explicit stack: hierarchies can be deep).
  std::vector<std::pair<int, ecs::Entity>> stack;
  for (auto it = roots->rbegin(); it != roots->rend(); ++it) stack.emplace_back(*it, parent);
  while (!stack.empty()) {
    const auto [node, node_parent] = stack.back();
    stack.pop_back();
    auto entity = import_node(im, node, node_parent);
    if (!entity) return entity.error();
    const auto& children = im.model.nodes[std::size_t(node)].children;
    for (auto it = children.rbegin(); it != children.rend(); ++it)
      stack.emplace_back(*it, entity.value());
  }
  return std::move(im.report);
}

}  // namespace

Result<GltfImportReport> import_gltf(const std::filesystem::path& path, ecs::World& world,
                                     AssetStore& assets, ecs::Entity parent, ecs::Entity source,
                                     bool activate_first_camera) {
  try {
    return import(path, world, assets, parent, source, activate_first_camera);
  } catch (const std::bad_alloc&) {
    return Error{path.string(), "", "out of memory while importing"};
  } catch (const std::exception& e) {
    return Error{path.string(), "", std::string("import failed: ") + e.what()};
  }
}

}  // namespace kaskad
