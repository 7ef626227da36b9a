// Forward shading: Blinn-Phong driven by glTF metallic-roughness inputs, linear lighting, sRGB
// output through the sRGB colour target. Features (content/shaders/features.json) are selected by
// the preprocessor only; see README.md in this folder.
#include "common.glsl"
#include "features.glsl"

in vec3 v_world_pos;
in vec3 v_world_normal;
in vec2 v_uv;

#if VARIANT_HAS_SHADOW
layout(binding = 2) uniform sampler2DArrayShadow u_shadow_map;  // one layer per cascade
#endif

layout(location = 0) out vec4 o_color;
#if VARIANT_HAS_AOVS
layout(location = 1) out vec4 o_position;    // xyz world position, w mask (1 = geometry)
layout(location = 2) out vec4 o_normal;      // xyz world normal facing the camera, w view depth
layout(location = 3) out vec2 o_visibility;  // x shadow visibility of the shadowed light,
                                             // y its cascade (-1 outside every cascade)
#endif

// Cotangent frame from screen-space derivatives: normal mapping without stored tangents.
vec3 perturb_normal(vec3 n, vec3 p, vec2 uv, vec3 tangent_normal) {
  vec3 dp1 = dFdx(p), dp2 = dFdy(p);
  vec2 duv1 = dFdx(uv), duv2 = dFdy(uv);
  vec3 dp2perp = cross(dp2, n), dp1perp = cross(n, dp1);
  vec3 t = dp2perp * duv1.x + dp1perp * duv2.x;
  vec3 b = dp2perp * duv1.y + dp1perp * duv2.y;
  float det = max(dot(t, t), dot(b, b));
  if (det < 1e-20) return n;  // degenerate uvs: keep the geometric normal
  float inv = inversesqrt(det);
  return normalize(mat3(t * inv, b * inv, n) * tangent_normal);
}

// Visibility of the shadowed light at world position p with geometric normal n: 1 lit, 0
// shadowed (S4, with S0's cascades). Clamp-to-border with border depth 1 and the z > 1 test keep
// everything outside a cascade's light frustum lit. Cascade selection and blending mirror
// select_cascade_by_depth / select_cascade_by_map / cascade_blend_weight* in
// systems/cascade_math.h (change together).
#if VARIANT_HAS_SHADOW
#define CASCADES VARIANT_CASCADE_COUNT

// One cascade's lookup. The point moves along the normal by normal_offset texels of this
// cascade (MJP's normal offset), so the bias follows each cascade's resolution.
float cascade_visibility(int cascade, vec3 p, vec3 n) {
  vec3 q = p + n * (u_shadow_params.x * cascade_texel(cascade));
  vec4 clip = u_cascade_view_proj[cascade] * vec4(q, 1.0);
  vec3 c = clip.xyz / clip.w * 0.5 + 0.5;  // S0's M_bias
  if (c.z > 1.0) return 1.0;
  vec4 tc = vec4(c.xy, float(cascade), c.z);
#if VARIANT_SHADOW_FILTER == VARIANT_SHADOW_FILTER_PCF3X3
  // textureOffset needs constant offsets: the 3x3 kernel is written out.
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
#else
  return texture(u_shadow_map, tc);  // filtering (nearest / linear) is set on the texture
#endif
}

#if VARIANT_CASCADE_SELECTION == VARIANT_CASCADE_SELECTION_MAP_BOUNDS
// Border kept free in NDC: the PCF kernel's reach plus the normal offset, in texels.
float map_border() { return 2.0 * (1.5 + u_shadow_params.x) / u_shadow_params.z; }
#endif

// The cascade of a point, -1 outside all. depth: view depth |z_view|.
int select_cascade(vec3 p, float depth) {
#if VARIANT_CASCADE_SELECTION == VARIANT_CASCADE_SELECTION_MAP_BOUNDS
  float limit = 1.0 - map_border();
  for (int i = 0; i < CASCADES; ++i) {
    vec4 clip = u_cascade_view_proj[i] * vec4(p, 1.0);
    vec3 ndc = clip.xyz / clip.w;
    if (abs(ndc.x) <= limit && abs(ndc.y) <= limit && abs(ndc.z) <= 1.0) return i;
  }
  return -1;
#else
  // S0: D[i] <= depth < D[i+1]; nearer than D[0] (the camera near plane) counts as cascade 0.
  if (depth >= cascade_split(CASCADES)) return -1;
  int cascade = 0;
  for (int i = 1; i < CASCADES; ++i)
    if (depth >= cascade_split(i)) cascade = i;
  return cascade;
#endif
}

// Weight of cascade + 1 in the blend band at the end of `cascade` (0 for the last one).
float blend_weight(int cascade, vec3 p, float depth) {
#if CASCADES > 1
  float band = u_shadow_params.y;
  if (cascade >= CASCADES - 1 || band <= 0.0) return 0.0;
#if VARIANT_CASCADE_SELECTION == VARIANT_CASCADE_SELECTION_MAP_BOUNDS
  vec4 clip = u_cascade_view_proj[cascade] * vec4(p, 1.0);
  vec2 ndc = abs(clip.xy / clip.w);
  float edge = 1.0 - map_border();
  return clamp((max(ndc.x, ndc.y) - (edge - band * edge)) / (band * edge), 0.0, 1.0);
#else
  float d0 = cascade_split(cascade), d1 = cascade_split(cascade + 1);
  float width = band * (d1 - d0);
  return clamp((depth - (d1 - width)) / width, 0.0, 1.0);
#endif
#else
  return 0.0;
#endif
}

