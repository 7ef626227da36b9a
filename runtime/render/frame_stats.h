// What a frame did: draw calls, shadow layers drawn and kept, technique passes, probe faces, GPU
// times and shader statistics (Renderer::stats()). Filled by the passes as they prepare and record.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

#include "components/limits.h"
#include "runtime/render/shader_library.h"

namespace kaskad::render {

/// Draw calls are GL draw calls: draws that share program, material and winding are one call, a
/// multi-draw of one instanced draw per mesh among them (mesh draws; a call of one mesh is a plain
/// instanced draw). Instances are the objects those calls draw.
struct FrameStats {
  /// Forward pass of the main view; with render.msaa > 1 and AOVs, its multisampled colour
  /// and single-sample AOV draws together (each object twice).
  int draw_calls = 0;
  int deformed_meshes = 0;            ///< meshes the deform pass posed (skins, morph targets)
  int mesh_draws = 0;                 ///< the instanced draws within them (one per mesh)
  int instances = 0;                  ///< objects drawn by them
  int frustum_culled = 0;             ///< draws outside the main view's frustum, not drawn
  std::size_t triangles = 0;          ///< submitted in the forward pass (both, as draw_calls)
  /// Shadow pass draw calls recorded this frame (0 when every layer kept its depth).
  int shadow_draw_calls = 0;
  int shadow_mesh_draws = 0;  ///< the instanced draws within them (one per mesh)
  /// Caster instances in the shadow map's layers (one per caster and layer) and their
  /// triangles, whether drawn this frame or kept from an earlier one (shadow_layers_rendered
  /// says which layers were drawn).
  int shadow_instances = 0;
  std::size_t shadow_triangles = 0;
  int shadow_layers = 0;  ///< layers of the shadow map this frame (all shadow views)
  /// Bit l: texture-array layer l was cleared and re-rendered this frame. The others kept their
  /// depth: same matrix, casters, caster matrices, bias and pass mode as when last drawn.
  std::uint32_t shadow_layers_rendered = 0;
  /// Caster instances left out of layers drawn this frame over part of their texels
  /// (shadow.scissor_to_receivers) because their boxes miss those texels.
  int shadow_rect_culled = 0;
  /// Bit l: layer l scrolled this frame (render.shadow_scroll): its matrix moved by whole texels
  /// (or not at all, its read rectangle having grown) and it kept the depth it held, drawing
  /// only the texels it did not hold (if any, its bit in shadow_layers_rendered is set too).
  std::uint32_t shadow_layers_scrolled = 0;
  /// render.shadow_cache: bit l when layer l kept its depth but for the texels of casters that
  /// moved, came or went (the same matrix: a still camera), which alone it drew again.
  std::uint32_t shadow_layers_patched = 0;
  /// Texels cleared and drawn this frame over all layers (each layer's size^2 when redrawn whole).
  std::int64_t shadow_texels_drawn = 0;
  /// Per layer of the shadow map array (all shadow views; view k's layers start at its
  /// first_layer): the casters it holds, their triangles, and metres per texel (spot and point
  /// layers: at 1 m from the light).
  std::array<int, kMaxShadowLayers> layer_casters{};
  std::array<std::size_t, kMaxShadowLayers> layer_triangles{};
  std::array<float, kMaxShadowLayers> layer_texel_size{};
  /// The texels of each layer that lookups read this frame, (x0, y0, x1, y1) with exclusive
  /// ends: its read rectangle (ShadowView::read_rect), the whole layer when a pass that reads
  /// anywhere runs. The depth pass clears and draws only these when it redraws the layer;
  /// outside them a layer may hold stale depth. Empty (x0 >= x1) when nothing reads it.
  std::array<glm::ivec4, kMaxShadowLayers> layer_rect{};
  /// Receiver pixels per cascade: pixels of the frame's AOV whose `cascade` channel is i (visible
  /// shadow-receiving surfaces shaded from cascade i; the first one where blending). Counted by
  /// cascade_pixel_counts(), which render_frames() calls after its last frame when AOVs are
  /// written; 0 otherwise.
  std::array<std::size_t, kMaxCascades> cascade_receiver_pixels{};
  /// ShadowTechnique::lom: shadow-map layers whose peels and occlusion factors were recomputed
  /// this frame (bit l, as shadow_layers_rendered), and texels, over all layers, where the
  /// depth peels found more light-facing surfaces than lom_layers (a point under all of them
  /// reads as umbra; shadow_lom.glsl's lom()).
  std::uint32_t lom_layers_computed = 0;
  std::int64_t lom_overflow_texels = 0;
  /// ShadowTechnique::vsm/evsm: shadow-map layers whose moments were recomputed this frame (bit
  /// l, as shadow_layers_rendered; MomentsPass).
  std::uint32_t vsm_layers_computed = 0;
  /// render.visibility_cache: the forward pass read each pixel's shadow visibility back from
  /// the frame before instead of looking the shadow maps up (nothing it depends on changed).
  bool visibility_reused = false;
  /// render.visibility_reproject: the camera alone moved, and the forward pass reused the
  /// visibility of the frame before where it found the same surface inside a shadow or a lit
  /// area (looking the maps up elsewhere), and stored its own.
  bool visibility_reprojected = false;
  /// render.visibility_cache: the forward pass stored each pixel's visibility for the next frame
  /// (a frame that sees what the frame before saw and does not read back).
  bool visibility_stored = false;
  /// GPU times are the previous frame's (queries are read a frame late); 0 until frame 3.
  /// GPU time (GL_TIMESTAMP pairs, GpuTimers) of the shadow pass with LOM and moments, the
  /// forward pass and the probe captures (previous frame).
  double shadow_gpu_ms = 0.0;
  double forward_gpu_ms = 0.0;
  double probe_gpu_ms = 0.0;
  /// Parts of the above (previous frame): LomPass and MomentsPass (in shadow_gpu_ms), and pbr
  /// prefiltering with SH projection of probes and the environment map (in probe_gpu_ms).
  double lom_gpu_ms = 0.0, moments_gpu_ms = 0.0, prefilter_gpu_ms = 0.0;
  int probe_faces_timed = 0;          ///< faces that probe_gpu_ms covers (previous frame's)
  int probe_faces = 0;                ///< reflection probe cube faces rendered this frame
  int probe_prefilters = 0;           ///< probe cubes whose pbr prefiltering completed this frame
  int probe_prefilter_faces = 0;      ///< cube faces prefiltered this frame (time-sliced)
  int probe_draw_calls = 0;           ///< draw calls into those faces (not in draw_calls)
  int probe_instances = 0;            ///< objects they draw
  int probe_culled = 0;               ///< draws outside a captured face's frustum, not drawn
  /// Colour samples per pixel of the main view (render.msaa as the driver offers it; 1: none).
  int msaa_samples = 1;
  int program_switches = 0;           ///< glUseProgram calls in the frame (draws are sorted)
  int material_switches = 0;          ///< material uniform/texture updates in the frame
  ShaderStats shaders;                ///< compiles, cache hits, compile ms (since creation)
};

}  // namespace kaskad::render
