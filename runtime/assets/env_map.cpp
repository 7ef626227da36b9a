// Environment maps on the CPU: S3's cube-map and sphere-map formulas, and the static layouts.
// Conventions are documented once, in env_map.h.
#include "runtime/assets/env_map.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string_view>
#include <system_error>

#include "runtime/assets/image_io.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/log.h"
#include "runtime/fields/fields.h"

namespace kaskad {
namespace {

constexpr std::array<const char*, 6> kFaceSuffix = {"px", "nx", "py", "ny", "pz", "nz"};
/// S3's 3ds Max face names in CubeFace order of their 3ds Max axes (+X RIGHT, -X LEFT, +Y BACK,
/// -Y FRONT, +Z UP, -Z DOWN; S3, Fig. 8).
constexpr std::array<const char*, 6> kMaxFaceName = {"right", "left", "back",
                                                     "front", "up",   "down"};

std::string size_text(int w, int h) {
  std::string s = std::to_string(w);
  s += "x";
  s += std::to_string(h);
  return s;
}

/// Bilinear lookup in a row-major grid at continuous texel coordinate (fx, fy) (texel centres at
/// integer + 0.5), clamped at the edges; `wrap_x` wraps columns instead (equirect longitude).
glm::vec4 bilinear(const std::vector<glm::vec4>& texels, int w, int h, float fx, float fy,
                   bool wrap_x = false) {
  fx -= 0.5f;
  fy -= 0.5f;
  const float x0f = std::floor(fx);
  const float y0f = std::floor(fy);
  const float ax = fx - x0f;
  const float ay = fy - y0f;
  auto column = [&](int x) {
    if (wrap_x) return ((x % w) + w) % w;
    return std::clamp(x, 0, w - 1);
  };
  const int x0 = column(int(x0f));
  const int x1 = column(int(x0f) + 1);
  const int y0 = std::clamp(int(y0f), 0, h - 1);
  const int y1 = std::clamp(int(y0f) + 1, 0, h - 1);
  auto at = [&](int x, int y) -> const glm::vec4& {
    return texels[std::size_t(y) * std::size_t(w) + std::size_t(x)];
  };
  const glm::vec4 top = glm::mix(at(x0, y0), at(x1, y0), ax);
  const glm::vec4 bottom = glm::mix(at(x0, y1), at(x1, y1), ax);
  return glm::mix(top, bottom, ay);
}

/// RGBA texels of an image: channels by name when it has R/G/B(/A) names (EXR may reorder
/// them), else by position; grey expands to RGB, a missing alpha is 1.
std::vector<glm::vec4> rgba_texels(const Image& image) {
  std::array<int, 4> ch = {-1, -1, -1, -1};
  constexpr std::array<const char*, 4> kNames = {"R", "G", "B", "A"};
  bool named = false;
  for (std::size_t i = 0; i < 4; ++i) {
    const auto it = std::find(image.channel_names.begin(), image.channel_names.end(), kNames[i]);
    if (it != image.channel_names.end() && it - image.channel_names.begin() < image.channels) {
      ch[i] = int(it - image.channel_names.begin());
      named = true;
    }
  }
  if (!named || ch[0] < 0) {
    // Positional: 1 = grey, 2 = grey + alpha, 3 = RGB, 4+ = RGBA.
    const int c = image.channels;
    ch = {0, c >= 3 ? 1 : 0, c >= 3 ? 2 : 0, c == 2 ? 1 : (c >= 4 ? 3 : -1)};
  } else {
    if (ch[1] < 0) ch[1] = ch[0];
    if (ch[2] < 0) ch[2] = ch[0];
  }
  std::vector<glm::vec4> out(std::size_t(image.width) * std::size_t(image.height));
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      glm::vec4& t = out[std::size_t(y) * std::size_t(image.width) + std::size_t(x)];
      t.r = image.at(x, y, ch[0]);
      t.g = image.at(x, y, ch[1]);
      t.b = image.at(x, y, ch[2]);
      t.a = ch[3] >= 0 ? image.at(x, y, ch[3]) : 1.0f;
    }
  }
  return out;
}

/// The largest finite half float: environments and probes live in GL_RGBA16F textures, and a
/// larger value (a sun in a real HDRI may reach 10^5) would turn to infinity there.
constexpr float kMaxHalf = 65504.0f;

