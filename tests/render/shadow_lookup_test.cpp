// The shadow lookup (content/shaders/shadow.glsl) in GL.
// 1. Its filter kernel, shadow_taps(), against the 3x3 PCF as first written (S4): nine
// nearest-filtered compares at constant texel offsets around the lookup point. shadow_taps() may
// compute the same box differently (four compare-gathers instead of nine taps); this
// pins that it is the same kernel. A random depth array is sampled at random points (inside
// texels away from their edges, where "the nearest texel" is unambiguous; some outside the map,
// where clamp-to-border compares as lit), random layers and random reference depths; both
// results are written per pixel and compared.
// 2. The forward pass without AOVs (the lookup skipped on surfaces facing away from the light)
// renders the same colour as with AOVs (the lookup everywhere).
#include <gtest/gtest.h>

#include <epoxy/gl.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "components/shadow_settings.h"
#include "runtime/app/player.h"
#include "runtime/gpu/gl_handles.h"
#include "runtime/gpu/shader.h"
#include "runtime/features/feature_manifest.h"
#include "tests/render/headless_gl.h"
#include "tests/render/player_fixture.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

// The test's fragment shader: o.x the production kernel, o.y the nine-tap reference.
// What both test fragment shaders start with: the production lookup, the output, the layer
// count and a hash for random points.
constexpr const char* kFragPrelude = R"(#include "common.glsl"
#include "features.glsl"
#include "shadow.glsl"

layout(location = 0) out vec4 o;
layout(location = 20) uniform int u_layers;

uint hash(uint x) {
  x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
  return x;
}
float rnd(inout uint s) { s = hash(s); return float(s >> 8) / 16777216.0; }
)";

const std::string kTestFrag = std::string(kFragPrelude) + R"(
float nine_taps(int layer, vec3 c) {
  vec4 tc = vec4(c.xy, float(layer), c.z);
  float sum = 0.0;
  sum += textureOffset(u_shadow_map, tc, ivec2(-1, -1));
  sum += textureOffset(u_shadow_map, tc, ivec2(0, -1));
  sum += textureOffset(u_shadow_map, tc, ivec2(1, -1));
  sum += textureOffset(u_shadow_map, tc, ivec2(-1, 0));
  sum += texture(u_shadow_map, tc);
  sum += textureOffset(u_shadow_map, tc, ivec2(1, 0));
  sum += textureOffset(u_shadow_map, tc, ivec2(-1, 1));
  sum += textureOffset(u_shadow_map, tc, ivec2(0, 1));
  sum += textureOffset(u_shadow_map, tc, ivec2(1, 1));
  return sum / 9.0;
}

void main() {
  uint s = uint(gl_FragCoord.x) + 4096u * uint(gl_FragCoord.y);
  float size = float(textureSize(u_shadow_map, 0).x);
  // A texel from -2 to size + 1 (outside the map too), a point inside it away from its edges.
  vec2 texel = floor(vec2(rnd(s), rnd(s)) * (size + 4.0)) - 2.0;
  vec2 inside = 0.05 + 0.9 * vec2(rnd(s), rnd(s));
  int layer = int(rnd(s) * float(u_layers));
  vec3 c = vec3((texel + inside) / size, rnd(s));
  o = vec4(shadow_taps(layer, c), nine_taps(layer, c), 0.0, 1.0);
}
)";

struct Format {
  const char* name;
  GLenum internal_format;
};
void PrintTo(const Format& f, std::ostream* os) { *os << f.name; }

class ShadowLookupTest : public HeadlessGlTest, public ::testing::WithParamInterface<Format> {};

