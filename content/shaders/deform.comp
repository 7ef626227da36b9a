// The deform pass: one invocation per vertex of a deformed mesh poses it (morph targets, then
// the skin) from its source mesh's vertices into its posed copy, both in the GPU cache's shared
// vertex buffer. The pose is runtime/assets/mesh_pose.h's, which the CPU computes the same way
// for the references (tests/render/deform_test compares the two). DEFORM_SKIN: joints a vertex
// (none, 4, 8); DEFORM_MORPH: morph targets.
layout(local_size_x = 64) in;

layout(std430, binding = BUF_VERTICES) buffer Vertices { float vertices[]; };
layout(std430, binding = BUF_JOINTS) readonly buffer Joints { uint joints[]; };
layout(std430, binding = BUF_JOINT_WEIGHTS) readonly buffer JointWeights { float joint_weights[]; };
layout(std430, binding = BUF_MORPH_DELTAS) readonly buffer MorphDeltas { float deltas[]; };
layout(std430, binding = BUF_SKIN_MATRICES) readonly buffer SkinMatrices { mat4 skin[]; };
layout(std430, binding = BUF_MORPH_WEIGHTS) readonly buffer MorphWeights { float morph_weights[]; };

// x source base vertex, y posed base vertex, z vertex count, w first skin matrix.
layout(location = LOC_DEFORM_JOB) uniform ivec4 u_job;
// x first morph weight, y morph targets.
layout(location = LOC_DEFORM_MORPH) uniform ivec4 u_morph;

vec3 read3(uint at) { return vec3(vertices[at], vertices[at + 1u], vertices[at + 2u]); }
void write3(uint at, vec3 v) {
  vertices[at] = v.x;
  vertices[at + 1u] = v.y;
  vertices[at + 2u] = v.z;
}
vec3 normalized_or_zero(vec3 v) {
  float len2 = dot(v, v);
  return len2 > 0.0 ? v * (1.0 / sqrt(len2)) : v;
}

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uint(u_job.z)) return;
  uint src = (uint(u_job.x) + i) * uint(VERTEX_FLOATS);
  uint dst = (uint(u_job.y) + i) * uint(VERTEX_FLOATS);
  vec3 p = read3(src + uint(VERTEX_POSITION));
  vec3 n = read3(src + uint(VERTEX_NORMAL));
  vec3 t = read3(src + uint(VERTEX_TANGENT));
  float handedness = vertices[src + uint(VERTEX_TANGENT) + 3u];
#if DEFORM_MORPH
  for (int k = 0; k < u_morph.y; ++k) {
    float w = morph_weights[u_morph.x + k];
    if (w == 0.0) continue;
    uint d = (uint(k) * uint(u_job.z) + i) * uint(MORPH_DELTA_FLOATS);
    p += w * vec3(deltas[d], deltas[d + 1u], deltas[d + 2u]);
    n += w * vec3(deltas[d + 3u], deltas[d + 4u], deltas[d + 5u]);
    t += w * vec3(deltas[d + 6u], deltas[d + 7u], deltas[d + 8u]);
  }
#endif
#if DEFORM_SKIN != DEFORM_SKIN_NONE
  const uint influences = DEFORM_SKIN == DEFORM_SKIN_JOINTS8 ? 8u : 4u;
  mat4 m = mat4(0.0);
  for (uint k = 0u; k < influences; ++k) {
    float w = joint_weights[i * influences + k];
    if (w != 0.0) m += w * skin[uint(u_job.w) + joints[i * influences + k]];
  }
  p = vec3(m * vec4(p, 1.0));
  // The cofactor matrix turns normals as the inverse transpose does, up to a positive scale.
  mat3 a = mat3(m);
  n = mat3(cross(a[1], a[2]), cross(a[2], a[0]), cross(a[0], a[1])) * n;
  t = a * t;
#endif
  // Everything but position, normal and tangent (uvs) is the source's.
  for (uint f = 0u; f < uint(VERTEX_FLOATS); ++f) vertices[dst + f] = vertices[src + f];
  write3(dst + uint(VERTEX_POSITION), p);
  write3(dst + uint(VERTEX_NORMAL), normalized_or_zero(n));
  write3(dst + uint(VERTEX_TANGENT), normalized_or_zero(t));
  vertices[dst + uint(VERTEX_TANGENT) + 3u] = handedness;
}
