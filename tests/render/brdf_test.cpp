// The shading BRDF in GL (content/shaders/brdf.glsl, brdf_evaluate()) against its CPU
// evaluation of the glTF 2.0 specification's Appendix B (components/brdf.h): 4,096 samples of
// normal, view and light directions (grazing ones included), base colour, metalness (0, 1 and
// between) and roughness (from the clamp to 1) are uploaded as a texture, a fragment shader
// evaluates the shipped GLSL function per pixel into an RGBA32F target, and every channel must
// agree within 1e-3 (relative above 1: GGX peaks reach 1e5 at low roughness).
#include "components/brdf.h"

#include <gtest/gtest.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "runtime/gpu/gl_handles.h"
#include "runtime/gpu/shader.h"
#include "tests/render/headless_gl.h"
#include "tests/test_tmp.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;

// Four texels per sample: (n, -), (v, roughness), (l, metallic), (base, -).
constexpr const char* kTestFrag = R"(#include "brdf.glsl"
layout(location = 0) out vec4 o;
layout(binding = 0) uniform sampler2D u_samples;

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 n = texelFetch(u_samples, ivec2(4 * p.x, p.y), 0);
  vec4 v = texelFetch(u_samples, ivec2(4 * p.x + 1, p.y), 0);
  vec4 l = texelFetch(u_samples, ivec2(4 * p.x + 2, p.y), 0);
  vec4 base = texelFetch(u_samples, ivec2(4 * p.x + 3, p.y), 0);
  o = vec4(brdf_evaluate(base.rgb, l.w, v.w, n.xyz, v.xyz, l.xyz), 1.0);
}
)";

constexpr int kSide = 64;  // kSide^2 samples

struct Sample {
  glm::vec3 n, v, l;
  BrdfInputs in;
};

/// A unit vector whose cosine with n is `cosine`, at a random azimuth.
glm::vec3 around(const glm::vec3& n, float cosine, float azimuth) {
  const glm::vec3 helper = std::abs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  const glm::vec3 t = glm::normalize(glm::cross(helper, n));
  const glm::vec3 b = glm::cross(n, t);
  const float sine = std::sqrt(std::max(0.0f, 1.0f - cosine * cosine));
  return glm::normalize(cosine * n + sine * (std::cos(azimuth) * t + std::sin(azimuth) * b));
}

std::vector<Sample> make_samples() {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float roughness[] = {0.0f, 0.03f, 0.05f, 0.1f, 0.25f, 0.5f, 0.75f, 1.0f};
  const float metallic[] = {0.0f, 1.0f, 0.5f, 0.2f};
  const float cosines[] = {1.0f, 0.9f, 0.5f, 0.1f, 0.01f};  // grazing included
  std::vector<Sample> samples(std::size_t(kSide) * kSide);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    Sample& s = samples[i];
    const float theta = std::acos(2.0f * u(rng) - 1.0f), phi = 2.0f * kPi * u(rng);
    s.n = glm::vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                    std::cos(theta));
    // Half the samples on the grids above, half random; a few lights below the surface.
    const bool grid = i % 2 == 0;
    const float cos_v = grid ? cosines[(i / 2) % 5] : u(rng);
    const float cos_l = grid ? cosines[(i / 10) % 5] : 1.1f * u(rng) - 0.1f;
    s.v = around(s.n, cos_v, 2.0f * kPi * u(rng));
    s.l = around(s.n, cos_l, 2.0f * kPi * u(rng));
    if (i % 7 == 3) s.l = glm::reflect(-s.v, s.n);  // on the specular peak
    s.in.roughness = grid ? roughness[(i / 50) % 8] : u(rng);
    s.in.metallic = grid ? metallic[(i / 400) % 4] : u(rng);
    s.in.base = glm::vec3(u(rng), u(rng), u(rng));
  }
  return samples;
}

class BrdfTest : public HeadlessGlTest {};

