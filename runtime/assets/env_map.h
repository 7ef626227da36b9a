// Environment maps on the CPU (S3 in shared/reference/SEEDS.md): cube maps in OpenGL's face
// convention, sphere maps per S3 eq. (2), (4), (5), and loaders for the usual static layouts
// (six face images, horizontal / vertical crosses, equirectangular panoramas, sphere-map images),
// including 3ds Max (Z-up) authored cube maps via S3's face table and M_rot.
//
// Conventions used throughout, shared with the GPU side (systems/environment_probe_*,
// content/shaders/cube_face.glsl); the render tests ProbeTest.ColouredCubeInAMirrorSphereAndPlane
// (GPU reflections of a cube loaded here against sample_cube()), ThreeDsMaxCubeIsConvertedOnLoad
// and SphereMapFromTheCubeAndRuntimeSwitch (against sphere_map_from_cube()) fail when they part:
//   - Directions are in the engine's world space: right-handed, +Y up, a camera looks down -Z.
//     A CubeMap maps a world direction d to the environment seen along d; no extra rotation is
//     applied between world space and cube-map space (the shader samples with R_world directly).
//   - A cube face's texel (x, y) lies at GL face coordinate s = (x + 0.5) / size,
//     t = (y + 0.5) / size; the face's row y is the y-th row glTexImage2D uploads, so faces go to
//     GL as they are. Image files are read top row first, so row 0 of a face image file is t ~ 0.
//   - Face coordinates follow the OpenGL 4.5 spec, section 8.13, table 8.19 (major axis ma,
//     s = (sc / |ma| + 1) / 2, t = (tc / |ma| + 1) / 2):
//       face   ma   sc   tc            face   ma   sc   tc
//       +X     +x   -z   -y            -X     -x   +z   -y
//       +Y     +y   +x   +z            -Y     -y   +x   -z
//       +Z     +z   +x   -y            -Z     -z   -x   -y
//     So for the four side faces, row 0 (the top of the image file) is the +Y side.
//   - Sphere maps are images with row 0 at the top (+Y of view space) and column 0 at the left
//     (-X of view space). See SphereMap.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "components/env_layout.h"
#include "runtime/result/result.h"
#include "runtime/math/sphere_map_math.h"

namespace kaskad {


/// Short face names used in file names: "px", "nx", "py", "ny", "pz", "nz" (in CubeFace order).
const char* cube_face_suffix(CubeFace face);

/// A cube map in memory, e.g. loaded from files or read back from a probe.
struct CubeMap {
  int size = 0;  ///< face width = height, texels
  /// Linear RGBA per face, row-major, size*size; texel (x, y) is GL's face coordinate
  /// s = (x + 0.5)/size, t = (y + 0.5)/size, i.e. row y is the row glTexImage2D uploads y-th,
  /// so faces upload to GL as is (OpenGL 4.5 spec section 8.13, table 8.19).
  std::array<std::vector<glm::vec4>, 6> faces;

  glm::vec4& at(CubeFace face, int x, int y) {
    return faces[std::size_t(face)][std::size_t(y) * std::size_t(size) + std::size_t(x)];
  }
  const glm::vec4& at(CubeFace face, int x, int y) const {
    return faces[std::size_t(face)][std::size_t(y) * std::size_t(size) + std::size_t(x)];
  }
};

/// A cube map of `size` texels a side whose every texel holds fill(direction of its centre).
/// Precondition: size >= 1.
template <class F>
CubeMap make_cube_map(int size, F&& fill);



/// Bilinear lookup inside the face the direction selects (clamped at that face's edges: no
/// filtering across faces, so seams are off by at most half a texel). Empty cube: vec4(0).
glm::vec4 sample_cube(const CubeMap& cube, const glm::vec3& direction);

/// A sphere map (S3 section 2): square, `size` x `size` texels, row 0 at the TOP (image
/// convention, as files store it). Texel (i, j) (column i, row j from the top) has its centre at
/// S3's (s, t) = (2 (i + 0.5) / size - 1, 1 - 2 (j + 0.5) / size), s to view-space +X, t to +Y
/// (S3 counts j from the bottom and uses the texel corner; we use centres and image rows).
/// Inside the unit circle the texel holds the environment along eq. (2)'s R. The centre is
/// R = +Z of view space (the direction back towards the eye); the rim is R = -Z (the viewing
/// direction, behind the mirror ball), S3's "every point of the rim maps to (0, 0, -1)".
/// Texels outside the circle hold the rim value (R = -Z) so bilinear lookups near the rim stay
/// sensible. To upload to GL so that texture(map, sphere_map_uv(R)) works, upload rows bottom
/// up (row size-1 first), or sample at (u, 1 - v).
struct SphereMap {
  int size = 0;
  std::vector<glm::vec4> texels;  ///< size * size, row-major, row 0 at the top