/// An environment's texels are summed into its SH coefficients and prefiltered radiance, and
/// sampled by every reflection: one NaN or infinity spreads over the whole lighting. So each
/// image an environment is made from is checked whole, and the first such value (in file order:
/// rows from the top, then columns, then channels) is an error naming its pixel and channel.
/// Finite values beyond the half-float range are clamped to it, with a warning that counts them.
Status check_finite(Image& image, const std::string& file) {
  std::size_t clamped = 0;
  float largest = 0.0f;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      for (int c = 0; c < image.channels; ++c) {
        float& v = image.at(x, y, c);
        if (std::isfinite(v)) {
          if (std::abs(v) > kMaxHalf) {
            largest = std::max(largest, std::abs(v));
            v = std::copysign(kMaxHalf, v);
            ++clamped;
          }
          continue;
        }
        const std::string channel = c < int(image.channel_names.size()) &&
                                            !image.channel_names[std::size_t(c)].empty()
                                        ? image.channel_names[std::size_t(c)]
                                        : std::to_string(c);
        const char* what = std::isnan(v) ? "NaN" : v > 0 ? "+Inf" : "-Inf";
        std::string message = "pixel (";
        message += std::to_string(x);
        message += ", ";
        message += std::to_string(y);
        message += "), channel ";
        message += channel;
        message += ", is ";
        message += what;
        message += ": an environment map's pixels must be finite numbers (x from the left, y "
                   "from the top row)";
        return Error{file, "", message};
      }
    }
  }
  if (clamped > 0)
    log::warn("%s: %zu pixel value(s) beyond the half-float range (up to %g) are clamped to %g: "
              "environment maps are kept as half floats",
              file.c_str(), clamped, double(largest), double(kMaxHalf));
  return {};
}

Image image_of(const std::vector<glm::vec4>& texels, int w, int h) {
  Image img;
  img.width = w;
  img.height = h;
  img.channels = 4;
  img.channel_names = {"R", "G", "B", "A"};
  img.pixels.resize(texels.size() * 4);
  for (std::size_t i = 0; i < texels.size(); ++i) {
    for (int c = 0; c < 4; ++c) img.pixels[i * 4 + std::size_t(c)] = texels[i][c];
  }
  return img;
}

/// The square cell (col, row) of `n`-texel faces out of an image's texels; `rotate_180` turns it
/// (the vertical cross's -Z).
std::vector<glm::vec4> cell(const std::vector<glm::vec4>& texels, int width, int n, int col,
                            int row, bool rotate_180) {
  std::vector<glm::vec4> face(std::size_t(n) * std::size_t(n));
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const int sx = rotate_180 ? n - 1 - x : x;
      const int sy = rotate_180 ? n - 1 - y : y;
      face[std::size_t(y) * std::size_t(n) + std::size_t(x)] =
          texels[std::size_t(row * n + sy) * std::size_t(width) + std::size_t(col * n + sx)];
    }
  }
  return face;
}

/// The same environment at another face size (bilinear).
CubeMap resized(const CubeMap& cube, int size) {
  if (size == cube.size) return cube;
  return make_cube_map(size, [&](const glm::vec3& d) { return sample_cube(cube, d); });
}

/// Face sizes derived from an image (equirect width / 4, sphere size / 2) stop here: 2048^2 x 6
/// RGBA floats are 400 MB. An explicit EnvLoadOptions::face_size may go up to kMaxFaceSize.
constexpr int kMaxDerivedFaceSize = 2048;
constexpr int kMaxFaceSize = 8192;

/// Which texel of a `size` face a direction computed from another texel centre lands on (exact
/// permutations of texel centres: rounding absorbs float error).
int texel_index(float st, int size) {
  return std::clamp(int(std::floor(st * float(size))), 0, size - 1);
}

// --- layouts ---------------------------------------------------------------------------------

/// A faces pattern: the file of face f is prefix + name + suffix.
struct FacePattern {
  std::string prefix, suffix;
};

bool ends_with(std::string_view s, std::string_view tail) {
  return s.size() >= tail.size() && s.substr(s.size() - tail.size()) == tail;
}

/// Face names accepted for face f (its axis name; with 3ds Max also S3's word).
std::vector<std::string> face_names(int f, bool max) {
  std::vector<std::string> names = {kFaceSuffix[std::size_t(f)]};
  if (max) names.emplace_back(kMaxFaceName[std::size_t(f)]);
  return names;
}