TEST_F(BrdfTest, GlslMatchesTheCpuEvaluationOfAppendixB) {
  const fs::path shaders = fs::path(KASKAD_CONTENT_DIR) / "shaders";
  const fs::path dir = testing_util::test_tmp();
  fs::create_directories(dir);
  for (const char* f : {"brdf.glsl", "fullscreen.vert"})
    fs::copy_file(shaders / f, dir / f, fs::copy_options::overwrite_existing);
  std::ofstream(dir / "test.frag") << kTestFrag;
  auto vs = gpu::preprocess_shader(dir, "fullscreen.vert", {});
  auto fs = gpu::preprocess_shader(dir, "test.frag", {});
  ASSERT_TRUE(vs.ok()) << vs.error().to_string();
  ASSERT_TRUE(fs.ok()) << fs.error().to_string();
  auto program = gpu::build_program(*vs, *fs);
  ASSERT_TRUE(program.ok()) << program.error().to_string();

  const std::vector<Sample> samples = make_samples();
  std::vector<float> texels;
  texels.reserve(samples.size() * 16);
  for (const Sample& s : samples) {
    for (float x : {s.n.x, s.n.y, s.n.z, 0.0f, s.v.x, s.v.y, s.v.z, s.in.roughness, s.l.x, s.l.y,
                    s.l.z, s.in.metallic, s.in.base.r, s.in.base.g, s.in.base.b, 0.0f})
      texels.push_back(x);
  }
  gpu::Texture input = gpu::make_texture(GL_TEXTURE_2D);
  glTextureStorage2D(input.id(), 1, GL_RGBA32F, 4 * kSide, kSide);
  glTextureSubImage2D(input.id(), 0, 0, 0, 4 * kSide, kSide, GL_RGBA, GL_FLOAT, texels.data());
  gpu::Texture target = gpu::make_texture(GL_TEXTURE_2D);
  glTextureStorage2D(target.id(), 1, GL_RGBA32F, kSide, kSide);
  gpu::Framebuffer fbo = gpu::make_framebuffer();
  glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT0, target.id(), 0);
  gpu::VertexArray vao = gpu::make_vertex_array();
  glBindFramebuffer(GL_FRAMEBUFFER, fbo.id());
  glViewport(0, 0, kSide, kSide);
  glDisable(GL_DEPTH_TEST);
  glUseProgram(program->id());
  glBindTextureUnit(0, input.id());
  glBindVertexArray(vao.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  std::vector<float> out(std::size_t(kSide) * kSide * 4);
  glGetTextureImage(target.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(out.size() * sizeof(float)),
                    out.data());
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glUseProgram(0);

  int compared = 0, bad = 0, peaks = 0, zeros = 0;
  float worst = 0.0f;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Sample& s = samples[i];
    const glm::vec3 want = brdf_evaluate(s.in, s.n, s.v, s.l);
    for (int c = 0; c < 3; ++c) {
      const float got = out[4 * i + std::size_t(c)];
      const float error = std::abs(got - want[c]) / std::max(1.0f, std::abs(want[c]));
      worst = std::max(worst, error);
      ++compared;
      if (!(error <= 1e-3f)) {
        if (++bad <= 10)
          ADD_FAILURE() << "sample " << i << " channel " << c << ": GLSL " << got << ", CPU "
                        << want[c] << " (roughness " << s.in.roughness << ", metallic "
                        << s.in.metallic << ", N.V " << glm::dot(s.n, s.v) << ", N.L "
                        << glm::dot(s.n, s.l) << ")";
      }
    }
    peaks += want.g > 10.0f;
    zeros += want == glm::vec3(0.0f);
  }
  std::printf("compared %d values, worst relative error %.3g\n", compared, double(worst));
  EXPECT_EQ(bad, 0);
  // The samples cover both lobes: some on sharp specular peaks, some lights below the surface.
  EXPECT_GT(peaks, 20);
  EXPECT_GT(zeros, 20);
}

}  // namespace
}  // namespace kaskad