  const glm::vec4& at(int i, int j) const {
    return texels[std::size_t(j) * std::size_t(size) + std::size_t(i)];
  }
};


/// Sphere map from a cube map per S3 eq. (2), for a viewer whose view-space directions turn into
/// world (cube) directions by `view_to_world` (the rotation part of (MV)^-1, S3 eq. 6; the
/// transpose of the view matrix's rotation). Identity: a viewer looking down world -Z with +Y up,
/// so the centre shows the cube's +Z direction and the rim its -Z direction. Each texel takes
/// sample_cube() along view_to_world * R at its centre. Precondition: size >= 1.
SphereMap sphere_map_from_cube(const CubeMap& cube, int size,
                               const glm::mat3& view_to_world = glm::mat3(1.0f));


/// Bilinear lookup of a sphere map at sphere_map_uv(reflected_view), clamped at the map's edges.
/// Empty map: vec4(0).
glm::vec4 sample_sphere(const SphereMap& map, const glm::vec3& reflected_view);


/// Name of a layout as used in messages and settings: "auto", "faces", "horizontal_cross",
/// "vertical_cross", "equirect", "sphere".
const char* env_layout_name(EnvLayout layout);

struct EnvLoadOptions {
  EnvLayout layout = EnvLayout::auto_detect;
  /// The faces were authored in 3ds Max (Z up, front = -Y): convert with S3's face table and
  /// M_rot into the engine's Y-up convention (cube_from_3dsmax). Faces and crosses only (an error
  /// for equirect and sphere maps): face files are named, and cross cells placed, by 3ds Max's
  /// axes (the cell drawn +Y below holds 3ds Max's +Y = BACK image, and so on).
  bool z_up_3dsmax = false;
  /// Face size of the result in texels, at most 8192; 0 = from the image: the face images'
  /// size, the cross width / 4 (horizontal) or / 3 (vertical), the equirect width / 4 (90
  /// degrees of the 360 the width covers) and the sphere map's size / 2, those two at most 2048.
  /// Another value resamples (bilinear).
  int face_size = 0;
};

/// Loads a cube map. Layouts (docs/guide/envmaps.md, "Layouts"):
///   - faces: six images `<prefix>px<suffix>` ... `<prefix>nz<suffix>`; `path` is either a
///     pattern with one `*` (e.g. "sky_*.png"), any one of the six files (e.g. "sky_px.png":
///     the name's stem must end in one of the six face names), or a folder holding px.<ext> ...
///     nz.<ext>. With z_up_3dsmax the names are
///     3ds Max's axes (px = RIGHT, nx = LEFT, py = BACK, ny = FRONT, pz = UP, nz = DOWN), and
///     S3's face names right/left/back/front/up/down are accepted too.
///   - horizontal_cross (4:3):   . +Y  .  .        vertical_cross (3:4):   . +Y  .
///                              -X +Z +X -Z                                -X +Z +X
///                               . -Y  .  .                                 . -Y  .
///                                                                          . -Z  .
///     Every cell is the GL face image as is, except the vertical cross's -Z: turned 180°.
///   - equirect (2:1): longitude along x, column centre u = 0.5 is -Z, u = 0.75 is +X (as seen
///     from inside, not mirrored), u = 0 / 1 is +Z; row 0 is +Y (up), the last row -Y.
///     direction = (cos(lat) sin(lon), sin(lat), -cos(lat) cos(lon)), lon = 2 pi (u - 0.5),
///     lat = pi (0.5 - v).
///   - sphere (1:1): a sphere-map image (see SphereMap) resampled into a cube with view space =
///     cube space (the -Z side comes from the rim, so it is poor there).
///   - auto_detect: faces when the path contains `*`, its stem ends in a face name, or it is a
///     folder of faces;
///     otherwise by the image's aspect ratio (4:3, 3:4, 2:1, 1:1).
/// Errors name the file and the problem: unreadable images, missing face files, non-square or
/// mismatched faces, a wrong aspect for the layout, face_size out of range, a NaN or infinite
/// pixel (the first one's x, y and channel; every image is checked whole, before any layout).
/// `detected`, when given, receives the layout used (auto_detect resolved), also on errors
/// found after detection.
Result<CubeMap> load_cube_map(const std::filesystem::path& path, const EnvLoadOptions& options = {},
                              EnvLayout* detected = nullptr);

/// Loads a sphere-map image (square; row 0 at the top, see SphereMap). A NaN or infinite pixel
/// is an error, as for load_cube_map().
Result<SphereMap> load_sphere_map(const std::filesystem::path& path);

/// Debug dump of the six faces as images (format from the extension; EXR keeps floats).
/// `pattern_or_dir`: a path with one `*`, replaced by px nx py ny pz nz (e.g. "out/probe_*.png"),
/// or a folder (made when missing, one level) that receives px.exr ... nz.exr. All six files
/// are checked before the first is written; each is written atomically.
Status save_cube_faces(const CubeMap& cube, const std::filesystem::path& pattern_or_dir);

/// The checks of save_cube_faces without writing: the folder (made when missing), then every
/// face file's format and path.
/// The six files save_cube_faces() writes for `pattern_or_dir` (px nx py ny pz nz): the `*`
/// replaced by each face name, or DIR/px.exr ... for a folder.
std::array<std::string, 6> cube_face_files(const std::filesystem::path& pattern_or_dir);

Status check_cube_faces_output(const std::filesystem::path& pattern_or_dir);

/// Debug dump of a sphere map as an image (format from the extension).
Status save_sphere_map(const SphereMap& map, const std::filesystem::path& path);

// --- 3ds Max (Z-up) conversion, S3 eq. (7) and its face table -----------------------------------


/// Converts a cube whose faces hold 3ds Max-authored images, named by 3ds Max axes (face px =
/// RIGHT (+X), nx = LEFT, py = BACK (+Y), ny = FRONT (-Y), pz = UP (+Z), nz = DOWN (-Z)), into
/// the engine's convention: sample_cube(result, d) is the authored environment along the engine
/// direction d. Exact (a texel permutation, no filtering). See env_map.cpp for the derivation.
CubeMap cube_from_3dsmax(const CubeMap& max_faces);

// --- implementation of the template ------------------------------------------------------------

template <class F>
CubeMap make_cube_map(int size, F&& fill) {
  KASKAD_CHECK(size >= 1, "size must be >= 1, was " + std::to_string(size));
  CubeMap cube;
  cube.size = size;
  for (int f = 0; f < 6; ++f) {
    auto& face = cube.faces[std::size_t(f)];
    face.resize(std::size_t(size) * std::size_t(size));
    for (int y = 0; y < size; ++y) {
      for (int x = 0; x < size; ++x) {
        const glm::vec3 d = cube_direction(CubeFace(f), (float(x) + 0.5f) / float(size),
                                           (float(y) + 0.5f) / float(size));
        face[std::size_t(y) * std::size_t(size) + std::size_t(x)] = fill(d);
      }
    }
  }
  return cube;
}

}  // namespace kaskad
