// Forward shading: the glTF 2.0 metallic-roughness BRDF (brdf.glsl, the specification's Appendix
// B), linear lighting, sRGB output through the sRGB colour target. A light's colour is the
// illuminance it delivers (outgoing radiance = f * E * N.L; components/brdf.h). Light from the
// surroundings (ibl.glsl, components/ibl.h) is the environment map (VARIANT_ENVIRONMENT map),
// else u_ambient as a uniform radiance, or a pbr reflector's probe. Features
// (content/shaders/features.json) are selected by the preprocessor only; see content/shaders/README.md.
#include "brdf.glsl"
#include "common.glsl"
#include "features.glsl"
#include "ibl.glsl"
#include "shadow.glsl"
#include "tone_mapping.glsl"

in vec3 v_world_pos;
in vec3 v_world_normal;
in vec2 v_uv;
#if MATERIAL_HAS_NORMAL_MAP
in vec4 v_world_tangent;  // xyz tangent, w bitangent sign (zero without uvs)
#endif

layout(location = 0) out vec4 o_color;
#if VARIANT_HAS_AOVS
layout(location = 1) out vec4 o_position;    // xyz world position, w mask (1 = geometry)
layout(location = 2) out vec4 o_normal;      // xyz world normal (reversed on back faces), w view depth
layout(location = 3) out vec2 o_visibility;  // x shadow visibility of the shadow view
                                             // u_counts.z names (the first by default),
                                             // y its cascade (-1 outside every cascade)
layout(location = 4) out vec4 o_reflection;  // rgb reflected colour C_t, a 1 with a map (else 0)
#endif

// render.visibility_cache (Renderer::render()): a frame that stores writes each pixel's shadow
// visibility per shadow view; a frame that sees what the frame before saw reads it back, so the
// pixel that ends up in front reads its own value and the image is the same, bit for bit. With
// one shadow view, a frame whose camera alone moved reprojects it (reprojected_visibility()).
// Stored per pixel: channel k the visibility of view k (-1 where the surface faces away from its
// light: visibility 0, no lookup); with one view, channel 1 the reprojection code: the distance
// from the camera to the surface's plane where the visibility is 1, minus it where 0, and 0
// elsewhere (partly lit, or facing away). Points of one plane share that distance, so a
// neighbour across a crease or a silhouette does not pass for the surface.
#define SHADOW_REUSE (VARIANT_HAS_SHADOW && MATERIAL_RECEIVES_SHADOWS && !VARIANT_HAS_AOVS)
#define SHADOW_REUSE_IS(mode) (SHADOW_REUSE && VARIANT_SHADOW_REUSE == VARIANT_SHADOW_REUSE_##mode)
#define SHADOW_STORES (SHADOW_REUSE_IS(STORE) || SHADOW_REUSE_IS(REPROJECT))
#if SHADOW_STORES
layout(location = 1) out vec4 o_cached_visibility;
#endif
#if SHADOW_REUSE_IS(LOAD) || SHADOW_REUSE_IS(REPROJECT)
layout(binding = UNIT_CACHED_VISIBILITY) uniform sampler2D u_cached_visibility;
#endif

#if SHADOW_STORES
// The distance from camera position c to the plane through p facing n, the surface's side of it
// (the camera sees the side its geometric normal faces: positive).
float plane_distance(vec3 p, vec3 n, vec3 c) { return dot(n, c - p); }
#endif

#if SHADOW_REUSE_IS(REPROJECT)
// The visibility stored under the previous camera around world point p (geometric normal n),
// when the four stored pixels around where that camera saw p all show this surface (their
// planes' distances from that camera within `tolerance` of p's) and agree on 1 or on 0: inside a lit area or a shadow. -1 otherwise
// (a shadow edge, a surface newly in view, a silhouette): the frame's second forward pass looks
// such pixels up (ForwardPass::record()).
float reprojected_visibility(vec3 p, vec3 n, float tolerance) {
#if SHADOW_VIEWS == 1
  const vec4 clip = u_previous_view_proj * vec4(p, 1.0);
  if (clip.w <= 0.0) return -1.0;
  const vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
  const vec2 size = vec2(textureSize(u_cached_visibility, 0));
  if (any(lessThan(uv * size, vec2(0.5))) || any(greaterThan(uv * size, size - 0.5))) return -1.0;
  const vec4 code = textureGather(u_cached_visibility, uv, 1);
  const float expected = plane_distance(p, n, u_previous_camera_pos.xyz);
  const vec4 off = abs(abs(code) - expected);
  if (max(max(off.x, off.y), max(off.z, off.w)) > tolerance) return -1.0;
  if (all(greaterThan(code, vec4(0.0)))) return 1.0;
  if (all(lessThan(code, vec4(0.0)))) return 0.0;
#endif
  return -1.0;
}
#endif

