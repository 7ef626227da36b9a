// World-space shadow stability: a fixed set of points on receivers, a camera
// path while the light and the scene stay still, and each frame the engine's visibility at those
// points through the forward pass's own shadow lookup (Renderer::shadow_at_points). A stabilised
// configuration under camera translation can score exactly 0.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "components/bounds.h"
#include "runtime/assets/image_io.h"
#include "runtime/app/player.h"
#include "runtime/reference/shadow_metrics.h"

namespace kaskad {

/// Receiver points taken from an AOV image (Renderer::read_aovs): the geometry pixels (mask = 1,
/// finite position and normal) on a regular pixel grid, at most `max_points` of them.
struct StabilityPoints {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  ///< unit, the AOV's N (the side the camera sees)
  std::vector<glm::ivec2> pixels;  ///< where each point was taken from (x right, y down)
};
Result<StabilityPoints> stability_points(const Image& aov, int max_points = 4096);
/// Drops the points outside `box` (world space, faces included).
void keep_points_within(StabilityPoints& points, const Aabb& box);

/// The camera path: `frames` frames; frame f moves the camera by f * step along its own right
/// and up axes (step * (right + 0.5 up)), so every point keeps its view depth and no point
/// changes cascade by depth: only the shadow maps' placement can change what a point sees.
struct CameraPath {
  int frames = 16;
  float step = 0.0f;  ///< metres per frame; 0 = auto: 0.07 % of the scene bounds' diagonal
};

struct StabilityRun {
  reference::StabilityStats stats;
  float step = 0.0f;  ///< metres per frame actually used
  /// visibility[f][p]: point p in frame f (for tests and dumps); NaN while the point is outside
  /// the camera's view (not counted by shadow_stability()).
  std::vector<std::vector<float>> visibility;
};

/// Renders the path (colour only, AOVs off) and evaluates the points every frame. The camera's
/// Transform is restored afterwards. Errors: no camera, a root-less (parented) camera, GL/shader
/// errors.
/// The engine's visibility at `points` after the last frame (Renderer::shadow_at_points), NaN
/// for points outside the view of `camera` (that frame's camera).
Result<std::vector<float>> visibility_at_seen_points(render::Renderer& renderer,
                                                     const CameraState& camera,
                                                     const StabilityPoints& points);

Result<StabilityRun> measure_stability(Player& player, Scene& scene, const StabilityPoints& points,
                                       const CameraPath& path = {});

}  // namespace kaskad
