// The viewport's debug views as images: an AOV view (editor/script.h, View), a cube map's faces, a
// sphere map, a one-channel map as grey; and the window as drawn, for window screenshots.
#pragma once

#include "editor/script.h"
#include "runtime/assets/env_map.h"
#include "runtime/assets/image_io.h"

namespace kaskad::editor {

/// The window's back buffer (panels and viewport) as RGB, top row first. Needs the GL context.
Image read_window(int w, int h);

/// Linear radiance clamped to [0, 1] and encoded for display with a 2.2 gamma (an approximation
/// of sRGB is enough for a debug view).
float display_gamma(float linear);

/// An AOV view (is_aov_view(view)) as an RGB image; `aovs` has the channels of
/// Renderer::read_aovs(), found by the names it gives them (docs/guide/cli.md, "AOV contract").
Image aov_view(View view, const Image& aovs);

/// A cube map's faces side by side (+X -X +Y -Y +Z -Z), encoded by display_gamma().
Image cube_strip(const CubeMap& cube);

/// A sphere map (row 0 at the top) as an image, encoded by display_gamma().
Image sphere_image(const SphereMap& map);

/// A one-channel image as grey RGB.
Image grey(const Image& one);

}  // namespace kaskad::editor