/// The pattern of a faces path: one `*`, a file whose stem ends in a face name, or a directory
/// holding a file whose stem is a face name (e.g. px.jpg: the pattern is dir/`*`.jpg).
std::optional<FacePattern> face_pattern(const std::filesystem::path& path, bool max) {
  const std::string s = path.string();
  if (const auto star = s.find('*'); star != std::string::npos) {
    return FacePattern{s.substr(0, star), s.substr(star + 1)};
  }
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    // The extension of px, else of the first face file by name (directory order varies).
    std::vector<std::filesystem::path> faces;
    for (const auto& entry : std::filesystem::directory_iterator(path, ec)) {
      const std::string stem = entry.path().stem().string();
      for (int f = 0; f < 6; ++f)
        for (const std::string& name : face_names(f, max))
          if (stem == name) faces.push_back(entry.path());
    }
    if (faces.empty()) return std::nullopt;
    std::sort(faces.begin(), faces.end(), [](const auto& a, const auto& b) {
      const bool apx = a.stem() == kFaceSuffix[0], bpx = b.stem() == kFaceSuffix[0];
      return apx != bpx ? apx : a < b;
    });
    return FacePattern{(path / "").string(), faces.front().extension().string()};
  }
  const std::string stem = path.stem().string();
  const std::string ext = path.extension().string();
  const std::string dir = path.has_parent_path() ? path.parent_path().string() + "/" : "";
  for (int f = 0; f < 6; ++f) {
    for (const std::string& name : face_names(f, max)) {
      if (ends_with(stem, name))
        return FacePattern{dir + stem.substr(0, stem.size() - name.size()), ext};
    }
  }
  return std::nullopt;
}

/// Whether all six files of `pattern` exist (each by any of its face names).
bool all_faces_present(const FacePattern& pattern, bool max) {
  for (int f = 0; f < 6; ++f) {
    bool found = false;
    std::error_code ec;
    for (const std::string& name : face_names(f, max))
      found = found || std::filesystem::is_regular_file(pattern.prefix + name + pattern.suffix, ec);
    if (!found) return false;
  }
  return true;
}

Result<CubeMap> load_faces(const std::filesystem::path& path, bool max) {
  const std::string name = path.string();
  const auto pattern = face_pattern(path, max);
  if (!pattern) {
    return Error{name, "",
                 "faces layout: the path must contain one '*', name one face file whose name "
                 "ends in px, nx, py, ny, pz or nz, or be a folder holding such files"};
  }
  if (pattern->suffix.find('*') != std::string::npos)
    return Error{name, "", "faces layout: the pattern may contain only one '*'"};

  CubeMap cube;
  std::string first_file;
  for (int f = 0; f < 6; ++f) {
    std::string file;
    std::error_code ec;
    for (const std::string& face_name : face_names(f, max)) {
      std::string candidate = pattern->prefix;
      candidate += face_name;
      candidate += pattern->suffix;
      if (std::filesystem::exists(candidate, ec)) {
        file = candidate;
        break;
      }
    }
    if (file.empty()) {
      std::string expected = pattern->prefix;
      expected += kFaceSuffix[std::size_t(f)];
      expected += pattern->suffix;
      std::string message = "missing face file ";
      message += expected;
      if (max) {
        message += " (or ";
        message += pattern->prefix;
        message += kMaxFaceName[std::size_t(f)];
        message += pattern->suffix;
        message += ")";
      }
      return Error{name, "", message};
    }
    auto image = load_image(file);
    if (!image) return image.error();
    KASKAD_TRY(check_finite(*image, file));
    if (image->width != image->height) {
      return Error{
          file, "",
          "a cube face must be square, this one is " + size_text(image->width, image->height)};
    }
    if (f == 0) {
      cube.size = image->width;
      first_file = file;
    } else if (image->width != cube.size) {
      std::string message = "face size ";
      message += size_text(image->width, image->height);
      message += " differs from ";
      message += size_text(cube.size, cube.size);
      message += " of ";
      message += first_file;
      return Error{file, "", message};
    }
    cube.faces[std::size_t(f)] = rgba_texels(*image);
  }
  return cube;
}

