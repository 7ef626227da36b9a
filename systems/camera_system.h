// Camera selection and framing.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "components/bounds.h"
#include "components/camera.h"
#include "runtime/ecs/world.h"

namespace kaskad {

struct CameraState {
  ecs::Entity entity = ecs::kNullEntity;  ///< null when the scene has no camera
  Camera camera;
  glm::mat4 view{1.0f};   ///< world -> view (scale removed from the camera's world matrix)
  glm::mat4 proj{1.0f};   ///< OpenGL clip space, aspect resolved
  glm::vec3 position{0.0f};
  float aspect = 1.0f;
};

/// A camera's uniform world scale, the cube root of its world basis' volume (1 where that is not
/// a positive finite number): a camera inside a scaled hierarchy (a glTF model scaled to the
/// scene's units) has its near, far and ortho height scaled by it, so it sees what it saw
/// before the scaling.
float camera_world_scale(const glm::mat4& world_matrix);

/// The first Camera with active = true, else the first Camera; needs WorldTransform.
/// `output_aspect` is used when the camera's own aspect is 0.
CameraState select_camera(const ecs::World& world, float output_aspect);

/// The output size for a requested `width` x `height` when the rendering camera has an aspect
/// of its own (Camera::aspect > 0, e.g. a glTF camera's aspectRatio): the largest size of that
/// aspect inside the request, so the image is never stretched. The request when the camera
/// takes its aspect from the output.
glm::ivec2 fit_output_to_camera(const ecs::World& world, int width, int height);

/// What a user should hear about the rendering camera of `world` (WorldBounds needed), as
/// sentences; empty when all is well. Checked once, after a scene is loaded:
/// - more than one camera is active (the first renders);
/// - the depth buffer cannot tell surfaces apart at the distance of what the camera sees: the
///   depth step there (window depth has 24 bits of precision near 1: d^2 (far - near) /
///   (near far 2^24) metres at distance d) is over 1% of the distance (near far too small);
/// - what it sees lies so far from the origin that 32-bit float positions there are over half
///   a pixel apart at their distance from the camera (vertices and shadows jitter).
/// `output_height` is the image's height in pixels.
std::vector<std::string> camera_warnings(const ecs::World& world, float output_aspect,
                                         int output_height);

/// Near and far of a camera at `position` fitted to `bounds` (not empty): far just past the
/// farthest corner, near 0.9x the distance to the nearest point of the box (0 inside it), kept
/// between far / 1000 and far / 2, so near < far wherever the camera looks. For an auto_frame
/// camera moved after the load (the editor's fly camera, a playback's camera keys): the planes
/// framing fitted from where the load put it would clip what the camera flies up to.
void fit_planes_to_bounds(Camera& camera, const glm::vec3& position, const Aabb& bounds);

/// Moves every auto_frame camera back along its view axis until `bounds` fits its field of view,
/// and sets near/far to enclose the bounds, far also the farthest corner of `depth_bounds` in
/// front of the camera (a ground wider than the models). Updates Transform (root cameras only; a
/// parented auto_frame camera is left alone with a warning).
void frame_auto_cameras(ecs::World& world, const Aabb& bounds, const Aabb& depth_bounds,
                        float output_aspect);

}  // namespace kaskad
