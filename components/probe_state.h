// The EnvironmentProbeSystem's own state for each Reflector (STYLE.md 5): added and written by
// the system only. The GPU maps live in the renderer, named by `handle`; components hold no GL.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

namespace kaskad {

inline constexpr std::uint32_t kNoProbe = 0xffffffffu;

/// The renderer's name for one probe's maps: its Reflector entity's index and generation, so a
/// reflector created in a reused entity slot gets fresh maps, never its predecessor's.
struct ProbeHandle {
  std::uint64_t value = ~std::uint64_t(0);  ///< generation << 32 | index; all ones: none

  static constexpr ProbeHandle of(std::uint32_t index, std::uint32_t generation) {
    return {(std::uint64_t(generation) << 32) | index};
  }
  constexpr bool valid() const { return value != ~std::uint64_t(0); }
  constexpr auto operator<=>(const ProbeHandle&) const = default;
};
inline constexpr ProbeHandle kNoProbeHandle{};
/// All six cube faces, bit f = GL face f (+X, -X, +Y, -Y, +Z, -Z).
inline constexpr std::uint8_t kAllFaces = 0x3f;

struct ProbeState {
  ProbeHandle handle;               ///< the renderer's name for this probe's maps
  glm::vec3 center{0.0f};           ///< capture centre used this frame, world space
  /// Two cube maps per probe: `front` is shown, captures render into the other one (the back
  /// buffer) and it becomes the front only when all six faces are done.
  int front = 0;
  bool has_map = false;             ///< the front buffer holds a complete map
  bool capturing = false;           ///< a capture into the back buffer is in progress
  std::uint8_t faces_done = 0;      ///< faces of the back buffer rendered so far (kAllFaces bits)
  bool requested = false;           ///< a capture is due; it starts when none is in progress
  std::uint64_t last_capture_frame = 0;  ///< frame on which the front map's capture completed
  std::uint64_t signature = 0;      ///< on_change: hash of what lay in range at the capture start
  bool warned_off_centre = false;   ///< the off-centre pivot warning was logged
  // Counters since the scene was loaded (tests, `kaskad render`).
  std::uint64_t captures = 0;       ///< completed captures (or static loads)
  std::uint64_t faces_rendered = 0; ///< cube faces rendered
};

/// Set by the scene loader on a static_file Reflector: its loaded cube map, an index into
/// AssetStore::env_maps.
struct StaticEnvMap {
  std::uint32_t index = kNoProbe;
};

}  // namespace kaskad