#if VARIANT_ENVIRONMENT == VARIANT_ENVIRONMENT_MAP
// render.environment prefiltered by roughness (IblMaps): level k holds roughness k / u_environment.y.
layout(binding = UNIT_ENVIRONMENT) uniform samplerCube u_environment_cube;
#endif

// Reflection maps (S3). The probe's map and x = k_s * p_r (eq. (3)) are set per draw. The pbr
// model (MATERIAL_HAS_REFLECTION_PBR) gets the probe's prefiltered cube instead, and x = p_r,
// y its SH row, z its last level.
#if MATERIAL_HAS_REFLECTION_CUBE || MATERIAL_HAS_REFLECTION_SPHERE
layout(location = LOC_REFLECTION) uniform vec4 u_reflection;
#endif
#if MATERIAL_HAS_REFLECTION_CUBE
layout(binding = UNIT_REFLECTION_CUBE) uniform samplerCube u_reflection_cube;
#endif
#if MATERIAL_HAS_REFLECTION_BOX
layout(location = LOC_REFLECTION_BOX_MIN) uniform vec4 u_reflection_box_min;  // xyz: world-space box (Reflector)
layout(location = LOC_REFLECTION_BOX_MAX) uniform vec4 u_reflection_box_max;
layout(location = LOC_REFLECTION_CENTRE) uniform vec4 u_reflection_centre;   // xyz: the probe's capture centre

// Box projection (parallax correction, beyond S3): the environment is taken to lie on the box,
// so look up the direction from the capture centre to where the ray (p, r) leaves the box.
vec3 box_project(vec3 p, vec3 r) {
  vec3 exits = max((u_reflection_box_max.xyz - p) / r, (u_reflection_box_min.xyz - p) / r);
  float t = max(min(min(exits.x, exits.y), exits.z), 0.0);
  return p + t * r - u_reflection_centre.xyz;
}
#endif
#if MATERIAL_HAS_REFLECTION_SPHERE
layout(binding = UNIT_REFLECTION_SPHERE) uniform sampler2D u_reflection_sphere;  // made for this camera (probe_sphere.frag)
#endif

// Cotangent frame from screen-space derivatives: normal mapping where the vertex has no tangent.
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


