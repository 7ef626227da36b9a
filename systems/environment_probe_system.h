// EnvironmentProbeSystem (S3): per Reflector, decides on frame k whether to load its static map
// or which cube faces to capture, keeps a front/back pair of maps so a time-sliced capture never
// shows a half-updated cube, and publishes ProbeData for the renderer. The frame's Probes phase.
// Schedule and capture-camera maths are pure (no GL) and unit-tested; the renderer records the
// captures (runtime/render/probe_capture.h).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "components/bounds.h"
#include "components/probe_state.h"
#include "components/reflector.h"
#include "runtime/ecs/world.h"
#include "runtime/render/frame_input.h"

namespace kaskad {

/// What the probes do this frame: one renderer job per Reflector, plus counters.
struct ProbeData {
  struct Entry {
    ecs::Entity entity = ecs::kNullEntity;
    render::ProbeJob job;
    bool has_map = false;  ///< a complete map is visible after this frame (shade with it)
    bool sphere = false;   ///< the map type shown (Reflector::map)
    float amount = 1.0f;   ///< S3's p_r
  };
  std::vector<Entry> probes;
  int faces_this_frame = 0;          ///< cube faces captured this frame, all probes and rounds
  int rounds = 1;                    ///< capture rounds this frame (probe_capture_rounds())
  int captures_this_frame = 0;       ///< captures completed (or files loaded) this frame
  std::uint64_t captures_total = 0;  ///< since load, all probes (ProbeState counters)
  std::uint64_t faces_total = 0;

  /// The entry of `e`, or nullptr.
  const Entry* find(ecs::Entity e) const;
};

/// Phase 4 (Probes). Adds ProbeState to new Reflectors, computes each capture centre (explicit,
/// else the world-bounds centre, warning once about an off-centre pivot), the on_change
/// signature, runs schedule_probe(), then gives the probes that capture all six faces this frame
/// probe_capture_rounds() rounds (`bounces`: render.probe_bounces, in [1, 4]); faces counters
/// count every round. With `commit` false (planning: prewarm, `kaskad variants`) nothing in the
/// world changes. Needs current WorldTransform/WorldBounds.
ProbeData update_environment_probes(ecs::World& world, std::uint64_t frame, bool commit = true,
                                    int bounces = kDefaultProbeBounces);

// ---- Pure parts, exposed for tests -------------------------------------------------------------

/// World bounds of a reflector: its own mesh's, or for a model entity (no mesh of its own) the
/// union of the meshes imported under it. Empty when neither has bounds.
Aabb reflector_bounds(const ecs::World& world, ecs::Entity e);

/// What one probe does on one frame.
struct ProbeWork {
  std::uint8_t faces = 0;  ///< faces of the back buffer to render now (bit f = GL face f)
  bool swap = false;       ///< after them the back buffer is complete and becomes the front
  bool load = false;       ///< static_file: load the file into the front buffer now
};

/// Advances `s` by frame `frame` of a probe with settings `r`. `signature` summarises what lies in
/// the probe's range (scene_signature()); on_change captures when it differs from the one taken
/// at the last capture start. Rules:
///   static_file  loads once, on the first frame, and never captures.
///   first_frame  captures once, starting on the first frame.
///   every_n      a capture starts on frames 0, N, 2N, ... (a start that falls while a sliced
///                capture is still running waits for it and starts on the next frame).
///   on_change    captures on the first frame, then whenever the signature changed.
/// A capture renders min(faces_per_frame, remaining) faces per frame into the back buffer in
/// GL face order and swaps only when all six are done. The first capture renders all six on its
/// first frame (no map exists yet to show meanwhile).
ProbeWork schedule_probe(const Reflector& r, ProbeState& s, std::uint64_t frame,
                         std::uint64_t signature);

/// Capture rounds of a frame on which `full_captures` probes capture all six faces, `any_first`
/// whether one of them captures for the first time, and `bounces` is render.probe_bounces (in
/// [kMinProbeBounces, kMaxProbeBounces]; a precondition). Those probes are captured `bounces`
/// times in a row, round k reading the others' maps of round k - 1 (round 1: their maps as of
/// before the frame, black before a first capture), so with 2 a mirror seen in another mirror's
/// first map shows its own first map instead of black. Else 1: re-captures read the others'
/// maps of earlier frames, which already hold their bounces, and time-sliced captures keep their
/// per-frame cost. A probe never sees itself, so one capturing probe alone gets 1 round too.
int probe_capture_rounds(int full_captures, bool any_first, int bounces);

/// GL cube-map face f (0..5 = +X, -X, +Y, -Y, +Z, -Z): world -> view of a 90° camera at `center`
/// (S3: the pivot's translation, the six orientations by rotation) such that NDC (x, y) is the
/// face's texture (s, t) in GL's cube-map convention (GL 4.5 spec table 8.19), so a face rendered
/// into the cube map's layer f is looked up correctly with no flips.
glm::mat4 cube_face_view(int face, const glm::vec3& center);
/// The matching projection: 90° vertical field of view, aspect 1.
glm::mat4 cube_face_projection(float near, float far);

/// The on_change signature of the probe on `self` centred at `center` with range `far`: every
/// light, and every MeshRenderer other than `self` and outside `exclude_layers` whose world
/// bounds intersect the sphere (center, far): entity, world matrix, mesh and material.
std::uint64_t scene_signature(const ecs::World& world, ecs::Entity self, const glm::vec3& center,
                              float far, std::uint32_t exclude_layers);

}  // namespace kaskad
