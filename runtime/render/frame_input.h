// What the renderer is given each frame (phase 5's output, systems/frame.h): plain data, no GL.
// The passes of runtime/render/renderer.h draw exactly this.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "components/bounds.h"
#include "components/ibl.h"
#include "components/light.h"
#include "components/limits.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/probe_state.h"
#include "components/tone_mapping.h"
#include "components/shadow_settings.h"

namespace kaskad {
struct CubeMap;
}

namespace kaskad::render {

struct CameraView {
  glm::mat4 view{1.0f};
  glm::mat4 proj{1.0f};
  glm::vec3 position{0.0f};
};

struct DrawItem {
  MeshId mesh = kNoMesh;
  glm::mat4 model{1.0f};
  Material material;
  bool cast_shadows = true;
  bool receive_shadows = true;
  /// Bit l: drawn into layer l of the shadow map array (when cast_shadows). Each shadow view
  /// owns the layers first_layer .. first_layer + layer_count - 1 (ShadowView).
  std::uint32_t shadow_layers = ~0u;
  int layer = 0;  ///< MeshRenderer::layer (probes may exclude layers)
  /// World bounds, for culling against the main view and each probe face; empty: always drawn.
  Aabb bounds;
  /// The reflection probe this draw reflects (its own Reflector; none by default). The draw is
  /// never drawn into that probe. With a reflection material feature on, it is shaded with the
  /// probe's visible map, scaled by `reflection_scale` = k_s * p_r (S3 eq. (3)).
  ProbeHandle probe;
  float reflection_scale = 0.0f;
  /// A deformed draw (skin or morph targets): `mesh` is its entity's own copy that the deform
  /// pass writes this frame, and `pose` a hash of what posed it (changes whenever the shape
  /// does; the shadow and visibility caches compare it). 0 for a mesh drawn as stored.
  std::uint64_t pose = 0;
};

/// One deformed mesh's GPU work this frame (the deform pass, runtime/render/deform_pass.h):
/// `source`'s vertices posed into `posed` with skin matrices first_matrix .. + matrix_count of
/// FrameInput::skin_matrices (none: not skinned) and morph weights first_weight .. +
/// weight_count of FrameInput::morph_weights (runtime/assets/mesh_pose.h defines the pose).
struct DeformJob {
  MeshId source = kNoMesh, posed = kNoMesh;
  int influences = 0;  ///< joints a vertex (MeshDeform::influences); 0 when not skinned
  std::uint32_t vertex_count = 0;
  std::uint64_t pose = 0;  ///< DrawItem::pose of its draw
  std::uint32_t first_matrix = 0, matrix_count = 0;
  std::uint32_t first_weight = 0, weight_count = 0;
};

/// One reflection probe's GPU work this frame (systems/environment_probe_system.h). Each probe
/// has two cube maps (RGBA16F with mips): `faces` of buffer `target` are captured, then buffer
/// `visible` is shaded with. Captures draw the frame's draws (shadows included) except the
/// probe's own and excluded layers; reflective draws in them read probe_read_buffer(): the
/// maps as of before this frame's captures, or in bounce rounds the previous round's.
struct ProbeJob {
  ProbeHandle handle;
  glm::vec3 center{0.0f};
  float near = 0.05f, far = 100.0f;
  int resolution = 128;
  std::uint32_t exclude_layers = 0;
  std::uint8_t faces = 0;  ///< bit f: capture GL face f (+X, -X, +Y, -Y, +Z, -Z) into `target`
  int target = 1;
  int visible = 0;
  bool sphere = false;     ///< shade with a sphere map made from the visible cube (S3 eq. (2))
  bool box = false;        ///< box projection of cube lookups onto [box_min, box_max] (world)
  /// A draw of the pbr reflection model reflects this probe: its visible cube is prefiltered
  /// (SH and GGX levels, IblMaps) whenever it has changed, `faces_per_frame` faces a frame like
  /// the captures (all six for the first map).
  bool prefilter = false;
  int faces_per_frame = 6;
  glm::vec3 box_min{0.0f}, box_max{0.0f};
  /// World -> clip of the six 90° face cameras (systems/environment_probe_system.h).
  std::array<glm::mat4, 6> view_proj{};
  /// Static file: index into AssetStore::env_maps to upload into buffer `visible` this frame;
  /// kNoProbe: nothing to upload.
  std::uint32_t env_map = kNoProbe;
  /// Capture rounds this frame (render.probe_bounces; 1: one capture). With more, `faces` (all
  /// six) are captured `rounds` times, alternating between the two buffers so that the last
  /// round writes `target` (capture_buffer()), and captures of round r see this probe's map of
  /// round r - 1 (probe_read_buffer()).
  int rounds = 1;
};

/// The buffer that capture round `round` (1..job.rounds) of `job` renders into: `target` in the
/// last round, the other buffer in the one before, and so on.
constexpr int capture_buffer(const ProbeJob& job, int round) {
  return (job.rounds - round) % 2 == 0 ? job.target : 1 - job.target;
}

/// The buffer of `job` that a reflective draw of it reads while capture round `round` of this
/// frame renders; 0: the main view, after every capture. Never the buffer `job` is being
/// captured into, so a round reads the previous round's map (round 1: the map as of before this
/// frame; a first capture's other buffer is black).
constexpr int probe_read_buffer(const ProbeJob& job, int round) {
  if (round == 0) return job.visible;
  if (job.rounds > 1 && round <= job.rounds) return 1 - capture_buffer(job, round);
  const bool swapped_now = job.faces != 0 && job.target == job.visible;
  return swapped_now ? 1 - job.visible : job.visible;  // the map as of before this frame
}

/// A light as the shaders see it (light_shading() in components/light.h makes one).
using LightItem = LightShading;

/// Every layer read whole: the NDC rectangle [-1, 1]^2 per layer (ShadowView::read_rect).
inline std::array<glm::vec4, kMaxCascades> whole_layers() {
  std::array<glm::vec4, kMaxCascades> r;
  r.fill(glm::vec4(-1.0f, -1.0f, 1.0f, 1.0f));
  return r;
}

/// One shadowed light's maps (systems/shadow_cascade_system.h makes them): its layers of the
/// shared depth texture array and what the depth pass and the shaders need to draw and read
/// them. Every view is handled by the same code; only the first may be a spot or point light
/// (its projection is a frame shader feature), the others are ortho cascades.
struct ShadowView {
  int light_index = -1;  ///< index into FrameInput::lights (one of the shaded ones)
  /// ortho: a directional light's cascades; perspective: a spot map; cube (6 faces) or
  /// dual_paraboloid (2 hemispheres): a point light's maps. "Cascade" below means layer.
  ShadowProjection projection = ShadowProjection::ortho;
  int first_layer = 0;  ///< its first layer in the shadow map array; views follow each other
  int layer_count = 1;  ///< in [1, kMaxCascades]
  /// World -> light clip space per layer; dual_paraboloid: world -> hemisphere view.
  std::array<glm::mat4, kMaxCascades> view_proj{};
  /// S0's D, metres of view depth; spot/point: [near, far] metres from the light.
  std::array<float, kMaxCascades + 1> splits{};
  /// Metres per texel per layer; spot/point: at 1 m from the light.
  std::array<float, kMaxCascades> texel_size{};
  std::array<bool, kMaxCascades> skipped{};  ///< no receivers: cleared, nothing drawn
  /// The part of each layer the lookups read, NDC x/y (min x, min y, max x, max y); empty when
  /// min > max (ShadowData::read_rect). The depth pass clears and draws only there unless a
  /// pass that reads anywhere in the map (a probe capture, the layered pass) runs this frame.
  std::array<glm::vec4, kMaxCascades> read_rect = whole_layers();
  /// Bit c: layer c keeps its depth from when it was last drawn even if its casters moved (a far
  /// cascade between updates, ShadowSettings::far_cascade_interval), when it holds the texels
  /// needed now. Its matrix is the one it was drawn with.
  std::uint32_t held = 0;
  /// Shading: the normal offset in texels of the layer (0 for the basic map, FitMode::scene),
  /// the blend band (fraction of a cascade), the paraboloid margin (dual_paraboloid).
  float normal_offset = 0.0f;
  float blend_band = 0.0f;
  float paraboloid_margin = 0.0f;
  /// Soft shadows (ShadowSettings::technique): the light's size (ShadowData::light_size:
  /// directional, 2 tan(angular size / 2), penumbra metres per metre of blocker-receiver
  /// distance; spot/point, the emitter width 2 radius in metres; area, its width (map x) and
  /// height (map y)), and the Poisson disc's taps
  /// and radius in texels (ShadowSettings::pcf_taps, pcf_radius).
  glm::vec2 light_size{0.0f};
  int pcf_taps = 16;
  float pcf_radius = 2.5f;
  /// Texels the lookup reaches from the point's texel (filter_reach_texels()): map_bounds
  /// selection keeps this, plus the normal offset, free at a cascade's edges.
  float filter_reach = 1.5f;
  /// Depth pass: polygon offset and face culling.
  float slope_bias = 0.0f, constant_bias = 0.0f;
  CullMode cull = CullMode::back;
};

struct FrameInput {
  int width = 1280;
  int height = 720;
  CameraView camera;
  std::vector<DrawItem> draws;
  std::vector<LightItem> lights;  ///< at most kMaxLights are shaded
  /// One per shadowed light, at most kMaxShadowedLights; empty: no shadow pass.
  std::vector<ShadowView> shadow_views;
  /// The first shadowed light's settings: the shadow map array and the shadow features every
  /// view shares (for_each_shared_field(); ShadowData::settings). The passes read those fields
  /// only; a view's own values are in its ShadowView.
  ShadowSettings shadow_settings;
  /// The view whose visibility and cascade the AOV shows (an index into shadow_views).
  int aov_shadow_view = 0;
  std::vector<ProbeJob> probes;
  /// Meshes to pose before any pass draws (skins and morph targets) and their inputs.
  std::vector<DeformJob> deforms;
  std::vector<glm::mat4> skin_matrices;
  std::vector<float> morph_weights;
  /// Light from the surroundings (components/ibl.h): the environment map when there is one
  /// (not owned; prefiltered once per `environment_key`), its radiance times
  /// `environment_intensity`; else the uniform ambient radiance.
  glm::vec3 ambient{0.05f};
  const CubeMap* environment = nullptr;
  std::uint64_t environment_key = 0;
  Sh9 environment_sh{};  ///< its SH coefficients (project_sh9, once per load)
  float environment_intensity = 1.0f;
  glm::vec3 clear_color{0.0f};
  float exposure = 1.0f;
  /// The curve the colour output goes through after the exposure (the AOVs and probe cubes stay
  /// linear); also applied to the clear colour.
  ToneMapping tone_mapping = ToneMapping::none;
  /// Write the AOV targets (position, normal + depth, visibility). Off, the forward pass writes
  /// colour only: on llvmpipe the three float targets cost more than the shading itself.
  bool write_aovs = true;
  /// Colour samples per pixel (render.msaa: 1, 2, 4 or 8; the renderer uses the nearest count
  /// the driver offers). Above 1 the colour is drawn multisampled and resolved; the AOVs are
  /// drawn by a single-sample pass of their own, as with 1.
  int msaa = 1;
  /// Keep shadow-map layers whose inputs did not change (ShadowMapPass); off: draw all.
  bool shadow_cache = true;
  /// render.shadow_scroll: with shadow_cache, scroll a moved stable cascade (ShadowMapPass).
  bool shadow_scroll = true;
  /// render.multi_draw: a batch of meshes sharing program, material and winding is one call.
  bool multi_draw = true;
  /// render.visibility_cache: the main view keeps each pixel's shadow visibility, and a frame
  /// whose visibility inputs equal the frame before's reads it back instead of looking the
  /// shadow maps up (Renderer::render()). Not with AOVs, MSAA or the cascade tint.
  bool visibility_cache = true;
  /// render.visibility_reproject: with visibility_cache, a frame whose camera alone moved
  /// reprojects the stored visibility and looks up only where it cannot reuse it.
  bool visibility_reproject = true;
};

}  // namespace kaskad::render
