#define VERTEX_STAGE_INSTANCED
#include "common.glsl"

layout(location = ATTR_POSITION) in vec3 a_position;
layout(location = ATTR_NORMAL) in vec3 a_normal;
layout(location = ATTR_UV) in vec2 a_uv;
#if MATERIAL_HAS_TEXTURE_TRANSFORM
layout(location = ATTR_UV1) in vec2 a_uv1;  // slots on TEXCOORD_1 (features.glsl, slot_uv)
out vec2 v_uv1;
#endif
#if MATERIAL_HAS_NORMAL_MAP
layout(location = ATTR_TANGENT) in vec4 a_tangent;  // xyz tangent, w bitangent sign
#endif

out vec3 v_world_pos;
out vec3 v_world_normal;
out vec2 v_uv;
#if MATERIAL_HAS_NORMAL_MAP
out vec4 v_world_tangent;
#endif

void main() {
  vec4 world = a_model * vec4(a_position, 1.0);
  v_world_pos = world.xyz;
  v_world_normal = a_normal_matrix * a_normal;
  v_uv = a_uv;
#if MATERIAL_HAS_TEXTURE_TRANSFORM
  v_uv1 = a_uv1;
#endif
#if MATERIAL_HAS_NORMAL_MAP
  // A tangent lies in the surface: it goes through the model matrix, not the normal matrix. A
  // mirroring transform reverses cross(n, t), so the bitangent's sign follows the determinant.
  // Unit length at the vertex, as MikkTSpace's frame expects (a scaled model would lengthen it).
  mat3 m = mat3(a_model);
  vec3 t = m * a_tangent.xyz;
  float len2 = dot(t, t);
  v_world_tangent = vec4(len2 > 0.0 ? t * inversesqrt(len2) : vec3(0.0),
                         determinant(m) < 0.0 ? -a_tangent.w : a_tangent.w);
#endif
  gl_Position = u_view_proj * world;
}
