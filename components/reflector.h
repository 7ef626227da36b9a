// An environment reflection probe on a reflecting object (S3): which map it uses, when it is
// (re)captured, and how strongly it reflects. Authored data only; the EnvironmentProbeSystem adds
// and owns ProbeState (components/probe_state.h). validate_reflector() names the first bad value.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <tuple>

#include <glm/glm.hpp>

#include "components/env_layout.h"
#include "components/limits.h"
#include "runtime/fields/fields.h"

namespace kaskad {

/// render.probe_bounces (runtime/assets/scene.h): capture rounds on a frame where probes make
/// their first capture. S3 has one round (a mirror seen in another's first map is black); 2, the
/// default, lets every first map show the others' first maps (one inter-reflection), which is
/// what a viewer notices; each further round costs the first captures once more. Engine choice.
inline constexpr int kMinProbeBounces = 1, kMaxProbeBounces = 4, kDefaultProbeBounces = 2;

/// The reflection map type (S3): a cube map, or a sphere map generated from the cube.
enum class ReflectionMap { cube, sphere };
constexpr std::array<std::string_view, 2> enum_names(ReflectionMap) { return {"cube", "sphere"}; }
static_assert(enum_names(ReflectionMap{}).size() == std::size_t(ReflectionMap::sphere) + 1);

/// When the map is (re)made. S3 names the first three (a)-(c); on_change is beyond S3.
enum class ProbeUpdate {
  static_file,  ///< S3 (a): prepared images, loaded once
  first_frame,  ///< S3 (b): rendered once, on the first frame
  every_n,      ///< S3 (c): re-rendered on frames 0, N, 2N, ...; the last one is reused between
  on_change,    ///< rendered on the first frame, then again when something in range changed
};
constexpr std::array<std::string_view, 4> enum_names(ProbeUpdate) {
  return {"static_file", "first_frame", "every_n", "on_change"};
}
static_assert(enum_names(ProbeUpdate{}).size() == std::size_t(ProbeUpdate::on_change) + 1);

struct Reflector {
  ReflectionMap map = ReflectionMap::cube;
  ProbeUpdate update = ProbeUpdate::first_frame;
  /// every_n: frames between captures, >= 1 (1: every frame).
  int every_n = 10;
  /// Faces rendered per frame while a capture is in progress, in [1, 6]. 6: S3 (all at once);
  /// fewer spreads a capture over frames (time slicing) into a back buffer that becomes visible
  /// only when all six faces are done. The first capture renders all six at once.
  int faces_per_frame = 6;
  /// Texels per cube face side, power of two in [8, 2048]. 128: engine choice (S3 does not say).
  int resolution = 128;
  /// Capture centre in world space. Unset: the object's world-bounds centre (S3 needs the pivot
  /// at the geometric centre; an off-centre pivot is warned about once).
  bool has_center = false;
  glm::vec3 center{0.0f};
  /// Near / far planes of the six capture cameras, metres, 0 < near < far. far is also the
  /// probe's range for on_change.
  float near = 0.05f;
  float far = 100.0f;
  /// MeshRenderer layers (bit i = layer i) not drawn into the probe; the reflector itself is
  /// never drawn into its own probe.
  std::uint32_t exclude_layers = 0;
  /// Box projection (parallax correction; beyond S3, as in Unity, Godot and Bevy), cube maps
  /// only: lookups treat the environment as lying on this world-space box (which should hold the
  /// capture centre), so R is replaced by the direction from the centre to where the ray from the
  /// shaded point along R leaves the box.
  bool box_projection = false;
  glm::vec3 box_min{0.0f}, box_max{0.0f};
  /// S3's p_r, the map's amount, as a fraction in [0, 1] (the paper's percent / 100).
  float amount = 1.0f;
  /// static_file: the image, or the six faces' name pattern with one `*` (load_cube_map in
  /// runtime/assets/env_map.h), relative to the scene. Resampled to `resolution` texels a face.
  std::string file;
  EnvLayout layout = EnvLayout::auto_detect;
  /// static_file: the file is 3ds Max-authored (Z up): S3 eq. (7) and its face table apply.
  bool z_up_3dsmax = false;
};

/// The fields of Reflector with one value each, once (runtime/fields/fields.h); center, box and
/// exclude_layers have forms of their own (runtime/assets/reflector_io.cpp).
constexpr auto field_table(fields::Of<Reflector>) {
  using R = Reflector;
  using namespace fields;
  return std::tuple{
      choice("map", &R::map, "A cube map, or a sphere map made from the cube"),
      choice("update", &R::update, "When the map is (re)made"),
      integer("every_n", &R::every_n, 1, 1 << 20, "update every_n: frames between captures"),
      integer("faces_per_frame", &R::faces_per_frame, 1, 6,
              "Cube faces rendered per frame while a capture is in progress"),
      integer("resolution", &R::resolution, 8, 2048, "Texels per cube face side", kPowerOfTwo),
      number("near", &R::near, 1e-6, kMaxCoordinate, "Near plane of the capture cameras, metres"),
      number("far", &R::far, 1e-6, kMaxCoordinate,
             "Far plane of the capture cameras (and on_change's range), metres"),
      number("amount", &R::amount, 0, 1, "The map's amount (S3's p_r)"),
      text("file", &R::file, "update static_file: the image or the faces' name pattern with one *"),
      choice("layout", &R::layout, "update static_file: how the file holds its cube map"),
      flag("z_up_3dsmax", &R::z_up_3dsmax, "update static_file: the file is 3ds Max-authored (Z up)"),
  };
}

/// Empty when valid, else a message starting with the bad field's name, e.g.
/// "faces_per_frame must be in [1, 6], was 7": the table's ranges, then the rules across fields.
inline std::string validate_reflector(const Reflector& r) {
  if (std::string bad = fields::validate_fields(r); !bad.empty()) return bad;
  if (!(r.far > r.near))
    return "far must be greater than near (" + fields::format_number(r.near) + "), was " +
           fields::format_number(r.far);
  if (r.box_projection && !(r.box_min.x < r.box_max.x && r.box_min.y < r.box_max.y &&
                            r.box_min.z < r.box_max.z))
    return "box min must be below max on every axis";
  if (r.box_projection && r.has_center &&
      (glm::any(glm::lessThan(r.center, r.box_min)) || glm::any(glm::greaterThan(r.center, r.box_max))))
    return "box must contain the capture centre";
  if (r.update == ProbeUpdate::static_file && r.file.empty())
    return "file must name an image when update is static_file";
  return {};
}

}  // namespace kaskad