Result<CubeMap> cube_from_cross(const Image& image, const std::string& name, bool vertical) {
  const int w = image.width, h = image.height;
  const int cols = vertical ? 3 : 4, rows = vertical ? 4 : 3;
  if (w % cols != 0 || h % rows != 0 || w / cols != h / rows) {
    std::string message =
        vertical ? "a vertical cross must be 3:4" : "a horizontal cross must be 4:3";
    message += " with whole square faces (width divisible by ";
    message += std::to_string(cols);
    message += "), this image is ";
    message += size_text(w, h);
    return Error{name, "", message};
  }
  const int n = w / cols;
  const std::vector<glm::vec4> texels = rgba_texels(image);
  // Cells (column, row) of each face in CubeFace order; env_map.h draws both crosses.
  struct Cell {
    int col, row;
    bool rotate_180;
  };
  const std::array<Cell, 6> cells = vertical ? std::array<Cell, 6>{{{2, 1, false},
                                                                    {0, 1, false},
                                                                    {1, 0, false},
                                                                    {1, 2, false},
                                                                    {1, 1, false},
                                                                    {1, 3, true}}}
                                             : std::array<Cell, 6>{{{2, 1, false},
                                                                    {0, 1, false},
                                                                    {1, 0, false},
                                                                    {1, 2, false},
                                                                    {1, 1, false},
                                                                    {3, 1, false}}};
  CubeMap cube;
  cube.size = n;
  for (int f = 0; f < 6; ++f) {
    const Cell& c = cells[std::size_t(f)];
    cube.faces[std::size_t(f)] = cell(texels, w, n, c.col, c.row, c.rotate_180);
  }
  return cube;
}

Result<CubeMap> cube_from_equirect(const Image& image, const std::string& name, int face_size) {
  const int w = image.width, h = image.height;
  if (w != 2 * h) {
    return Error{name, "",
                 "an equirectangular map must be 2:1 (width = 2 x height), this image is " +
                     size_text(w, h)};
  }
  const std::vector<glm::vec4> texels = rgba_texels(image);
  const int size = face_size > 0 ? face_size : std::clamp(w / 4, 1, kMaxDerivedFaceSize);
  constexpr float kPi = std::numbers::pi_v<float>;
  return make_cube_map(size, [&](const glm::vec3& d) {
    // Inverse of env_map.h's direction = (cos(lat) sin(lon), sin(lat), -cos(lat) cos(lon)).
    const float lon = std::atan2(d.x, -d.z);
    const float lat = std::asin(std::clamp(d.y, -1.0f, 1.0f));
    const float u = lon / (2.0f * kPi) + 0.5f;
    const float v = 0.5f - lat / kPi;
    return bilinear(texels, w, h, u * float(w), v * float(h), /*wrap_x=*/true);
  });
}

Result<SphereMap> sphere_from_image(const Image& image, const std::string& name) {
  if (image.width != image.height) {
    return Error{
        name, "",
        "a sphere map must be square, this image is " + size_text(image.width, image.height)};
  }
  SphereMap map;
  map.size = image.width;
  map.texels = rgba_texels(image);
  return map;
}

}  // namespace

const char* cube_face_suffix(CubeFace face) {
  return kFaceSuffix[std::size_t(face)];
}

const char* env_layout_name(EnvLayout layout) {
  return fields::name_of(layout).data();  // the names are literals: NUL-terminated
}



glm::vec4 sample_cube(const CubeMap& cube, const glm::vec3& direction) {
  if (cube.size <= 0) return glm::vec4(0.0f);
  const CubeCoord c = cube_coord(direction);
  return bilinear(cube.faces[std::size_t(c.face)], cube.size, cube.size, c.s * float(cube.size),
                  c.t * float(cube.size));
}


SphereMap sphere_map_from_cube(const CubeMap& cube, int size, const glm::mat3& view_to_world) {
  KASKAD_CHECK(size >= 1, "size must be >= 1, was " + std::to_string(size));
  SphereMap map;
  map.size = size;
  map.texels.resize(std::size_t(size) * std::size_t(size));
  for (int j = 0; j < size; ++j) {
    for (int i = 0; i < size; ++i) {
      map.texels[std::size_t(j) * std::size_t(size) + std::size_t(i)] =
          sample_cube(cube, view_to_world * sphere_map_direction(i, j, size));
    }
  }
  return map;
}


