// The direction maths of cube and sphere maps (S3): where a direction meets a cube face and
// back, the sphere map's reflection direction per texel and texture coordinate per direction, and
// S3's M_rot. GLM only (kaskad::math); the maps themselves, their sampling and loaders are in
// runtime/assets/env_map.h, whose header comment states the conventions (OpenGL 4.5 table 8.19
// face coordinates; sphere-map rows from the top).
#pragma once

#include <glm/glm.hpp>

namespace kaskad {

/// GL cube-map face order: face i is GL_TEXTURE_CUBE_MAP_POSITIVE_X + i.
enum class CubeFace : int { pos_x, neg_x, pos_y, neg_y, pos_z, neg_z };

/// The unit direction through face coordinate (s, t), s,t in [0,1] (table 8.19 inverted; also
/// S3's face formulas, e.g. +X: s = -z / (2|x|) + 1/2, t = -y / (2|x|) + 1/2).
glm::vec3 cube_direction(CubeFace face, float s, float t);

/// Where a direction meets the cube: the face of its major axis (ties go to X, then Y, then Z;
/// S3: "the coordinate with the largest absolute value, by its sign") and s,t in [0,1].
struct CubeCoord {
  CubeFace face;
  float s, t;
};
/// Inverse of cube_direction for any non-zero direction (need not be unit). Zero or non-finite
/// directions give {pos_z, 0.5, 0.5}.
CubeCoord cube_coord(const glm::vec3& direction);

/// S3 eq. (2) at texel centre (i, j) of a `size` map (row j from the top, see SphereMap): the
/// view-space reflection direction stored there. Outside the unit circle: (0, 0, -1).
glm::vec3 sphere_map_direction(int i, int j, int size);

/// S3 eq. (4)-(5): the texture coordinate (s', t') in [0,1]^2 of a view-space reflection
/// direction (need not be unit): A_z = sqrt((R_z + 1) / 2), s = R_x / (2 A_z), t = R_y / (2 A_z),
/// s' = (s + 1) / 2, t' = (t + 1) / 2. t' grows UPWARDS (GL texture convention): t' = 1 is the
/// top row (row 0) of a SphereMap. R = (0, 0, -1) (the singular rim point) gives (1, 0.5).
glm::vec2 sphere_map_uv(const glm::vec3& reflected_view);

/// S3's M_rot: (x, y, z) -> (x, -z, y), a 90 degree rotation about X. It maps an engine (Y-up)
/// direction to the same direction in 3ds Max (Z-up) coordinates, and a 3ds Max direction to
/// S3's cube-map space (CMCS).
glm::vec3 m_rot(const glm::vec3& v);

}  // namespace kaskad
