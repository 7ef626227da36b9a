// The renderer's passes, in the order Renderer::render() runs them (renderer.h):
//   DeformPass         skinned and morphed meshes posed (compute)          deform_pass.h
//   ShadowMapPass      the depth layers of every shadow view (S0, S4)       shadow_map_pass.h
//   LomPass            S1's layered occlusion map (technique lom)           lom_pass.h
//   MomentsPass        the blurred, mipmapped moments of vsm/evsm           moments_pass.h
//   ProbeCapturePass   reflection probe faces, mips and sphere maps (S3)    probe_capture_pass.h
//   ForwardPass        colour and AOVs of the main view                     forward_pass.h
// Each pass has prepare() (what it checks and decides before any draw: storage, which layers or
// faces are drawn) and record() (the GL commands), and says what is true after it. Draws go
// through DrawState (draw_state.h), which switches programs and materials only when they
// change. What the passes share: layer_cache.h (the GL-free rule for which texels of a layer are
// kept, drawn or scrolled), depth_draws.h (casters as instanced depth draws) and
// texture_storage.h (the driver's texture limits, border samplers, read-back).
#pragma once

#include "runtime/render/deform_pass.h"
#include "runtime/render/draw_state.h"
#include "runtime/render/forward_pass.h"
#include "runtime/render/lom_pass.h"
#include "runtime/render/moments_pass.h"
#include "runtime/render/probe_capture_pass.h"
#include "runtime/render/shadow_map_pass.h"
