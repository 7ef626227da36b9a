// Shared declarations. Change together with FrameBlock in runtime/render/renderer.cpp.
#define MAX_LIGHTS 8
#define MAX_CASCADES 8
#define MAX_EXTRA_SHADOWS 3  // further shadowed directional lights (render::kMaxShadowedLights - 1)
#define LIGHT_DIRECTIONAL 0
#define LIGHT_SPOT 1
#define LIGHT_POINT 2

layout(std140, binding = 0) uniform FrameBlock {
  mat4 u_view_proj;
  mat4 u_view;
  vec4 u_camera_pos;               // xyz: world position
  vec4 u_ambient;                  // rgb: linear ambient radiance, w: exposure
  ivec4 u_counts;                  // x: light count, y: shadowed light index (-1: none),
                                   // z: cascade count, w: shadowed light the AOV shows (0 the
                                   // first, k extra light k - 1)
  vec4 u_shadow_params;            // x: normal offset (texels), y: blend band, z: map size
  mat4 u_cascade_view_proj[MAX_CASCADES];  // world -> shadow clip space per cascade
  vec4 u_cascade_splits[3];        // S0's D[0..8], four per vec4: cascade_split(i)
  vec4 u_cascade_texel[2];         // metres per texel per cascade: cascade_texel(i)
  vec4 u_light_color[MAX_LIGHTS];  // rgb: colour * intensity, w: type
  vec4 u_light_dir[MAX_LIGHTS];    // xyz: direction the light travels, w: range (0 = infinite)
  vec4 u_light_pos[MAX_LIGHTS];    // xyz: world position, w: cos(outer cone)
  vec4 u_light_cone[MAX_LIGHTS];   // x: cos(inner cone)
  // Further shadowed directional lights, each with its own cascades in the same texture array.
  ivec4 u_extra_count;                               // x: how many
  ivec4 u_extra_light[MAX_EXTRA_SHADOWS];            // x light index, y first layer, z cascades
  vec4 u_extra_params[MAX_EXTRA_SHADOWS];            // x normal offset, y blend band, z map size
  mat4 u_extra_view_proj[MAX_EXTRA_SHADOWS * MAX_CASCADES];  // [k * MAX_CASCADES + i]
  vec4 u_extra_splits[MAX_EXTRA_SHADOWS * 3];        // extra_split(k, i)
  vec4 u_extra_texel[MAX_EXTRA_SHADOWS * 2];         // extra_texel(k, i)
};

float cascade_split(int i) { return u_cascade_splits[i >> 2][i & 3]; }
float cascade_texel(int i) { return u_cascade_texel[i >> 2][i & 3]; }
float extra_split(int k, int i) { return u_extra_splits[k * 3 + (i >> 2)][i & 3]; }
float extra_texel(int k, int i) { return u_extra_texel[k * 2 + (i >> 2)][i & 3]; }

// Per-draw uniforms (explicit locations: no name look-ups at draw time).
layout(location = 0) uniform mat4 u_model;
layout(location = 4) uniform mat3 u_normal_matrix;
// Per-material uniforms (set when the material changes; draws are sorted by material).
layout(location = 8) uniform vec4 u_base_color;
layout(location = 9) uniform vec4 u_material;  // x metallic, y roughness, z normal scale, w alpha cutoff
layout(location = 10) uniform vec3 u_emissive;

layout(binding = 0) uniform sampler2D u_base_color_tex;
layout(binding = 1) uniform sampler2D u_normal_tex;