float shadow_visibility(vec3 p, vec3 n, float depth, out int cascade) {
  cascade = select_cascade(p, depth);
  if (cascade < 0) return 1.0;
  float v = cascade_visibility(cascade, p, n);
  float w = blend_weight(cascade, p, depth);
  if (w > 0.0) v = mix(v, cascade_visibility(cascade + 1, p, n), w);
  return v;
}

#if VARIANT_DEBUG_CASCADES
// Tints per cascade: red, green, blue, yellow, magenta, cyan, orange, violet.
vec3 cascade_tint(int cascade) {
  const vec3 tints[8] = vec3[8](vec3(1.0, 0.35, 0.35), vec3(0.35, 1.0, 0.35), vec3(0.4, 0.5, 1.0),
                                vec3(1.0, 1.0, 0.3), vec3(1.0, 0.35, 1.0), vec3(0.3, 1.0, 1.0),
                                vec3(1.0, 0.65, 0.25), vec3(0.65, 0.4, 1.0));
  return cascade < 0 ? vec3(1.0) : tints[cascade];
}
#endif
#endif

void main() {
  vec4 base = u_base_color;
#if MATERIAL_HAS_BASE_COLOR_TEXTURE
  if (ENABLED(BIT_BASE_COLOR_TEXTURE)) base *= texture(u_base_color_tex, v_uv);
#endif
#if MATERIAL_HAS_ALPHA_MASK
  if (ENABLED(BIT_ALPHA_MASK) && base.a < u_material.w) discard;
#endif
  vec3 view_vec = u_camera_pos.xyz - v_world_pos;
  vec3 v = normalize(view_vec);
  vec3 geometric_n = normalize(v_world_normal);
  if (dot(geometric_n, v) < 0.0) geometric_n = -geometric_n;  // back faces face the camera
  vec3 n = geometric_n;
#if MATERIAL_HAS_NORMAL_MAP
  if (ENABLED(BIT_NORMAL_MAP)) {
    vec3 tn = texture(u_normal_tex, v_uv).xyz * 2.0 - 1.0;
    tn.xy *= u_material.z;
    n = perturb_normal(n, v_world_pos, v_uv, normalize(tn));
  }
#endif

  float metallic = clamp(u_material.x, 0.0, 1.0);
  float roughness = clamp(u_material.y, 0.03, 1.0);
  vec3 diffuse_color = base.rgb * (1.0 - metallic);
  vec3 f0 = mix(vec3(0.04), base.rgb, metallic);
  // Blinn-Phong exponent from roughness (alpha = roughness^2, n = 2 / alpha^2 - 2), energy-normalised.
  float alpha = roughness * roughness;
  float shininess = max(2.0 / (alpha * alpha) - 2.0, 1.0);
  float spec_norm = (shininess + 8.0) / 8.0;

  float visibility = 1.0;
  int cascade = -1;
  float view_depth = -(u_view * vec4(v_world_pos, 1.0)).z;
#if VARIANT_HAS_SHADOW && MATERIAL_RECEIVES_SHADOWS
  if (ENABLED(BIT_RECEIVE_SHADOWS))
    visibility = shadow_visibility(v_world_pos, geometric_n, view_depth, cascade);
#endif

  vec3 color = u_ambient.rgb * diffuse_color;
#if MATERIAL_HAS_EMISSIVE
  if (ENABLED(BIT_EMISSIVE)) color += u_emissive;
#endif
  for (int i = 0; i < u_counts.x; ++i) {
    int type = int(u_light_color[i].w);
    vec3 l;
    float attenuation = 1.0;
    if (type == LIGHT_DIRECTIONAL) {
      l = -normalize(u_light_dir[i].xyz);
    } else {
      vec3 to_light = u_light_pos[i].xyz - v_world_pos;
      float d2 = max(dot(to_light, to_light), 1e-8);
      l = to_light * inversesqrt(d2);
      attenuation = 1.0 / d2;
      float range = u_light_dir[i].w;
      if (range > 0.0) {  // KHR_lights_punctual's recommended smooth window
        float r = d2 / (range * range);
        attenuation *= clamp(1.0 - r * r, 0.0, 1.0);
      }
      if (type == LIGHT_SPOT) {
        float cd = dot(-l, normalize(u_light_dir[i].xyz));
        attenuation *= smoothstep(u_light_pos[i].w, u_light_cone[i].x, cd);
      }
    }
    float ndl = max(dot(n, l), 0.0);
    if (ndl <= 0.0) continue;
    vec3 h = normalize(l + v);
    vec3 spec = f0 * spec_norm * pow(max(dot(n, h), 0.0), shininess);
    float shadow = (i == u_counts.y) ? visibility : 1.0;
    color += (diffuse_color + spec) * u_light_color[i].rgb * ndl * attenuation * shadow;
  }

#if VARIANT_HAS_SHADOW && VARIANT_DEBUG_CASCADES
  color *= cascade_tint(cascade);
#endif
  o_color = vec4(color * u_ambient.w, 1.0);
#if VARIANT_HAS_AOVS
  o_position = vec4(v_world_pos, 1.0);
  o_normal = vec4(geometric_n, view_depth);
  o_visibility = vec2(visibility, float(cascade));
#endif
}
