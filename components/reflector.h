// An environment reflection probe on a reflecting object (S3): which map it uses, when it is
// (re)captured, and how strongly it reflects. Authored data only; the EnvironmentProbeSystem adds
// and owns ProbeState (components/probe_state.h). validate_reflector() names the first bad value.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include <glm/glm.hpp>

namespace kaskad {

/// render.probe_bounces (runtime/assets/scene.h): capture rounds on a frame where probes make
/// their first capture. S3 has one round (a mirror seen in another's first map is black); 2, the
/// default, lets every first map show the others' first maps (one inter-reflection), which is
/// what a viewer notices; each further round costs the first captures once more. Engine choice.
inline constexpr int kMinProbeBounces = 1, kMaxProbeBounces = 4, kDefaultProbeBounces = 2;

/// The reflection map type (S3): a cube map, or a sphere map generated from the cube.
enum class ReflectionMap { cube, sphere };

/// When the map is (re)made. S3 names the first three (a)-(c); on_change is beyond S3.
enum class ProbeUpdate {
  static_file,  ///< S3 (a): prepared images, loaded once
  first_frame,  ///< S3 (b): rendered once, on the first frame
  every_n,      ///< S3 (c): re-rendered on frames 0, N, 2N, ...; the last one is reused between
  on_change,    ///< rendered on the first frame, then again when something in range changed
};

/// How a static file holds its cube map (see README "Reflection probes" for the file names).
/// Mirrors EnvLayout in runtime/assets/env_map.h (change together).
enum class EnvLayoutName { auto_detect, faces, horizontal_cross, vertical_cross, equirect, sphere };

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
  EnvLayoutName layout = EnvLayoutName::auto_detect;
  /// static_file: the file is 3ds Max-authored (Z up): S3 eq. (7) and its face table apply.
  bool z_up_3dsmax = false;
};

namespace reflector_detail {
inline std::string str(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
  return buf;
}
}  // namespace reflector_detail

/// Empty when valid, else a message starting with the bad field's name, e.g.
/// "faces_per_frame must be in [1, 6], was 7".
inline std::string validate_reflector(const Reflector& r) {
  using reflector_detail::str;
  if (r.every_n < 1) return "every_n must be >= 1, was " + std::to_string(r.every_n);
  if (r.faces_per_frame < 1 || r.faces_per_frame > 6)
    return "faces_per_frame must be in [1, 6], was " + std::to_string(r.faces_per_frame);
  if (r.resolution < 8 || r.resolution > 2048 || (r.resolution & (r.resolution - 1)) != 0)
    return "resolution must be a power of two in [8, 2048], was " + std::to_string(r.resolution);
  if (!(r.near > 0.0f && std::isfinite(r.near))) return "near must be > 0, was " + str(r.near);
  if (!(r.far > r.near && std::isfinite(r.far)))
    return "far must be finite and greater than near, was " + str(r.far);
  if (!(r.amount >= 0.0f && r.amount <= 1.0f)) return "amount must be in [0, 1], was " + str(r.amount);
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
