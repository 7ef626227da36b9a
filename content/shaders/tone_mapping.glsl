// The frame's tone mapping (VARIANT_TONE_MAPPING, render.tone_mapping): the curves of
// components/tone_mapping.h (see there for their sources), evaluated per fragment on the linear
// colour after exposure. Probe captures and the AOVs stay linear (no tone mapping).
#if VARIANT_TONE_MAPPING == VARIANT_TONE_MAPPING_KHR_PBR_NEUTRAL
vec3 tone_map(vec3 c) {
  const float start = 0.8 - 0.04;
  const float desaturation = 0.15;
  float x = min(c.r, min(c.g, c.b));
  float offset = x < 0.08 ? x - 6.25 * x * x : 0.04;
  c -= offset;
  float peak = max(c.r, max(c.g, c.b));
  if (peak < start) return c;
  const float d = 1.0 - start;
  float new_peak = 1.0 - d * d / (peak + d - start);
  c *= new_peak / peak;
  float g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
  return mix(c, vec3(new_peak), g);
}
#elif VARIANT_TONE_MAPPING == VARIANT_TONE_MAPPING_ACES
vec3 tone_map(vec3 x) {
  return clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}
#else
vec3 tone_map(vec3 c) { return c; }
#endif
