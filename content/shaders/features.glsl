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
// program by FeatureManifest::defines() from kFeatureTable (runtime/render/variant_key.h).
