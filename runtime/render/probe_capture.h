// GL resources of the reflection probes (S3): per probe two cube maps (RGBA16F, full mip chain;
// a front one shown and a back one captured into), a 2D sphere map when the probe shows one,
// one capture framebuffer with a depth renderbuffer per face size, and the fullscreen pass that
// makes sphere maps from cubes (S3 eq. (2), content/shaders/probe_sphere.frag). The Renderer owns
// one ProbeMaps and records captures through its own forward path (renderer.cpp); this file holds
// everything else about probes on the GPU.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "components/probe_state.h"
#include "runtime/assets/env_map.h"
#include "runtime/core/result.h"
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

  /// The pbr reflection model (IblMaps): prefilters cube `buffer` into the probe's specular
  /// cube and SH row unless that cube was prefiltered since it last changed. True when it ran.
  bool prefilter(ProbeHandle handle, int buffer);
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
    /// The pbr model's prefiltered cube and SH row (-1: none yet); `changes` counts completed
    /// captures and uploads per buffer, `prefiltered` what the specular cube was made from.
    gpu::Texture specular;
    int sh_row = -1;
    std::uint64_t changes[2] = {0, 0};
    std::pair<int, std::uint64_t> prefiltered{-1, 0};
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