glm::vec4 sample_sphere(const SphereMap& map, const glm::vec3& reflected_view) {
  if (map.size <= 0) return glm::vec4(0.0f);
  const glm::vec2 uv = sphere_map_uv(reflected_view);
  // t' grows upwards, rows downwards.
  return bilinear(map.texels, map.size, map.size, uv.x * float(map.size),
                  (1.0f - uv.y) * float(map.size));
}


CubeMap cube_from_3dsmax(const CubeMap& max_faces) {
  // Derivation. 3ds Max is Z-up with FRONT at -Y; the engine is Y-up. A Max scene exported to
  // the engine maps Max (x, y, z) to engine (x, z, -y), so an engine direction e is the Max
  // direction m = M_rot e (S3's M_rot: (x, y, z) -> (x, -z, y)).
  // S3 puts the Max images into GL faces by its face table (Fig. 8): RIGHT -> +X, LEFT -> -X,
  // BACK (+Y) -> +Z, FRONT (-Y) -> -Z, UP (+Z) -> -Y, DOWN (-Z) -> +Y, i.e. the Max face of axis
  // a goes to the GL face of axis M_rot a, and it looks up the Max direction m at M_rot m
  // (eq. 7). So the engine direction e reads that cube at M_rot (M_rot e) = (x, -y, -z): a
  // rotation by 180 degrees about X, which maps texel centres onto texel centres (exact).
  constexpr std::array<CubeFace, 6> kGlFaceOfMaxAxis = {CubeFace::pos_x, CubeFace::neg_x,
                                                        CubeFace::pos_z, CubeFace::neg_z,
                                                        CubeFace::neg_y, CubeFace::pos_y};
  CubeMap s3;  // S3's GL cube: the Max images placed by the face table
  s3.size = max_faces.size;
  for (int a = 0; a < 6; ++a) {
    s3.faces[std::size_t(kGlFaceOfMaxAxis[std::size_t(a)])] = max_faces.faces[std::size_t(a)];
  }
  if (s3.size <= 0) return s3;
  CubeMap out;
  out.size = s3.size;
  for (int f = 0; f < 6; ++f) {
    out.faces[std::size_t(f)].resize(std::size_t(out.size) * std::size_t(out.size));
    for (int y = 0; y < out.size; ++y) {
      for (int x = 0; x < out.size; ++x) {
        const glm::vec3 e = cube_direction(CubeFace(f), (float(x) + 0.5f) / float(out.size),
                                           (float(y) + 0.5f) / float(out.size));
        const CubeCoord c = cube_coord(m_rot(m_rot(e)));
        out.at(CubeFace(f), x, y) =
            s3.at(c.face, texel_index(c.s, s3.size), texel_index(c.t, s3.size));
      }
    }
  }
  return out;
}