// Draws `frag` (a test shader that writes o.x = the production kernel, o.y = its reference) over
// a kTarget^2 target with a random kSize^2 x kLayers depth array of `format` bound as the
// renderer binds its shadow map, and returns the target's RGBA floats. The shaders as shipped
// are copied, with the test's own, into a scratch folder `dir_name` (includes resolve there).
constexpr int kSize = 64, kLayers = 3, kTarget = 256;
std::vector<float> draw_lookup(const std::string& dir_name, const std::string& frag,
                               const std::vector<std::pair<const char*, int>>& features,
                               GLenum format) {
  const fs::path shaders = fs::path(KASKAD_CONTENT_DIR) / "shaders";
  const fs::path dir = testing_util::test_tmp(dir_name);
  fs::create_directories(dir);
  // The lookup's files: common.glsl, features.glsl, shadow.glsl and the filter files it includes.
  for (const auto& entry : fs::directory_iterator(shaders))
    if (entry.path().extension() == ".glsl")
      fs::copy_file(entry.path(), dir / entry.path().filename(),
                    fs::copy_options::overwrite_existing);
  fs::copy_file(shaders / "fullscreen.vert", dir / "fullscreen.vert",
                fs::copy_options::overwrite_existing);
  std::ofstream(dir / "test.frag") << frag;

  auto manifest = render::FeatureManifest::load(shaders / "features.json");
  EXPECT_TRUE(manifest.ok()) << manifest.error().to_string();
  if (!manifest.ok()) return {};
  render::VariantKey key;
  for (const auto& [name, value] : features) key = manifest->with(key, *manifest->find(name), value);
  auto vs = gpu::preprocess_shader(dir, "fullscreen.vert",
                                   manifest->defines(key, render::ShaderStage::vertex));
  auto fs = gpu::preprocess_shader(dir, "test.frag",
                                   manifest->defines(key, render::ShaderStage::fragment));
  EXPECT_TRUE(vs.ok() && fs.ok());
  if (!vs.ok() || !fs.ok()) return {};
  auto program = gpu::build_program(*vs, *fs);
  EXPECT_TRUE(program.ok()) << program.error().to_string();
  if (!program.ok()) return {};

  // A random depth array, set up as the renderer sets up its shadow map.
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> depth(0.0f, 1.0f);
  std::vector<float> depths(std::size_t(kSize) * kSize * kLayers);
  for (float& d : depths) d = depth(rng);
  gpu::Texture map = gpu::make_texture(GL_TEXTURE_2D_ARRAY);
  glTextureStorage3D(map.id(), 1, format, kSize, kSize, kLayers);
  glTextureSubImage3D(map.id(), 0, 0, 0, 0, kSize, kSize, kLayers, GL_DEPTH_COMPONENT, GL_FLOAT,
                      depths.data());
  glTextureParameteri(map.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
  glTextureParameteri(map.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
  const float border[4] = {1.0f, 1.0f, 1.0f, 1.0f};
  glTextureParameterfv(map.id(), GL_TEXTURE_BORDER_COLOR, border);
  glTextureParameteri(map.id(), GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glTextureParameteri(map.id(), GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  glTextureParameteri(map.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(map.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);

  gpu::Texture target = gpu::make_texture(GL_TEXTURE_2D);
  glTextureStorage2D(target.id(), 1, GL_RGBA32F, kTarget, kTarget);
  gpu::Framebuffer fbo = gpu::make_framebuffer();
  glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT0, target.id(), 0);
  gpu::VertexArray vao = gpu::make_vertex_array();
  glBindFramebuffer(GL_FRAMEBUFFER, fbo.id());
  glViewport(0, 0, kTarget, kTarget);
  glDisable(GL_DEPTH_TEST);
  glUseProgram(program->id());
  glProgramUniform1i(program->id(), 20, kLayers);
  glBindTextureUnit(2, map.id());
  glBindVertexArray(vao.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  std::vector<float> out(std::size_t(kTarget) * kTarget * 4);
  glGetTextureImage(target.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(out.size() * sizeof(float)),
                    out.data());
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glUseProgram(0);
  return out;
}

TEST_P(ShadowLookupTest, Pcf3x3IsTheNineNearestComparesAroundThePoint) {
  // One folder per format: ctest runs the instances in parallel.
  const std::vector<float> out =
      draw_lookup(std::string("shadow_lookup_") + GetParam().name, kTestFrag,
                  {{"shadow", 1}, {"shadow_filter", int(ShadowFilter::pcf3x3)}},
                  GetParam().internal_format);
  ASSERT_EQ(out.size(), std::size_t(kTarget) * kTarget * 4);
  int partial = 0, unequal = 0;
  float worst = 0.0f;
  for (std::size_t i = 0; i < out.size(); i += 4) {
    const float got = out[i], want = out[i + 1];
    const float diff = std::abs(got - want);
    if (diff > 1e-6f) ++unequal;
    worst = std::max(worst, diff);
    if (want > 0.05f && want < 0.95f) ++partial;
  }
  EXPECT_EQ(unequal, 0) << "largest difference " << worst;
  // The points exercise the kernel: most see a mix of lit and shadowed taps.
  EXPECT_GT(partial, kTarget * kTarget / 2);
}

INSTANTIATE_TEST_SUITE_P(Formats, ShadowLookupTest,
                         ::testing::Values(Format{"d16", GL_DEPTH_COMPONENT16},
                                           Format{"d24", GL_DEPTH_COMPONENT24},
                                           Format{"d32f", GL_DEPTH_COMPONENT32F}),
                         [](const auto& info) { return std::string(info.param.name); });


// The N x N boxes of pcf_kernel 5, 7, 9 (box_pcf(), compare-gathers) with a flat receiver plane
// are the N^2 nearest compares at the texel centres around the point's texel.
const std::string kBoxFrag = std::string(kFragPrelude) + R"(
float box_taps(int layer, vec3 c) {
  float size = float(textureSize(u_shadow_map, 0).x);
  vec2 t = floor(c.xy * size);
  const int h = (PCF_SIDE - 1) / 2;
  float sum = 0.0;
  for (int j = -h; j <= h; ++j)
    for (int i = -h; i <= h; ++i)
      sum += texture(u_shadow_map, vec4((t + vec2(i, j) + 0.5) / size, float(layer), c.z));
  return sum / float(PCF_SIDE * PCF_SIDE);
}

void main() {
  uint s = uint(gl_FragCoord.x) + 4096u * uint(gl_FragCoord.y);
  float size = float(textureSize(u_shadow_map, 0).x);
  vec2 texel = floor(vec2(rnd(s), rnd(s)) * (size + 4.0)) - 2.0;
  vec2 inside = 0.05 + 0.9 * vec2(rnd(s), rnd(s));
  int layer = int(rnd(s) * float(u_layers));
  vec3 c = vec3((texel + inside) / size, rnd(s));
  o = vec4(box_pcf(layer, c, vec2(0.0)), box_taps(layer, c), 0.0, 1.0);
}
)";

class BoxKernelTest : public HeadlessGlTest, public ::testing::WithParamInterface<int> {};

TEST_P(BoxKernelTest, IsTheNxNNearestComparesAroundThePoint) {
  const int side = 2 * GetParam() + 3;
  const std::vector<float> out =
      draw_lookup("box_kernel_" + std::to_string(side), kBoxFrag,
                  {{"shadow", 1},
                   {"shadow_filter", int(ShadowFilter::pcf3x3)},
                   {"shadow_kernel", GetParam()}},
                  GL_DEPTH_COMPONENT24);
  ASSERT_EQ(out.size(), std::size_t(kTarget) * kTarget * 4);
  int partial = 0, unequal = 0;
  float worst = 0.0f;
  for (std::size_t i = 0; i < out.size(); i += 4) {
    const float diff = std::abs(out[i] - out[i + 1]);
    if (diff > 1e-6f) ++unequal;
    worst = std::max(worst, diff);
    if (out[i + 1] > 0.05f && out[i + 1] < 0.95f) ++partial;
  }
  std::printf("[ %dx%d ] %d of %d points differ (largest %g)\n", side, side, unequal,
              kTarget * kTarget, double(worst));
  EXPECT_EQ(unequal, 0) << side << "x" << side << ": largest difference " << worst;
  EXPECT_GT(partial, kTarget * kTarget / 2);
}

INSTANTIATE_TEST_SUITE_P(Kernels, BoxKernelTest,
                         ::testing::Values(int(PcfKernel::k5x5), int(PcfKernel::k7x7),
                                           int(PcfKernel::k9x9)),
                         [](const auto& info) {
                           const int side = 2 * info.param + 3;
                           return std::to_string(side) + "x" + std::to_string(side);
                         });

// Without AOVs the forward pass skips the lookup where the geometric surface faces away from the
// shadowed light (forward.frag); with AOVs it looks up everywhere, as the AOV contract shows. The
// colour must not change: such surfaces get no direct light from it (no normal maps here).
// Directional (default, two suns) and spot (spot.json) lights.
class ForwardLookupTest : public PlayerTest {};

TEST_F(ForwardLookupTest, SkippingTheLookupOnSurfacesFacingAwayKeepsTheColour) {
  for (const char* name : {"default.json", "two_suns.json", "spot.json"}) {
    auto scene = load_scene(content_dir() / "scenes" / name, {});
    ASSERT_TRUE(scene.ok()) << scene.error().to_string();
    Image colour[2];
    for (int aovs = 0; aovs < 2; ++aovs) {
      RenderRun run;
      run.width = 320;
      run.height = 180;
      run.write_aovs = aovs == 1;
      auto t = render_frames(*player_, *scene, run);
      ASSERT_TRUE(t.ok()) << name << ": " << t.error().to_string();
      ASSERT_GT(t->last.stats.shadow_instances, 0) << name;
      colour[aovs] = player_->renderer->read_color();
    }
    ASSERT_EQ(colour[0].pixels.size(), colour[1].pixels.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < colour[0].pixels.size(); ++i)
      differ += colour[0].pixels[i] != colour[1].pixels[i];
    EXPECT_EQ(differ, 0u) << name << ": colour values differ with and without AOVs";
  }
}

}  // namespace
}  // namespace kaskad
