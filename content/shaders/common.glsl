// Shared declarations. FrameBlock is FrameBlock in runtime/render/frame_uniforms.h (std140; its
// offsets are tested against this block). MAX_LIGHTS, MAX_CASCADES and MAX_SHADOW_VIEWS are
// defined in every program from components/limits.h (FeatureManifest::defines), and LIGHT_*
// (LightType's values) from runtime/features/shader_interface.h.

// One shadowed light's maps: its layers of the shadow map array (ShadowViewBlock).
struct ShadowView {
  mat4 view_proj[MAX_CASCADES];  // world -> shadow clip space per layer
  vec4 splits[3];                // S0's D[0..8], four per vec4: view_split(k, i)
  vec4 texel[2];                 // metres per texel per layer: view_texel(k, i)
  ivec4 info;                    // x light index, y first layer, z layer count
  vec4 params;                   // x normal offset (texels), y blend band, z paraboloid margin,
                                 // w the light's size along the map's y (soft.x: along x)
  vec4 soft;                     // x light size along the map's x (ShadowView::light_size),
                                 // y disc radius (texels), z taps,
                                 // w the lookup's reach in texels (ShadowView::filter_reach)
};

layout(std140, binding = 0) uniform FrameBlock {
  mat4 u_view_proj;
  mat4 u_view;
  vec4 u_camera_pos;                // xyz: world position, w: pixel footprint (FrameBlock)
  vec4 u_ambient;                   // rgb: linear ambient radiance
  vec4 u_environment;               // x environment intensity, y its last prefiltered level
  vec4 u_environment_sh[9];         // rgb: the environment map's SH coefficients
  vec4 u_frame;                     // x exposure, y shadow map size (texels a side), z lom layers,
                                    // w vsm_bleed_reduction
  ivec4 u_counts;                   // x lights, y shadow views, z the view the AOV shows,
                                    // w vsm_blur (texels a side)
  vec4 u_light_color[MAX_LIGHTS];   // rgb: colour * intensity
  ivec4 u_light_info[MAX_LIGHTS];   // x type (LIGHT_*), y its shadow view (-1: none)
  vec4 u_light_dir[MAX_LIGHTS];     // xyz: direction the light travels, w: range (0 = infinite)
  vec4 u_light_pos[MAX_LIGHTS];     // xyz: world position, w: cos(outer cone)
  vec4 u_light_cone[MAX_LIGHTS];    // x: cos(inner cone)
  ShadowView u_shadow_views[MAX_SHADOW_VIEWS];
  mat4 u_previous_view_proj;        // a reprojecting frame: the camera of the visibility it reads
  vec4 u_previous_camera_pos;       // xyz: that camera's world position
};

float view_split(int k, int i) { return u_shadow_views[k].splits[i >> 2][i & 3]; }
float view_texel(int k, int i) { return u_shadow_views[k].texel[i >> 2][i & 3]; }

// Per-material uniforms (set when the material changes; draws are sorted by material). Locations,
// attributes and texture units are defined from runtime/features/shader_interface.h.
layout(location = LOC_BASE_COLOR) uniform vec4 u_base_color;
layout(location = LOC_MATERIAL) uniform vec4 u_material;  // x metallic, y roughness, z normal scale, w alpha cutoff
layout(location = LOC_EMISSIVE) uniform vec3 u_emissive;

layout(binding = UNIT_BASE_COLOR) uniform sampler2D u_base_color_tex;
layout(binding = UNIT_NORMAL) uniform sampler2D u_normal_tex;
#if MATERIAL_HAS_OCCLUSION_TEXTURE
layout(location = LOC_MATERIAL_EXTRA) uniform vec4 u_material_extra;  // x occlusion strength
layout(binding = UNIT_OCCLUSION) uniform sampler2D u_occlusion_tex;   // linear, R channel
#endif
#if MATERIAL_HAS_EMISSIVE_TEXTURE
layout(binding = UNIT_EMISSIVE) uniform sampler2D u_emissive_tex;  // sRGB, times u_emissive
#endif
#if MATERIAL_HAS_METALLIC_ROUGHNESS_TEXTURE
// Linear: B times the metallic factor, G times the roughness factor (glTF 2.0, 3.9.2).
layout(binding = UNIT_METALLIC_ROUGHNESS) uniform sampler2D u_metallic_roughness_tex;
#endif


#ifdef VERTEX_STAGE_INSTANCED
// Per instance (InstanceRecord): the model matrix and its normal matrix.
layout(location = ATTR_MODEL) in mat4 a_model;
layout(location = ATTR_NORMAL_MATRIX) in mat3 a_normal_matrix;
#endif
