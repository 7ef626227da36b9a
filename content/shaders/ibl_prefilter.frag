// One face of one level of a prefiltered specular cube (IblMaps::prefilter): the source cube's
// radiance convolved with the GGX lobe of roughness u_params.x around the texel's direction,
// taking N = V = R (the split sum's assumption; components/ibl.h), weighted by N.L. Filtered
// importance sampling (Colbert and Krivanek, GPU Gems 3, ch. 20): each of the u_params.z GGX
// samples reads the source mip whose texels cover the sample's share of the lobe's solid angle,
// so few samples give a smooth result.
#include "brdf.glsl"
#include "cube_face.glsl"

in vec2 v_uv;
layout(location = 0) out vec4 o_color;

layout(binding = 0) uniform samplerCube u_source;  // radiance, full mip chain
layout(location = 0) uniform ivec4 u_face;         // x face (GL order)
layout(location = 1) uniform vec4 u_params;        // x roughness, y source size (texels), z samples

vec2 hammersley(uint i, uint n) {
  uint b = bitfieldReverse(i);
  return vec2(float(i) / float(n), float(b) * 2.3283064365386963e-10);
}

void main() {
  vec3 n = normalize(cube_face_direction(u_face.x, v_uv));
  float roughness = clamp(u_params.x, BRDF_MIN_ROUGHNESS, 1.0);
  float alpha = roughness * roughness;
  float a2 = alpha * alpha;
  uint samples = uint(u_params.z);
  // An orthonormal frame around n.
  vec3 up = abs(n.y) < 0.999 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
  vec3 tx = normalize(cross(up, n));
  vec3 ty = cross(n, tx);
  float texel_solid_angle = 4.0 * BRDF_PI / (6.0 * u_params.y * u_params.y);
  vec3 sum = vec3(0.0);
  float weight = 0.0;
  for (uint i = 0u; i < samples; ++i) {
    vec2 u = hammersley(i, samples);
    float cos_t = sqrt((1.0 - u.y) / (1.0 + (a2 - 1.0) * u.y));
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    float phi = 2.0 * BRDF_PI * u.x;
    vec3 h = tx * (sin_t * cos(phi)) + ty * (sin_t * sin(phi)) + n * cos_t;
    vec3 l = 2.0 * dot(n, h) * h - n;
    float n_dot_l = dot(n, l);
    if (n_dot_l <= 0.0) continue;
    // pdf(l) = D (N.H) / (4 V.H) = D / 4 with N = V.
    float d = cos_t * cos_t * (a2 - 1.0) + 1.0;
    float pdf = a2 / (BRDF_PI * d * d) * 0.25;
    float sample_solid_angle = 1.0 / (float(samples) * pdf + 1e-6);
    float lod = max(0.5 * log2(sample_solid_angle / texel_solid_angle), 0.0);
    sum += textureLod(u_source, l, lod).rgb * n_dot_l;
    weight += n_dot_l;
  }
  o_color = vec4(sum / max(weight, 1e-6), 1.0);
}
