// A loaded scene: the ECS world, its CPU assets and its render settings.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <tuple>

#include <glm/glm.hpp>

#include "components/ibl.h"
#include "components/reflector.h"
#include "components/shadow_settings.h"
#include "components/tone_mapping.h"
#include "runtime/assets/asset_store.h"
#include "runtime/ecs/world.h"

namespace kaskad {

/// Whether the load phase adds a ground under the models (add_ground()).
enum class GroundMode {
  automatic,  ///< "auto": on for a .gltf/.glb opened directly, none for a scene file
  none,
  on,
};
constexpr std::array<std::string_view, 3> enum_names(GroundMode) { return {"auto", "none", "on"}; }
static_assert(enum_names(GroundMode{}).size() == std::size_t(GroundMode::on) + 1);

/// render.exposure_ev's range: 2^-20 to 2^13 (exposure's own limit is 1e4).
inline constexpr float kMinExposureEv = -20.0f, kMaxExposureEv = 13.0f;

/// Frame-wide render settings (scene file section "render").
struct RenderSettings {
  int width = 1280;                       ///< output image size, pixels
  int height = 720;
  /// Linear radiance arriving from every direction when there is no `environment`: surfaces
  /// reflect it through the BRDF's diffuse and specular lobes (components/ibl.h).
  glm::vec3 ambient{0.08f, 0.09f, 0.11f};
  glm::vec3 clear_color{0.55f, 0.65f, 0.8f};  ///< linear background colour
  /// An environment map lighting every surface instead of `ambient` (image-based lighting:
  /// its SH irradiance and GGX-prefiltered radiance), any layout load_cube_map() reads, relative
  /// to the scene file; empty: none. Loaded by load_environment() into Scene::environment_map.
  std::string environment;
  /// Multiplies the environment map's radiance.
  float environment_intensity = 1.0f;
  /// Multiplies linear colour before tone mapping and sRGB encoding. Scene files give it as
  /// `exposure` (this scale) or `exposure_ev` (stops: 2^EV, in [kMinExposureEv, kMaxExposureEv]).
  float exposure = 1.0f;
  /// The curve applied after the exposure (components/tone_mapping.h); none by default.
  ToneMapping tone_mapping = ToneMapping::none;
  /// Colour samples per pixel: 1 (no anti-aliasing, the default: every golden image and
  /// reference comparison was made so), 2, 4 or 8 (MSAA, resolved after tone mapping each
  /// sample; the AOVs stay single-sample). A count the driver does not offer is replaced by the
  /// nearest one it does, with a warning.
  int msaa = 1;
  /// Which shadowed light the AOV's visibility and cascade channels show: 0 the first, k the
  /// k-th further shadowed directional light (a debug path; colour is not affected).
  int aov_shadow_light = 0;
  /// A receive-only plane in a neutral grey under the models, large enough to catch their
  /// shadow, so that a bare model shows one.
  GroundMode ground = GroundMode::automatic;
  /// Shadow caching: a shadow-map layer whose inputs are those it was last drawn from keeps its
  /// depth. Off, every layer is drawn every frame (for measurements and comparisons).
  bool shadow_cache = true;
  /// Shadow scrolling: with shadow_cache, a stable cascade that moved by whole texels keeps the
  /// depth it holds and draws only the texels that came into view. Off, it is redrawn whole.
  bool shadow_scroll = true;
  /// Visibility caching: a frame that sees what the frame before saw (camera, draws, lights,
  /// shadow maps) reads each pixel's shadow visibility back instead of looking the maps up.
  /// Images are identical either way; off, every frame looks up (for measurements).
  bool visibility_cache = true;
  /// Visibility reprojection: with visibility_cache, a frame whose camera alone moved reuses
  /// the visibility of the frame before where it finds the same surface inside a shadow or a lit
  /// area, and looks the maps up only at shadow edges and surfaces newly in view. Off, a moving
  /// camera looks up every pixel (docs/design/shadow_cost.md, "Reprojected visibility").
  bool visibility_reproject = true;
  /// Multi-draw: draws with the same program, material and winding but different meshes are one
  /// glMultiDrawElementsIndirect (one instanced draw per mesh in it). Off, one call per mesh.
  /// Images are identical either way (for measurements, and drivers that mishandle it).
  bool multi_draw = true;
  /// Capture rounds on a frame where reflection probes make their first capture, in
  /// [kMinProbeBounces, kMaxProbeBounces] (components/reflector.h): each round reads the other
  /// probes' maps of the round before, so round k shows mirrors seen in mirrors k - 1 deep.
  int probe_bounces = kDefaultProbeBounces;
};

/// The fields of RenderSettings, once (runtime/fields/fields.h); exposure_ev, another form of
/// exposure, is the scene reader's.
constexpr auto field_table(fields::Of<RenderSettings>) {
  using R = RenderSettings;
  using namespace fields;
  return std::tuple{
      integer("width", &R::width, 1, 16384, "Output image width, pixels"),
      integer("height", &R::height, 1, 16384, "Output image height, pixels"),
      vector("ambient", &R::ambient, 0, 1.0e4, "Linear radiance from every direction without an environment"),
      vector("clear_color", &R::clear_color, 0, 1.0e4, "Linear background colour"),
      number("exposure", &R::exposure, 0, 1.0e4,
             "Scale of linear colour before tone mapping (or exposure_ev, stops)"),
      choice("tone_mapping", &R::tone_mapping, "The curve applied after the exposure"),
      text("environment", &R::environment, "Environment map lighting every surface; empty: ambient"),
      number("environment_intensity", &R::environment_intensity, 0, 1.0e4,
             "Multiplies the environment map's radiance"),
      integer("msaa", &R::msaa, 1, 8, "Colour samples per pixel", kPowerOfTwo),
      integer("aov_shadow_light", &R::aov_shadow_light, 0, 3,
              "Which shadowed light the AOV's visibility and cascade channels show", kDebug),
      choice("ground", &R::ground, "A receive-only ground plane under the models"),
      flag("shadow_cache", &R::shadow_cache, "Shadow-map layers whose inputs did not change keep their depth"),
      flag("shadow_scroll", &R::shadow_scroll,
           "A stable cascade moved by whole texels draws only the texels that came into view"),
      flag("visibility_cache", &R::visibility_cache,
           "A frame that sees what the frame before saw reads its shadow visibility back"),
      flag("visibility_reproject", &R::visibility_reproject,
           "A frame whose camera alone moved reuses the visibility of the frame before inside shadows and lit areas"),
      flag("multi_draw", &R::multi_draw,
           "Draws of one program and material but different meshes are one multi-draw"),
      integer("probe_bounces", &R::probe_bounces, kMinProbeBounces, kMaxProbeBounces,
              "Capture rounds on a frame where reflection probes make their first capture"),
  };
}

struct Scene {
  ecs::World world;
  AssetStore assets;
  RenderSettings render;
  /// Defaults for shadowed lights (scene file section "shadow"); a light's own "shadow" block
  /// overrides individual fields.
  ShadowSettings shadow_defaults;
  std::filesystem::path file;  ///< where it was loaded from (relative paths resolve against it)
  /// render.environment as loaded: an index into assets.env_maps (kNoEnvironment: none), the
  /// path it was loaded from, and a number unique to each load (the renderer prefilters a map
  /// once per number).
  static constexpr std::uint32_t kNoEnvironment = ~0u;
  std::uint32_t environment_map = kNoEnvironment;
  std::string environment_loaded;
  std::uint64_t environment_serial = 0;
  Sh9 environment_sh{};  ///< its SH coefficients (project_sh9)
  /// Frames run since the scene was loaded: the next frame's FrameContext::index. render_frames()
  /// advances it, so a caller that renders one frame per call (the editor) still counts frames
  /// (every_n probes, for one).
  std::uint64_t frames_rendered = 0;
};

}  // namespace kaskad
