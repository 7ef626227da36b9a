// glTF import, step 1: reading and parsing the file. Refuses what tinygltf cannot parse safely
// (size, JSON nesting, a broken GLB container), strips what it must not see (Draco primitives'
// index accessors), parses with tinygltf and decodes images given by URI through OIIO.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <string_view>

#include <nlohmann/json.hpp>

#include "runtime/assets/gltf_internal.h"
#include "runtime/assets/image_io.h"
#include "runtime/core/file_io.h"
#include "runtime/core/json_reader.h"

namespace kaskad::gltf_detail {
namespace {

/// Extensions we implement; a file that *requires* any other one is refused.
constexpr std::string_view kSupportedExtensions[] = {"KHR_draco_mesh_compression",
                                                     "KHR_lights_punctual", "KHR_mesh_quantization",
                                                     "KHR_materials_emissive_strength",
                                                     "KHR_materials_transmission",
                                                     "KHR_texture_transform", "EXT_texture_webp"};

// ---- Naming places in the file for messages -------------------------------------------------

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

// ---- Images ---------------------------------------------------------------------------------

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

std::string lowercase(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// The media type of a "data:" URI (lower case, "" when it names none), or nullopt for a URI that
/// is not one. `base64` tells whether the data is base64, the only encoding tinygltf decodes.
std::optional<std::string> data_uri_media_type(const std::string& uri, bool& base64) {
  if (uri.size() < 5 || lowercase(uri.substr(0, 5)) != "data:") return std::nullopt;
  const std::size_t comma = uri.find(',');
  std::string head = lowercase(uri.substr(5, comma == std::string::npos ? comma : comma - 5));
  base64 = head.size() >= 7 && head.compare(head.size() - 7, 7, ";base64") == 0;
  return head.substr(0, head.find(';'));
}

/// A data: URI must carry the media type its place takes. tinygltf decodes any base64 data: URI
/// as a buffer (text/plain too) and takes one with another image type for a file name.
Status check_data_uris(const tinygltf::Model& model, const std::string& file) {
  bool base64 = false;
  for (std::size_t i = 0; i < model.buffers.size(); ++i) {
    const auto type = data_uri_media_type(model.buffers[i].uri, base64);
    if (!type) continue;
    const std::string where = "/buffers/" + std::to_string(i) + "/uri";
    if (*type != "application/octet-stream" && *type != "application/gltf-buffer")
      return Error{file, where,
                   "a data: URI of media type '" + *type +
                       "'; a buffer's is application/octet-stream or application/gltf-buffer"};
    if (!base64) return Error{file, where, "a data: URI without ';base64': only base64 is read"};
  }
  for (std::size_t i = 0; i < model.images.size(); ++i) {
    const auto type = data_uri_media_type(model.images[i].uri, base64);
    if (!type) continue;
    const std::string where = "/images/" + std::to_string(i) + "/uri";
    if (type->rfind("image/", 0) != 0)
      return Error{file, where,
                   "a data: URI of media type '" + *type + "'; an image's is an image type "
                   "(image/png, image/jpeg)"};
    if (!base64) return Error{file, where, "a data: URI without ';base64': only base64 is read"};
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

}  // namespace

bool supported_extension(std::string_view name) {
  return std::find(std::begin(kSupportedExtensions), std::end(kSupportedExtensions), name) !=
         std::end(kSupportedExtensions);
}

std::string label(const char* array, int index, const std::string& name) {
  std::string s = std::string(array) + "[" + std::to_string(index) + "]";
  if (!name.empty()) s += " \"" + name + "\"";
  return s;
}

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

/// tinygltf's file callbacks for external buffers and images. Its own FileExists() opens the
/// file, which blocks forever on a FIFO; this one only asks the file system. Reads go through
/// read_file_bytes(), so a URI naming a FIFO or a device is refused with the same words and size
/// limit as any file.
bool file_exists(const std::string& path, void* /*user_data*/) {
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}

bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                     void* /*user_data*/) {
  auto bytes = read_file_bytes(path, kMaxFileBytes);
  if (!bytes) {
    if (err) *err += bytes.error().to_string() + "\n";
    return false;
  }
  out->assign(bytes->begin(), bytes->end());
  return true;
}

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
    KASKAD_TRY(json_reader::check_depth(
        std::string_view(reinterpret_cast<const char*>(data.data() + json_start), json_size), file));
    if (total_length == data.size() && json_length <= available) {
      const auto* json_text = reinterpret_cast<const char*>(data.data() + json_start);
      if (auto rewritten = strip_draco_indices(json_text, json_size))
        data = replace_glb_json(data, json_length, std::move(*rewritten));
    }
  } else {
    KASKAD_TRY(json_reader::check_depth(
        std::string_view(reinterpret_cast<const char*>(data.data()), data.size()), file));
    if (auto rewritten =
            strip_draco_indices(reinterpret_cast<const char*>(data.data()), data.size()))
      data.assign(rewritten->begin(), rewritten->end());
  }

  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&load_image_callback, &images);
  loader.SetFsCallbacks({&file_exists, &tinygltf::ExpandFilePath, &read_whole_file,
                         &tinygltf::WriteWholeFile, nullptr});
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
  KASKAD_TRY(check_data_uris(model, file));
  return model;
}

}  // namespace kaskad::gltf_detail
