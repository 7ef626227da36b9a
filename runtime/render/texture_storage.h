// The array textures of the shadow, LOM and moments passes: whether the driver can make one,
// samplers that read outside a map as lit, and reading slices back as an image.
#pragma once

#include <string>
#include <vector>

#include "runtime/assets/image_io.h"
#include "runtime/gpu/gl_handles.h"

namespace kaskad::render {

/// How a 2D array texture fits the driver (check_array_texture()).
struct TextureCheck {
  enum Fit { fits, over_limits, refused };
  Fit fit = fits;
  int max_size = 0, max_layers = 0;  ///< GL_MAX_TEXTURE_SIZE, GL_MAX_ARRAY_TEXTURE_LAYERS
  /// The limits for messages: "GL_MAX_TEXTURE_SIZE 16384, GL_MAX_ARRAY_TEXTURE_LAYERS 2048".
  std::string limits() const;
};

/// Whether the driver can make a 2D array texture of `layers` layers of `size`^2 texels in
/// `internal_format` (uploaded from floats as `format`): its size and layer limits, then a proxy
/// texture, so a texture it refuses is an error before any pass starts, not a string of GL
/// errors. The one texture-limit check of every pass's storage.
TextureCheck check_array_texture(GLenum internal_format, GLenum format, int size, int layers);

/// A sampler of shadow data with border 1, as the map itself (S4): outside it every compare is
/// lit, every raw depth 1 (LOM: nothing stored). `compare`: depth compare LEQUAL, else none.
gpu::Sampler border_sampler(bool compare, GLint filter);

/// Slices 0, step, 2 step, ... (`slices` of them) of 2D array texture `t` of `size`^2 texels as
/// one image, the first slice first, rows top to bottom within each (GL's bottom-to-top rows
/// flipped), in the channels `format` reads (GL_DEPTH_COMPONENT, GL_RED, GL_RG, GL_RGBA), named
/// `names`. No texture: an empty stack.
Image read_slices(const gpu::Texture& t, GLenum format, std::vector<std::string> names, int size,
                  int slices, int step = 1);

}  // namespace kaskad::render
