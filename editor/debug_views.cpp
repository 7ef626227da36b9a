#include "editor/debug_views.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

#include "components/bounds.h"
#include "runtime/result/result.h"

namespace kaskad::editor {

// The window as drawn (panels and viewport), top row first.
Image read_window(int w, int h) {
  Image img;
  img.width = w;
  img.height = h;
  img.channels = 3;
  std::vector<unsigned char> bytes(std::size_t(w) * std::size_t(h) * 3);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, bytes.data());
  img.pixels.resize(bytes.size());
  const std::size_t row = std::size_t(w) * 3;
  for (std::size_t y = 0; y < std::size_t(h); ++y)
    for (std::size_t i = 0; i < row; ++i)
      img.pixels[y * row + i] = float(bytes[(std::size_t(h) - 1 - y) * row + i]) / 255.0f;
  return img;
}

// Linear radiance clamped to [0, 1] and encoded for display with a 2.2 gamma (an approximation
// of sRGB is enough for a debug view).
float display_gamma(float linear) {
  return std::pow(std::clamp(linear, 0.0f, 1.0f), 1.0f / 2.2f);
}

// An AOV view as an RGB image; `aovs` has the channels of Renderer::read_aovs(), found by the
// names it gives them (docs/guide/cli.md, "AOV contract").
Image aov_view(View view, const Image& aovs) {
  Image out;
  out.width = aovs.width;
  out.height = aovs.height;
  out.channels = 3;
  out.pixels.assign(std::size_t(aovs.width) * std::size_t(aovs.height) * 3, 0.0f);
  auto channel = [&](const char* name) {
    const auto it = std::find(aovs.channel_names.begin(), aovs.channel_names.end(), name);
    KASKAD_CHECK(it != aovs.channel_names.end(), "the AOVs have a channel of every name read here");
    return int(it - aovs.channel_names.begin());
  };
  const int px = channel("P.X"), nx = channel("N.X"), z = channel("Z"), vis = channel("visibility"),
            mask = channel("mask"), cascade = channel("cascade"), rr = channel("reflection.R"),
            reflector = channel("reflector");
  // Cascades 0..7 in distinct colours (outside every cascade: black).
  static const glm::vec3 kCascade[] = {{1, 0.2f, 0.2f}, {0.2f, 1, 0.2f}, {0.3f, 0.4f, 1},
                                       {1, 1, 0.2f},    {1, 0.3f, 1},    {0.2f, 1, 1},
                                       {1, 0.6f, 0.2f}, {0.7f, 0.7f, 0.7f}};
  // The depth and position views span what is visible.
  float far = 0.0f;
  Aabb seen;
  auto vec3_at = [&](int x, int y, int first) {
    return glm::vec3(aovs.at(x, y, first), aovs.at(x, y, first + 1), aovs.at(x, y, first + 2));
  };
  for (int y = 0; y < aovs.height; ++y)
    for (int x = 0; x < aovs.width; ++x)
      if (aovs.at(x, y, mask) > 0.5f) {
        far = std::max(far, aovs.at(x, y, z));
        seen.expand(vec3_at(x, y, px));
      }
  const glm::vec3 span =
      seen.empty() ? glm::vec3(1.0f) : glm::max(seen.max - seen.min, glm::vec3(1e-6f));
  for (int y = 0; y < aovs.height; ++y)
    for (int x = 0; x < aovs.width; ++x) {
      glm::vec3 c{0.0f};
      if (aovs.at(x, y, mask) > 0.5f) {
        switch (view) {
          case View::visibility:
            c = glm::vec3(aovs.at(x, y, vis));
            break;
          case View::cascade: {
            const int k = int(std::lround(aovs.at(x, y, cascade)));
            if (k >= 0) c = kCascade[k % 8] * (0.4f + 0.6f * aovs.at(x, y, vis));
            break;
          }
          case View::normal:
            c = 0.5f * vec3_at(x, y, nx) + 0.5f;
            break;
          case View::depth:
            c = glm::vec3(far > 0.0f ? 1.0f - aovs.at(x, y, z) / far : 0.0f);
            break;
          case View::position:
            c = (vec3_at(x, y, px) - seen.min) / span;
            break;
          case View::reflection: {
            // C_t where a reflection map shades the surface; other surfaces dark grey (the
            // editor test's reflector mask, tests/editor/changed_within.py, knows this grey).
            constexpr float kNotReflecting = 0.08f;
            const glm::vec3 t = vec3_at(x, y, rr);
            c = aovs.at(x, y, reflector) > 0.5f
                    ? glm::vec3(display_gamma(t.r), display_gamma(t.g), display_gamma(t.b))
                    : glm::vec3(kNotReflecting);
            break;
          }
          default: break;
        }
      }
      float* p = &out.pixels[(std::size_t(y) * std::size_t(out.width) + std::size_t(x)) * 3];
      p[0] = c.r;
      p[1] = c.g;
      p[2] = c.b;
    }
  return out;
}

// A cube map's faces side by side (+X -X +Y -Y +Z -Z), encoded by display_gamma().
Image cube_strip(const CubeMap& cube) {
  Image out;
  out.width = cube.size * 6;
  out.height = cube.size;
  out.channels = 3;
  out.pixels.resize(std::size_t(out.width) * std::size_t(out.height) * 3);
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < cube.size; ++y)
      for (int x = 0; x < cube.size; ++x) {
        const glm::vec4 c = cube.at(CubeFace(f), x, y);
        float* p = &out.pixels[(std::size_t(y) * std::size_t(out.width) +
                                std::size_t(f * cube.size + x)) * 3];
        for (int k = 0; k < 3; ++k) p[k] = display_gamma(c[k]);
      }
  return out;
}

// A sphere map (row 0 at the top) as an image, encoded by display_gamma() like cube_strip().
Image sphere_image(const SphereMap& map) {
  Image out;
  out.width = out.height = map.size;
  out.channels = 3;
  out.pixels.resize(std::size_t(map.size) * std::size_t(map.size) * 3);
  for (std::size_t i = 0; i < map.texels.size(); ++i)
    for (int k = 0; k < 3; ++k)
      out.pixels[3 * i + std::size_t(k)] = display_gamma(map.texels[i][k]);
  return out;
}

// A one-channel image as grey RGB.
Image grey(const Image& one) {
  Image out;
  out.width = one.width;
  out.height = one.height;
  out.channels = 3;
  out.pixels.resize(one.pixels.size() * 3);
  for (std::size_t i = 0; i < one.pixels.size(); ++i)
    out.pixels[3 * i] = out.pixels[3 * i + 1] = out.pixels[3 * i + 2] = one.pixels[i];
  return out;
}

}  // namespace kaskad::editor