Result<CubeMap> load_cube_map(const std::filesystem::path& path, const EnvLoadOptions& options,
                              EnvLayout* detected) {
  const std::string name = path.string();
  if (options.face_size < 0 || options.face_size > kMaxFaceSize) {
    return Error{name, "",
                 "face_size must be in [0, " + std::to_string(kMaxFaceSize) +
                     "] (0 = from the image), was " + std::to_string(options.face_size)};
  }
  EnvLayout layout = options.layout;
  // A pattern or a folder is faces; so is a file named as a face (px.png, sky_px.png, sky-px.png),
  // and one whose name only ends in a face name (sunny.hdr ends in "ny") when its five siblings
  // are beside it: otherwise it is read as the single image it is.
  if (layout == EnvLayout::auto_detect) {
    std::error_code ec;
    if (const auto pattern = face_pattern(path, options.z_up_3dsmax)) {
      const char before = pattern->prefix.empty() ? '/' : pattern->prefix.back();
      if (path.string().find('*') != std::string::npos || std::filesystem::is_directory(path, ec) ||
          before == '/' || before == '_' || before == '-' || before == '.' ||
          all_faces_present(*pattern, options.z_up_3dsmax))
        layout = EnvLayout::faces;
    }
  }

  if (detected) *detected = layout;

  Result<CubeMap> cube = Error{};
  if (layout == EnvLayout::faces) {
    cube = load_faces(path, options.z_up_3dsmax);
  } else {
    auto image = load_image(path);
    if (!image) return image.error();
    KASKAD_TRY(check_finite(*image, name));
    const int w = image->width, h = image->height;
    if (layout == EnvLayout::auto_detect) {
      if (3 * w == 4 * h)
        layout = EnvLayout::horizontal_cross;
      else if (4 * w == 3 * h)
        layout = EnvLayout::vertical_cross;
      else if (w == 2 * h)
        layout = EnvLayout::equirect;
      else if (w == h)
        layout = EnvLayout::sphere;
      else {
        return Error{name, "",
                     "cannot tell the environment layout of a " + size_text(w, h) +
                         " image: expected 4:3 or 3:4 (cross), 2:1 (equirect), 1:1 "
                         "(sphere map), or six face files (a '*' pattern)"};
      }
      if (detected) *detected = layout;
    }
    if (options.z_up_3dsmax && (layout == EnvLayout::equirect || layout == EnvLayout::sphere)) {
      return Error{name, "",
                   std::string("the 3ds Max (Z-up) conversion applies to cube faces and "
                               "crosses, not to the ") +
                       env_layout_name(layout) + " layout"};
    }
    switch (layout) {
      case EnvLayout::horizontal_cross:
      case EnvLayout::vertical_cross:
        cube = cube_from_cross(*image, name, layout == EnvLayout::vertical_cross);
        break;
      case EnvLayout::equirect:
        return cube_from_equirect(*image, name, options.face_size);
      case EnvLayout::sphere: {
        auto map = sphere_from_image(*image, name);
        if (!map) return map.error();
        const int size = options.face_size > 0 ? options.face_size
                                               : std::clamp(map->size / 2, 1, kMaxDerivedFaceSize);
        return make_cube_map(size, [&](const glm::vec3& d) { return sample_sphere(*map, d); });
      }
      default:
        return Error{name, "", "internal: unhandled layout"};
    }
  }
  if (!cube) return cube;
  CubeMap result = options.z_up_3dsmax ? cube_from_3dsmax(*cube) : std::move(*cube);
  if (options.face_size > 0) result = resized(result, options.face_size);
  return result;
}

Result<SphereMap> load_sphere_map(const std::filesystem::path& path) {
  auto image = load_image(path);
  if (!image) return image.error();
  KASKAD_TRY(check_finite(*image, path.string()));
  return sphere_from_image(*image, path.string());
}

std::array<std::string, 6> cube_face_files(const std::filesystem::path& pattern_or_dir) {
  const std::string s = pattern_or_dir.string();
  const auto star = s.find('*');
  std::array<std::string, 6> files;
  for (std::size_t f = 0; f < 6; ++f) {
    if (star != std::string::npos) {
      // Appended piece by piece: GCC 12 warns (-Wrestrict, falsely) on a + b + c here.
      files[f] = s.substr(0, star);
      files[f] += kFaceSuffix[f];
      files[f] += s.substr(star + 1);
    } else {
      files[f] = (pattern_or_dir / (std::string(kFaceSuffix[f]) + ".exr")).string();
    }
  }
  return files;
}

Status check_cube_faces_output(const std::filesystem::path& pattern_or_dir) {
  const std::string s = pattern_or_dir.string();
  if (s.find('*') == std::string::npos) {
    // A folder the user named: made when missing (one level; its parent must exist).
    KASKAD_TRY(check_output_folder_to_make(pattern_or_dir));
    std::error_code ec;
    if (!std::filesystem::exists(pattern_or_dir, ec)) {
      std::filesystem::create_directory(pattern_or_dir, ec);
      if (ec) return Error{s, "", "cannot make this folder: " + ec.message()};
    }
  }
  for (const std::string& file : cube_face_files(pattern_or_dir)) KASKAD_TRY(check_image_output(file));
  return {};
}

Status save_cube_faces(const CubeMap& cube, const std::filesystem::path& pattern_or_dir) {
  KASKAD_CHECK(cube.size >= 1, "cube must be non-empty, size was " + std::to_string(cube.size));
  KASKAD_TRY(check_cube_faces_output(pattern_or_dir));  // all six before the first is written
  const auto files = cube_face_files(pattern_or_dir);
  for (std::size_t f = 0; f < 6; ++f)
    KASKAD_TRY(save_image(files[f], image_of(cube.faces[f], cube.size, cube.size)));
  return {};
}

Status save_sphere_map(const SphereMap& map, const std::filesystem::path& path) {
  KASKAD_CHECK(map.size >= 1, "sphere map must be non-empty, size was " + std::to_string(map.size));
  return save_image(path, image_of(map.texels, map.size, map.size));
}

}  // namespace kaskad
