// The headless (or windowed) player: loads a scene, renders frames through the frame phases, times
// them, and writes images and AOVs. Used by the `kaskad` CLI, the editor and the render tests.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/assets/scene.h"
#include "runtime/result/result.h"
#include "runtime/gpu/context.h"
#include "runtime/render/renderer.h"
#include "systems/frame.h"

namespace kaskad {

/// Where shaders, scenes and models live: $KASKAD_CONTENT_DIR, else the build-time content/ path.
std::filesystem::path content_dir();

/// Reads, canonicalises, applies `overrides` (--set), parses and instantiates a scene, then runs
/// the load phase: transforms, and framing of auto_frame cameras for render.width/height.
Result<Scene> load_scene(const std::filesystem::path& file,
                         const std::vector<std::string>& overrides = {});

/// load_scene() of a scene document already in memory (a canonical one, scene_to_json()), read
/// as if it were `file` (relative model paths): the editor's undo restores its snapshots so.
Result<Scene> load_scene_document(const nlohmann::json& document,
                                  const std::filesystem::path& file);

/// A GL context plus a renderer reading shaders from content_dir()/shaders.
struct Player {
  std::unique_ptr<gpu::Context> context;
  std::unique_ptr<render::Renderer> renderer;
  /// The systems' state of the scene being rendered, carried across render_frames() calls
  /// (frozen cascades, hysteresis, errors logged once) as the editor renders one call per frame.
  SystemState systems;

  /// Renderer options default to the shader binary cache in default_shader_cache_dir().
  static Result<Player> create(const gpu::ContextOptions& options,
                               const render::RendererOptions& renderer_options = defaults());
  static render::RendererOptions defaults();
};

struct RenderRun {
  int frames = 1;  ///< frames rendered; the last one is kept for read-back
  int width = 0;   ///< 0: take render.width / render.height from the scene
  int height = 0;
  bool write_aovs = true;  ///< needed for Renderer::read_aovs(); off saves fill rate
  bool prewarm = true;     ///< compile the scene's programs before the first frame
  /// Seconds the animation clock moves on per frame (FrameContext::dt); 0: every frame shows
  /// the same moment.
  double dt = 0.0;
};

struct RenderTimings {
  double prewarm_ms = 0.0;                  ///< shader programs built/loaded before frame 1
  double first_frame_ms = 0.0;              ///< includes uploads (and compiles if not prewarmed)
  std::vector<double> frame_ms;             ///< every frame after the first (CPU wall, GPU finished)
  double median_ms() const;                 ///< median of frame_ms (first frame if it is empty)
  FrameReport last;                         ///< phase times and counters of the last frame
  /// The first frame's probe capture rounds and faces (bounce rounds run on it; ProbeData).
  int first_probe_rounds = 1;
  int first_probe_faces = 0;
};

/// Renders `run.frames` frames of `scene`, waiting for the GPU after each so the times are honest.
/// Frame indices continue from scene.frames_rendered, which advances by `run.frames`.
Result<RenderTimings> render_frames(Player& player, Scene& scene, const RenderRun& run);

}  // namespace kaskad
