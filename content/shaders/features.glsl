// Feature selection. In a variant build every feature block is `#if FEATURE_DEFINE` and ENABLED()
// is true: no uniform decides anything. The test oracle (KASKAD_UBER_ORACLE, compiled only by the
// tests) turns every material feature on and lets ENABLED(bit) read u_oracle_features instead,
// so the same blocks run with uniform-driven selection for comparison.
#ifdef KASKAD_UBER_ORACLE
layout(location = LOC_FEATURE_BITS) uniform uint u_oracle_features;  // VariantKey material bits
#define ENABLED(bit) ((u_oracle_features & (1u << uint(bit))) != 0u)
#else
#define ENABLED(bit) true
#endif

// BIT_BASE_COLOR_TEXTURE, BIT_NORMAL_MAP, ...: the material features' key bits, defined in every
// program by FeatureManifest::defines() from kFeatureTable (runtime/features/variant_key.h).

// The uv a texture slot (UV_SLOT_*) reads: its uv set (TEXCOORD_0 `uv` or TEXCOORD_1 `v_uv1`, the
// first row's w) through its KHR_texture_transform. Two rows of the slot's affine map per slot
// (uv_transform_rows() in components/material.h), declared here after ENABLED().
#if MATERIAL_HAS_TEXTURE_TRANSFORM
layout(location = LOC_UV_TRANSFORM) uniform vec4 u_uv_transform[2 * UV_SLOT_COUNT];
in vec2 v_uv1;
vec2 slot_uv(int slot, vec2 uv) {
  if (!ENABLED(BIT_TEXTURE_TRANSFORM)) return uv;
  vec3 p = vec3(mix(uv, v_uv1, u_uv_transform[2 * slot].w), 1.0);
  return vec2(dot(u_uv_transform[2 * slot].xyz, p), dot(u_uv_transform[2 * slot + 1].xyz, p));
}
#else
vec2 slot_uv(int slot, vec2 uv) { return uv; }
#endif