void main() {
  vec4 base = u_base_color;
#if MATERIAL_HAS_BASE_COLOR_TEXTURE
  if (ENABLED(BIT_BASE_COLOR_TEXTURE))
    base *= texture(u_base_color_tex, slot_uv(UV_SLOT_BASE_COLOR, v_uv));
#endif
  float coverage = 1.0;  // o_color's alpha: 1, or a cut-out's coverage under alpha to coverage
#if MATERIAL_HAS_ALPHA_MASK && VARIANT_ALPHA_TO_COVERAGE
  // The multisampled colour pass (render.msaa > 1): alpha sharpened around the cutoff to about
  // one pixel's width, which GL_SAMPLE_ALPHA_TO_COVERAGE turns into covered samples, so the
  // cut-out's edge is anti-aliased like a triangle's (Golus, "Anti-aliased Alpha Test", 2017).
  if (ENABLED(BIT_ALPHA_MASK))
    coverage = clamp((base.a - u_material.w) / max(fwidth(base.a), 1e-4) + 0.5, 0.0, 1.0);
#elif MATERIAL_HAS_ALPHA_MASK
  if (ENABLED(BIT_ALPHA_MASK) && base.a < u_material.w) discard;
#endif
  vec3 view_vec = u_camera_pos.xyz - v_world_pos;
  vec3 v = normalize(view_vec);
  // The interpolated normal, reversed on back faces: only double-sided materials show those
  // (the renderer culls the others, with the winding of mirrored transforms reversed). Never
  // flipped by the view direction: a smooth normal may face slightly away from the camera at a
  // silhouette or ridge, and flipping it there shaded the surface from below (dark specks).
  vec3 geometric_n = normalize(v_world_normal);
  if (!gl_FrontFacing) geometric_n = -geometric_n;
  vec3 n = geometric_n;
#if MATERIAL_HAS_NORMAL_MAP
  if (ENABLED(BIT_NORMAL_MAP)) {
    // The cotangent frame follows the normal map's own (transformed) uvs.
    vec2 normal_uv = slot_uv(UV_SLOT_NORMAL, v_uv);
    vec3 tn = texture(u_normal_tex, normal_uv).xyz * 2.0 - 1.0;
    tn.xy *= u_material.z;
    if (dot(v_world_tangent.xyz, v_world_tangent.xyz) > 1e-12) {
      // MikkTSpace's per-pixel rule: the interpolated normal and tangent (unit at the vertices,
      // not normalised again), the bitangent sign * cross(n, t), and the whole frame turned
      // with the normal on back faces.
      vec3 vn = geometric_n;
      vec3 vt = gl_FrontFacing ? v_world_tangent.xyz : -v_world_tangent.xyz;
      vec3 vb = v_world_tangent.w * cross(normalize(v_world_normal), v_world_tangent.xyz);
      if (!gl_FrontFacing) vb = -vb;
      tn = normalize(tn);
      n = normalize(tn.x * vt + tn.y * vb + tn.z * vn);
    } else {
      n = perturb_normal(n, v_world_pos, normal_uv, normalize(tn));
    }
  }
#endif

  float metallic = clamp(u_material.x, 0.0, 1.0);
  float roughness = u_material.y;  // brdf_evaluate() and ibl_combine() clamp it
#if MATERIAL_HAS_METALLIC_ROUGHNESS_TEXTURE
  if (ENABLED(BIT_METALLIC_ROUGHNESS_TEXTURE)) {
    vec4 mr = texture(u_metallic_roughness_tex, slot_uv(UV_SLOT_METALLIC_ROUGHNESS, v_uv));
    metallic = clamp(u_material.x * mr.b, 0.0, 1.0);
    roughness = u_material.y * mr.g;
  }
#endif

  float view_depth = -(u_view * vec4(v_world_pos, 1.0)).z;
  // glTF's occlusion texture scales the light from the surroundings only:
  // 1 + strength * (occlusion - 1) (glTF 2.0, 3.9.3).
  float occlusion = 1.0;
#if MATERIAL_HAS_OCCLUSION_TEXTURE
  if (ENABLED(BIT_OCCLUSION_TEXTURE)) {
    float ao = texture(u_occlusion_tex, slot_uv(UV_SLOT_OCCLUSION, v_uv)).r;
    occlusion = 1.0 + u_material_extra.x * (ao - 1.0);
  }
#endif
  vec3 reflected = vec3(0.0);  // S3's C_t, or the pbr probe's prefiltered radiance (AOV)
  float reflector = 0.0;       // 1 where a reflection map applies (AOV)
  // S3 eq. (1), R = U - 2 (N.U) N with U the unit vector from the eye to the point. Computed in
  // world space, which is eq. (6)'s (MV)^-1 R_VCS (rotation part): the cube is in world space.
  // Also the direction the surroundings' specular light is looked up along.
  vec3 r_world = reflect(-v, n);
#if MATERIAL_HAS_REFLECTION_CUBE
  // Where a probe's cube is read along R, for S3's model and the pbr one alike.
  vec3 cube_lookup = r_world;
#if MATERIAL_HAS_REFLECTION_BOX
  if (ENABLED(BIT_REFLECTION_BOX)) cube_lookup = box_project(v_world_pos, r_world);
#endif
#endif
#if MATERIAL_HAS_REFLECTION_PBR
  bool reflection_pbr = ENABLED(BIT_REFLECTION_PBR);
#else
  bool reflection_pbr = false;
#endif

  // Light from the surroundings through the BRDF (ibl.glsl): irradiance over pi and the
  // radiance prefiltered for this roughness along the reflected view direction.
  float ibl_roughness = clamp(roughness, BRDF_MIN_ROUGHNESS, 1.0);
  float n_dot_v = clamp(dot(n, v), 0.0, 1.0);
#if VARIANT_ENVIRONMENT == VARIANT_ENVIRONMENT_MAP
  vec3 sh[9];
  for (int i = 0; i < 9; ++i) sh[i] = u_environment_sh[i].rgb;
  vec3 irradiance = u_environment.x * sh9_irradiance_over_pi(sh, n);
  vec3 specular = u_environment.x *
                  textureLod(u_environment_cube, r_world, ibl_roughness * u_environment.y).rgb;
#else
  vec3 irradiance = u_ambient.rgb;
  vec3 specular = u_ambient.rgb;
#endif
#if MATERIAL_HAS_REFLECTION_PBR
  if (reflection_pbr) {
    // The probe instead of the environment, by p_r.
    reflected = textureLod(u_reflection_cube, cube_lookup, ibl_roughness * u_reflection.z).rgb;
    reflector = 1.0;
    irradiance = mix(irradiance, sh9_irradiance_over_pi(int(u_reflection.y), n), u_reflection.x);
    specular = mix(specular, reflected, u_reflection.x);
  }
#endif
  vec3 color = ibl_combine(base.rgb, metallic, roughness, n_dot_v,
                           dfg_lookup(n_dot_v, ibl_roughness), irradiance, specular) * occlusion;
#if MATERIAL_HAS_EMISSIVE
  if (ENABLED(BIT_EMISSIVE)) {
    vec3 emissive = u_emissive;  // the factor, times KHR_materials_emissive_strength
#if MATERIAL_HAS_EMISSIVE_TEXTURE
    if (ENABLED(BIT_EMISSIVE_TEXTURE))
      emissive *= texture(u_emissive_tex, slot_uv(UV_SLOT_EMISSIVE, v_uv)).rgb;
#endif
    color += emissive;
  }
#endif
  // Shadow visibility per shadow view (as many views as the variant has: none is no code); the
  // AOV shows the view u_counts.z names, the debug tint view 0's cascade.
  float aov_visibility = 1.0;
  int aov_cascade = -1, tint_cascade = -1;
#if VARIANT_HAS_SHADOW && MATERIAL_RECEIVES_SHADOWS
  float view_visibility[SHADOW_VIEWS];
#if SHADOW_STORES
  vec4 stored = vec4(1.0);
#if SHADOW_VIEWS == 1
  stored.y = 0.0;
#endif
  const float plane_offset = plane_distance(v_world_pos, geometric_n, u_camera_pos.xyz);
#endif
#if SHADOW_REUSE_IS(LOAD)
  const vec4 cached_visibility = texelFetch(u_cached_visibility, ivec2(gl_FragCoord.xy), 0);
#elif SHADOW_REUSE_IS(REPROJECT)
  // The four stored pixels span at most a pixel's step along each axis: on a curved surface
  // their planes' distances differ from this point's by at most about fwidth; on a flat one
  // by rounding.
  const float reprojected = reprojected_visibility(
      v_world_pos, geometric_n,
      1.5 * fwidth(plane_offset) + 1e-4 * distance(v_world_pos, u_camera_pos.xyz));
  bool look_up = false;  // discarded at the end: the second pass looks it up
#endif
  for (int k = 0; k < SHADOW_VIEWS; ++k) {
    float visibility = 1.0;
    int cascade = -1;
    if (ENABLED(BIT_RECEIVE_SHADOWS)) {
#if VARIANT_HAS_AOVS
      visibility = shadow_visibility(k, v_world_pos, geometric_n, view_depth, cascade);
#elif SHADOW_REUSE_IS(LOAD)
      visibility = max(cached_visibility[k], 0.0);
#else
      // No AOV shows it: where the geometric surface faces away from the light it shadows
      // itself, so the lookup is skipped (visibility 0; only a normal-mapped normal can still
      // face the light there). With AOVs the lookup runs everywhere: the AOV contract and its
      // tests keep today's values on such pixels. llvmpipe runs the masked lookup anyway.
      visibility = 0.0;
      const bool lit_side = faces_light(u_shadow_views[k].info.x, v_world_pos, geometric_n);
      if (lit_side) {
#if SHADOW_REUSE_IS(REPROJECT)
        // No lookup here: llvmpipe would run it for every pixel of a SIMD vector whatever the
        // branch, so the pixels that need one are left to the second pass.
        visibility = max(reprojected, 0.0);
        look_up = reprojected < 0.0;
#else
        visibility = shadow_visibility(k, v_world_pos, geometric_n, view_depth, cascade);
#endif
      }
#if SHADOW_STORES
      stored[k] = lit_side ? visibility : -1.0;
#if SHADOW_VIEWS == 1
      // (A smooth normal may face slightly away from the camera at a silhouette: code 0.)
      stored.y = !lit_side || plane_offset <= 0.0 ? 0.0
                 : visibility >= 1.0 - 1e-6 ? plane_offset
                 : visibility <= 1e-6 ? -plane_offset : 0.0;
#endif
#endif
#endif
    }
    view_visibility[k] = visibility;
    if (k == u_counts.z) {
      aov_visibility = visibility;
      aov_cascade = cascade;
    }
    if (k == 0) tint_cascade = cascade;
  }
#if SHADOW_STORES
  o_cached_visibility = stored;
#endif
#endif
  for (int i = 0; i < u_counts.x; ++i) {
    int type = u_light_info[i].x;
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
      // light_emission() in components/light.h: the spot's cone; an area light's cone times
      // its Lambertian cosine.
      if (type == LIGHT_SPOT || type == LIGHT_AREA) {
        float cd = dot(-l, normalize(u_light_dir[i].xyz));
        attenuation *= smoothstep(u_light_pos[i].w, u_light_cone[i].x, cd);
        if (type == LIGHT_AREA) attenuation *= max(cd, 0.0);
      }
    }
    float ndl = max(dot(n, l), 0.0);
    if (ndl <= 0.0) continue;
    float shadow = 1.0;
#if VARIANT_HAS_SHADOW && MATERIAL_RECEIVES_SHADOWS
    for (int k = 0; k < SHADOW_VIEWS; ++k)  // constant indices: no dynamic array access
      if (u_light_info[i].y == k) shadow = view_visibility[k];
#endif
    color += brdf_evaluate(base.rgb, metallic, roughness, n, v, l) * u_light_color[i].rgb * ndl *
             attenuation * shadow;
  }

