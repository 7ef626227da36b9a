// The fixed interface between the renderer and the shaders, defined once: vertex attribute
// locations, uniform locations and texture units, and the per-instance record. The shader
// library defines each as a macro in every program (FeatureManifest::defines: ATTR_*, LOC_*,
// UNIT_*), so content/shaders/ write `layout(location = LOC_BASE_COLOR)` and never a number.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>

#include <glm/glm.hpp>

#include "components/light.h"

namespace kaskad::render {

// Vertex attributes: per vertex (a mesh's streams), then per instance (InstanceRecord).
inline constexpr unsigned kAttrPosition = 0, kAttrNormal = 1, kAttrUv = 2;
inline constexpr unsigned kAttrModel = 3;         ///< mat4: locations 3..6
inline constexpr unsigned kAttrNormalMatrix = 7;  ///< mat3: locations 7..9
inline constexpr unsigned kAttrLayer = 10;        ///< uint: the layered shadow pass's layer
/// vec4 per vertex: tangent xyz and bitangent sign w (glTF TANGENT, or generate_tangents()).
inline constexpr unsigned kAttrTangent = 11;
/// vec2 per vertex: the second uv set (MeshData::uv_set(1)), read by texture_transform programs.
inline constexpr unsigned kAttrUv1 = 12;

/// One vertex of the GPU cache's shared geometry (runtime/render/gpu_cache.h): the vertex
/// arrays read it by attribute, and the deform pass (deform.comp) as floats, at the offsets
/// below (VERTEX_* defines).
struct Vertex {
  glm::vec3 position{0.0f}, normal{0.0f};
  glm::vec2 uv{0.0f};
  glm::vec4 tangent{0.0f};
  glm::vec2 uv1{0.0f};
};
static_assert(sizeof(Vertex) == 56);
inline constexpr int kVertexFloats = int(sizeof(Vertex) / sizeof(float));
inline constexpr int kVertexPosition = int(offsetof(Vertex, position) / sizeof(float)),
                     kVertexNormal = int(offsetof(Vertex, normal) / sizeof(float)),
                     kVertexTangent = int(offsetof(Vertex, tangent) / sizeof(float));

/// The deform pass's shader storage bindings: the shared vertices (read and written), a source
/// mesh's joints, weights and morph displacements, the frame's skin matrices and morph weights.
inline constexpr int kBufVertices = 0, kBufJoints = 1, kBufJointWeights = 2, kBufMorphDeltas = 3,
                     kBufSkinMatrices = 4, kBufMorphWeights = 5;
/// The deform pass's uniforms: ivec4 (source base vertex, posed base vertex, vertex count,
/// first skin matrix) and ivec4 (first morph weight, morph targets, 0, 0).
inline constexpr int kLocDeformJob = 0, kLocDeformMorph = 1;
/// Floats per vertex and morph target in the displacement buffer: position, normal, tangent.
inline constexpr int kMorphDeltaFloats = 9;

/// One drawn instance, read by the vertex shaders through instanced attributes (divisor 1) from
/// the frame's instance buffer: the model matrix, its normal matrix (columns, w unused) and,
/// for the layered shadow pass, the layer of its view it goes to.
struct InstanceRecord {
  glm::mat4 model{1.0f};
  glm::vec4 normal_matrix[3]{};
  glm::uvec4 layer{0u};
};
static_assert(sizeof(InstanceRecord) == 128);

// Uniform locations (no name look-ups at draw time). Per-program ones may share a number when no
// program has both: the layered depth pass (13, 14, 16..), the points pass (13), reflections
// (16..19), the LOM occlusion pass (20: ivec4 view, layer of the view, peel, count overflow),
// the VSM moments pass (20: ivec4 view, layer of the view, step (0 depth to moments along x,
// 1 along y), blur side in texels; 21: ivec4 the layer's texels with valid depth, x0 y0 x1 y1,
// ends exclusive).
inline constexpr int kLocBaseColor = 8, kLocMaterial = 9, kLocEmissive = 10,
                     kLocFeatureBits = 11, kLocLightViewProj = 12, kLocTargetSize = 13,
                     kLocLayerBase = 14, kLocLayerViewProj = 16,
                     kLocReflection = 16, kLocReflectionBoxMin = 17, kLocReflectionBoxMax = 18,
                     kLocReflectionCentre = 19, kLocLomTarget = 20,
                     kLocVsmTarget = 20, kLocVsmRect = 21;
/// vec4: x occlusion strength (MATERIAL_HAS_OCCLUSION_TEXTURE).
inline constexpr int kLocMaterialExtra = 24;
/// vec4[10]: per texture slot (kUvSlot*) two rows (a, b, c) of its uv transform
/// u' = a.x u + a.y v + a.z, v' = b.x u + b.y v + b.z (MATERIAL_HAS_TEXTURE_TRANSFORM); 25..34.
/// a.w is the uv set the slot reads (TextureTransform::tex_coord: 0 or 1).
inline constexpr int kLocUvTransform = 25;
/// Texture slots in kLocUvTransform's array.
inline constexpr int kUvSlotBaseColor = 0, kUvSlotNormal = 1, kUvSlotOcclusion = 2,
                     kUvSlotEmissive = 3, kUvSlotMetallicRoughness = 4, kUvSlotCount = 5;

// Texture units.
/// kTexShadowDepth: the shadow map again, through a sampler without depth compare (raw depths for
/// PCSS's blocker search); kTexShadowLinear: again, compared with linear filtering (each tap of
/// the disc kernels a hardware 2x2 PCF). ShadowMapPass::bind() binds all three.
/// kTexLomDepth / kTexLomOcclusion: S1's layered depth map (signed depths, LomPass) and its
/// occlusion factors; kTexPeelPrevious: the layer before the one a depth peel draws.
/// kTexVsmMoments: the blurred, mipmapped moments of vsm/evsm (MomentsPass); kTexVsmSource: the
/// moments blurred along x, read by the blur along y.
/// kTexDfg, kTexSh, kTexEnvironment: image-based lighting (IblMaps): the split-sum table, the
/// rows of SH coefficients, the environment map's prefiltered cube.
/// kTexCachedVisibility: the main view's stored shadow visibility (VARIANT_SHADOW_REUSE load).
inline constexpr unsigned kTexBaseColor = 0, kTexNormal = 1, kTexShadow = 2,
                          kTexReflectionCube = 3, kTexReflectionSphere = 4, kTexShadowDepth = 5,
                          kTexShadowLinear = 6, kTexOcclusion = 7, kTexEmissive = 8,
                          kTexLomDepth = 9, kTexLomOcclusion = 10, kTexPeelPrevious = 11,
                          kTexVsmMoments = 12, kTexVsmSource = 13, kTexDfg = 14, kTexSh = 15,
                          kTexEnvironment = 16, kTexMetallicRoughness = 17,
                          kTexCachedVisibility = 18;

/// Every name above as the shaders see it (ATTR_POSITION, LOC_BASE_COLOR, UNIT_SHADOW, ...), and
/// the light types (LIGHT_DIRECTIONAL, ...: u_light_info[i].x holds a LightType).
inline std::array<std::pair<const char*, int>, 67> shader_interface_defines() {
  return {{{"LIGHT_DIRECTIONAL", int(LightType::directional)},
           {"VERTEX_FLOATS", kVertexFloats},
           {"VERTEX_POSITION", kVertexPosition},
           {"VERTEX_NORMAL", kVertexNormal},
           {"VERTEX_TANGENT", kVertexTangent},
           {"BUF_VERTICES", kBufVertices},
           {"BUF_JOINTS", kBufJoints},
           {"BUF_JOINT_WEIGHTS", kBufJointWeights},
           {"BUF_MORPH_DELTAS", kBufMorphDeltas},
           {"BUF_SKIN_MATRICES", kBufSkinMatrices},
           {"BUF_MORPH_WEIGHTS", kBufMorphWeights},
           {"LOC_DEFORM_JOB", kLocDeformJob},
           {"LOC_DEFORM_MORPH", kLocDeformMorph},
           {"MORPH_DELTA_FLOATS", kMorphDeltaFloats},
           {"LIGHT_SPOT", int(LightType::spot)},
           {"LIGHT_POINT", int(LightType::point)},
           {"LIGHT_AREA", int(LightType::area)},
           {"ATTR_POSITION", kAttrPosition},
           {"ATTR_NORMAL", kAttrNormal},
           {"ATTR_UV", kAttrUv},
           {"ATTR_MODEL", kAttrModel},
           {"ATTR_NORMAL_MATRIX", kAttrNormalMatrix},
           {"ATTR_LAYER", kAttrLayer},
           {"ATTR_TANGENT", kAttrTangent},
           {"ATTR_UV1", kAttrUv1},
           {"LOC_BASE_COLOR", kLocBaseColor},
           {"LOC_MATERIAL", kLocMaterial},
           {"LOC_EMISSIVE", kLocEmissive},
           {"LOC_FEATURE_BITS", kLocFeatureBits},
           {"LOC_LIGHT_VIEW_PROJ", kLocLightViewProj},
           {"LOC_TARGET_SIZE", kLocTargetSize},
           {"LOC_LAYER_BASE", kLocLayerBase},
           {"LOC_LAYER_VIEW_PROJ", kLocLayerViewProj},
           {"LOC_REFLECTION", kLocReflection},
           {"LOC_REFLECTION_BOX_MIN", kLocReflectionBoxMin},
           {"LOC_REFLECTION_BOX_MAX", kLocReflectionBoxMax},
           {"LOC_REFLECTION_CENTRE", kLocReflectionCentre},
           {"LOC_LOM_TARGET", kLocLomTarget},
           {"LOC_VSM_TARGET", kLocVsmTarget},
           {"LOC_VSM_RECT", kLocVsmRect},
           {"LOC_MATERIAL_EXTRA", kLocMaterialExtra},
           {"LOC_UV_TRANSFORM", kLocUvTransform},
           {"UV_SLOT_BASE_COLOR", kUvSlotBaseColor},
           {"UV_SLOT_NORMAL", kUvSlotNormal},
           {"UV_SLOT_OCCLUSION", kUvSlotOcclusion},
           {"UV_SLOT_EMISSIVE", kUvSlotEmissive},
           {"UV_SLOT_METALLIC_ROUGHNESS", kUvSlotMetallicRoughness},
           {"UV_SLOT_COUNT", kUvSlotCount},
           {"UNIT_BASE_COLOR", int(kTexBaseColor)},
           {"UNIT_NORMAL", int(kTexNormal)},
           {"UNIT_SHADOW", int(kTexShadow)},
           {"UNIT_SHADOW_DEPTH", int(kTexShadowDepth)},
           {"UNIT_SHADOW_LINEAR", int(kTexShadowLinear)},
           {"UNIT_LOM_DEPTH", int(kTexLomDepth)},
           {"UNIT_LOM_OCCLUSION", int(kTexLomOcclusion)},
           {"UNIT_PEEL_PREVIOUS", int(kTexPeelPrevious)},
           {"UNIT_VSM_MOMENTS", int(kTexVsmMoments)},
           {"UNIT_VSM_SOURCE", int(kTexVsmSource)},
           {"UNIT_REFLECTION_CUBE", int(kTexReflectionCube)},
           {"UNIT_REFLECTION_SPHERE", int(kTexReflectionSphere)},
           {"UNIT_OCCLUSION", int(kTexOcclusion)},
           {"UNIT_EMISSIVE", int(kTexEmissive)},
           {"UNIT_DFG", int(kTexDfg)},
           {"UNIT_SH", int(kTexSh)},
           {"UNIT_ENVIRONMENT", int(kTexEnvironment)},
           {"UNIT_METALLIC_ROUGHNESS", int(kTexMetallicRoughness)},
           {"UNIT_CACHED_VISIBILITY", int(kTexCachedVisibility)}}};
}

}  // namespace kaskad::render
