#include "runtime/render/draw_state.h"

#include <array>

#include <epoxy/gl.h>

#include "runtime/features/shader_interface.h"

namespace kaskad::render {

DrawState::DrawState(ShaderLibrary& shaders, GpuCache& cache, FrameStats& stats)
    : shaders_(shaders),
      cache_(cache),
      stats_(stats),
      features_by_uniform_(shaders.features_by_uniform()) {}

Status DrawState::use_program(Pass pass, VariantKey key) {
  auto prog = shaders_.program(pass, key);
  if (!prog) return prog.error();
  if (*prog != program_) {
    program_ = *prog;
    glUseProgram(program_.id());
    ++stats_.program_switches;
    material_ = nullptr;  // material uniforms are per program
  }
  return {};
}

void DrawState::bind_material(const DrawItem& d, VariantKey key) {
  const Material& m = d.material;
  // Über-programs read the feature bits from a uniform: equal materials differ by their keys.
  if (material_ && *material_ == m && (!features_by_uniform_ || material_key_ == key.material()))
    return;
  material_ = &m;
  material_key_ = key.material();
  ++stats_.material_switches;
  const glm::vec4 params(m.metallic, m.roughness, m.normal_scale, m.alpha_cutoff);
  glProgramUniform4fv(program_.id(), kLocBaseColor, 1, &m.base_color[0]);
  glProgramUniform4fv(program_.id(), kLocMaterial, 1, &params[0]);
  glProgramUniform3fv(program_.id(), kLocEmissive, 1, &m.emissive[0]);
  if (features_by_uniform_) glProgramUniform1ui(program_.id(), kLocFeatureBits, GLuint(key.material().bits()));
  glBindTextureUnit(kTexBaseColor, cache_.texture(m.base_color_texture, false).id());
  glBindTextureUnit(kTexNormal, cache_.texture(m.normal_texture, true).id());
  // The optional features' uniforms exist only in programs compiled with them (elsewhere their
  // location is an error or another uniform's): set them where `key` (the key the current
  // program was compiled for, as far as material features go) has the feature.
  const VariantKey features = key.material();
  if (features.has(VariantKey::kOcclusionTexture) || features_by_uniform_) {
    const glm::vec4 extra(m.occlusion_strength, 0.0f, 0.0f, 0.0f);
    glProgramUniform4fv(program_.id(), kLocMaterialExtra, 1, &extra[0]);
    glBindTextureUnit(kTexOcclusion, cache_.texture(m.occlusion_texture, false).id());
  }
  if (features.has(VariantKey::kEmissiveTexture) || features_by_uniform_)
    glBindTextureUnit(kTexEmissive, cache_.texture(m.emissive_texture, false).id());
  if (features.has(VariantKey::kMetallicRoughnessTexture) || features_by_uniform_)
    glBindTextureUnit(kTexMetallicRoughness,
                      cache_.texture(m.metallic_roughness_texture, false).id());
  if (features.has(VariantKey::kTextureTransform) || features_by_uniform_) {
    std::array<glm::vec4, 2 * kUvSlotCount> rows{};
    const TextureTransform* slots[kUvSlotCount] = {};
    slots[kUvSlotBaseColor] = &m.base_color_transform;
    slots[kUvSlotNormal] = &m.normal_transform;
    slots[kUvSlotOcclusion] = &m.occlusion_transform;
    slots[kUvSlotEmissive] = &m.emissive_transform;
    slots[kUvSlotMetallicRoughness] = &m.metallic_roughness_transform;
    for (int i = 0; i < kUvSlotCount; ++i) {
      const auto r = uv_transform_rows(*slots[i]);
      rows[std::size_t(2 * i)] = glm::vec4(r[0], float(slots[i]->tex_coord));
      rows[std::size_t(2 * i + 1)] = glm::vec4(r[1], 0.0f);
    }
    glProgramUniform4fv(program_.id(), kLocUvTransform, GLsizei(rows.size()), &rows[0][0]);
  }
}

bool DrawState::depth_reads_material(VariantKey key) const {
  // Blended draws are alpha-masked there (VariantKey::filtered_for()).
  return key.has(VariantKey::kAlphaMask) || key.has(VariantKey::kAlphaBlend) ||
         features_by_uniform_;
}

void draw_batch(const FrameInput& frame, GpuCache& cache, std::span<const MeshDraw> batch,
                int& calls, int& mesh_draws) {
  mesh_draws += int(batch.size());
  if (frame.multi_draw) {
    cache.draw_batch(batch);
    calls += batch.empty() ? 0 : 1;
    return;
  }
  for (const MeshDraw& d : batch) cache.draw_batch({&d, 1});
  calls += int(batch.size());
}

}  // namespace kaskad::render