#if MATERIAL_HAS_REFLECTION_CUBE
  if (ENABLED(BIT_REFLECTION_CUBE) && !reflection_pbr) {
    reflected = texture(u_reflection_cube, cube_lookup).rgb;
    reflector = 1.0;
  }
#endif
#if MATERIAL_HAS_REFLECTION_SPHERE
  if (ENABLED(BIT_REFLECTION_SPHERE)) {
    // S3 eq. (4)-(5) in view space: A_z = sqrt((R_z + 1) / 2), s = R_x / (2 A_z), t = R_y / (2 A_z).
    vec3 r_view = mat3(u_view) * r_world;
    float a_z = sqrt(max((r_view.z + 1.0) * 0.5, 1e-8));
    vec2 st = r_view.xy / (2.0 * a_z);
    reflected = texture(u_reflection_sphere, st * 0.5 + 0.5).rgb;
    reflector = 1.0;
  }
#endif
#if MATERIAL_HAS_REFLECTION_CUBE || MATERIAL_HAS_REFLECTION_SPHERE
  if (!reflection_pbr) color += u_reflection.x * reflected;  // S3 eq. (3): I' = I + k_s p_r C_t
#endif

#if VARIANT_HAS_SHADOW && VARIANT_DEBUG_CASCADES
  color *= cascade_tint(tint_cascade);
#endif
  // Tone mapped here, per sample under MSAA: the resolve averages displayable values.
  o_color = vec4(tone_map(color * u_frame.x), coverage);
#if MATERIAL_HAS_ALPHA_BLEND
  // glTF BLEND, premultiplied: the transparent phase blends (GL_ONE, GL_ONE_MINUS_SRC_ALPHA),
  // the over operator, in linear light (the sRGB target), on tone-mapped values.
  if (ENABLED(BIT_ALPHA_BLEND)) {
    float alpha = clamp(base.a, 0.0, 1.0);
    o_color = vec4(o_color.rgb * alpha, alpha);
  }
#endif
#if VARIANT_HAS_AOVS
  o_position = vec4(v_world_pos, 1.0);
  o_normal = vec4(geometric_n, view_depth);
  o_visibility = vec2(aov_visibility, float(aov_cascade));
  o_reflection = vec4(reflected, reflector);
#endif
#if SHADOW_REUSE_IS(REPROJECT)
  // Last, so that every derivative above saw the whole quad.
  if (look_up) discard;
#endif
}
