// GL resources of the reflection probes (S3): per probe two cube maps (RGBA16F, full mip chain;
// a front one shown and a back one captured into: ProbeState::front), a 2D sphere map when the
// probe shows one, and for the pbr reflection model a prefiltered cube and an SH row per buffer
// (made by IblMaps, which ProbeMaps owns); one capture framebuffer with one depth renderbuffer,
// remade when the face size changes; and the fullscreen pass that makes sphere maps from cubes
// (S3 eq. (2), content/shaders/probe_sphere.frag). GpuCache owns one ProbeMaps; the captures
// themselves (which faces, drawn through the forward path) are ProbeCapturePass's
// (probe_capture_pass.h), which draws into the faces begin_face() binds.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "components/probe_state.h"
#include "runtime/assets/env_map.h"
#include "runtime/result/result.h"
#include "runtime/gpu/gl_handles.h"
#include "runtime/render/ibl_maps.h"

namespace kaskad::render {

class ProbeMaps {
 public:
  /// Builds the sphere-map program from `shader_dir`. Needs a current GL 4.5 context.
  static Result<std::unique_ptr<ProbeMaps>> create(const std::filesystem::path& shader_dir);

  /// Cube buffer `buffer` (0 or 1) of probe `handle`, created (black) on first use and recreated
  /// when `resolution` changes (both buffers: a resize drops the old maps). References from this
  /// class stay valid until that probe's maps are recreated, retained away or cleared.
  gpu::TextureRef cube(ProbeHandle handle, int buffer, int resolution);
  /// The cube buffer if it exists, else none (for lookups: a probe never made has none).
  gpu::TextureRef existing_cube(ProbeHandle handle, int buffer) const;

  /// Binds face `face` (GL order) of the cube as the colour target of the capture framebuffer,
  /// with a depth buffer of the cube's size, sets the viewport and clears to `clear` (linear).
  void begin_face(ProbeHandle handle, int buffer, int face, const glm::vec3& clear);
  /// After the last face of a capture: rebuilds the cube's mip chain.
  void finish_cube(ProbeHandle handle, int buffer);
  /// Uploads a CPU cube map (faces as GL expects them, env_map.h) into a buffer, with mips.
  void upload(ProbeHandle handle, int buffer, const CubeMap& cube);

  /// Renders probe `handle`'s sphere map from cube `buffer` for a camera with world -> view
  /// rotation `view_rotation` (S3 eq. (2) in that view space); returns the 2D texture.
  gpu::TextureRef update_sphere(ProbeHandle handle, int buffer, const glm::mat3& view_rotation);
  /// The sphere map if one was rendered, else none.
  gpu::TextureRef existing_sphere(ProbeHandle handle) const;

  /// Read-back (tests, debug dumps): a cube buffer as a CubeMap (level 0), the sphere map with
  /// row 0 at the top (SphereMap's convention). Empty when the probe has no such map.
  CubeMap read_cube(ProbeHandle handle, int buffer) const;
  SphereMap read_sphere(ProbeHandle handle) const;

  /// The pbr reflection model (IblMaps): prefilters `faces` more faces of complete cube
  /// `buffer` into that buffer's specular cube, and after the sixth its SH row, and from then on
  /// lookups see it (existing_specular(), sh_row()); nothing when that cube's prefiltered
  /// version is already shown. A cube that changes again before it is done starts over. True
  /// when the sixth face was done by this call.
  bool prefilter(ProbeHandle handle, int buffer, int faces);
  /// Whether the probe has a prefiltered cube to show.
  bool has_specular(ProbeHandle handle) const;
  int prefilter_faces = 0;  ///< faces prefiltered since creation (stats and tests)
  /// The probe's prefiltered cube (none before prefilter()), its SH row and its last level.
  gpu::TextureRef existing_specular(ProbeHandle handle) const;
  int sh_row(ProbeHandle handle) const;
  int specular_last_level(ProbeHandle handle) const;
  /// Image-based lighting's tables, environment and passes.
  IblMaps& ibl() { return *ibl_; }
  const IblMaps& ibl() const { return *ibl_; }

  /// Forgets every probe (another scene: handles name entities of one world).
  void clear();
  /// Drops the maps of every probe not in `live` (sorted): reflectors that were destroyed.
  void retain(const std::vector<ProbeHandle>& live);

  int faces_rendered = 0;  ///< faces begun since creation (tests compare with the system)

 private:
  struct Probe {
    int resolution = 0;
    gpu::Texture cubes[2];
    gpu::Texture sphere;
    /// The pbr model's prefiltered cube and SH row per buffer (-1: none yet), `shown` the one
    /// lookups see (-1: none). `changes` counts completed captures and uploads per buffer;
    /// `shown_source` is the (buffer, changes) the shown cube was made from, `pending` the one
    /// being prefiltered and `pending_faces` its faces done.
    gpu::Texture specular[2];
    int sh_rows[2] = {-1, -1};
    int shown = -1;
    std::uint64_t changes[2] = {0, 0};
    std::pair<int, std::uint64_t> shown_source{-1, 0}, pending{-1, 0};
    int pending_faces = 0;
  };
  void drop(Probe& p);
  ProbeMaps() = default;
  gpu::Program sphere_program_;
  gpu::VertexArray empty_vao_;
  gpu::Framebuffer fbo_;
  gpu::Renderbuffer depth_;
  int depth_size_ = 0;
  std::map<ProbeHandle, Probe> probes_;
  std::unique_ptr<IblMaps> ibl_;
};

}  // namespace kaskad::render
