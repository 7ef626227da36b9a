#include "runtime/render/texture_storage.h"

#include <cstring>
#include <utility>

namespace kaskad::render {

std::string TextureCheck::limits() const {
  return "GL_MAX_TEXTURE_SIZE " + std::to_string(max_size) + ", GL_MAX_ARRAY_TEXTURE_LAYERS " +
         std::to_string(max_layers);
}

TextureCheck check_array_texture(GLenum internal_format, GLenum format, int size, int layers) {
  TextureCheck c;
  GLint max_size = 0, max_layers = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
  c.max_size = max_size;
  c.max_layers = max_layers;
  if (size > max_size || layers > max_layers) {
    c.fit = TextureCheck::over_limits;
    return c;
  }
  glTexImage3D(GL_PROXY_TEXTURE_2D_ARRAY, 0, GLint(internal_format), size, size, layers, 0, format,
               GL_FLOAT, nullptr);
  GLint got = 0;
  glGetTexLevelParameteriv(GL_PROXY_TEXTURE_2D_ARRAY, 0, GL_TEXTURE_WIDTH, &got);
  if (got == 0) c.fit = TextureCheck::refused;
  return c;
}

gpu::Sampler border_sampler(bool compare, GLint filter) {
  gpu::Sampler s = gpu::make_sampler();
  const GLuint id = s.id();
  glSamplerParameteri(id, GL_TEXTURE_COMPARE_MODE, compare ? GL_COMPARE_REF_TO_TEXTURE : GL_NONE);
  glSamplerParameteri(id, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  glSamplerParameteri(id, GL_TEXTURE_MIN_FILTER, filter);
  glSamplerParameteri(id, GL_TEXTURE_MAG_FILTER, filter);
  glSamplerParameteri(id, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
  glSamplerParameteri(id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
  const float border[4] = {1.0f, 1.0f, 1.0f, 1.0f};
  glSamplerParameterfv(id, GL_TEXTURE_BORDER_COLOR, border);
  return s;
}

Image read_slices(const gpu::Texture& t, GLenum format, std::vector<std::string> names, int size,
                  int slices, int step) {
  Image img;
  img.width = size;
  img.height = size * slices;
  img.channels = int(names.size());
  img.channel_names = std::move(names);
  if (!t) return img;
  const std::size_t row = std::size_t(size) * std::size_t(img.channels);
  const std::size_t layer = row * std::size_t(size);
  std::vector<float> stack(layer * std::size_t(slices));
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  if (step == 1) {
    glGetTextureImage(t.id(), 0, format, GL_FLOAT, GLsizei(stack.size() * sizeof(float)),
                      stack.data());
  } else {
    for (int l = 0; l < slices; ++l)
      glGetTextureSubImage(t.id(), 0, 0, 0, l * step, size, size, 1, format, GL_FLOAT,
                           GLsizei(layer * sizeof(float)), &stack[std::size_t(l) * layer]);
  }
  img.pixels.resize(stack.size());
  for (int l = 0; l < slices; ++l)
    for (int y = 0; y < size; ++y)
      std::memcpy(&img.pixels[std::size_t(l) * layer + std::size_t(y) * row],
                  &stack[std::size_t(l) * layer + std::size_t(size - 1 - y) * row],
                  row * sizeof(float));
  return img;
}

}  // namespace kaskad::render
