#pragma once
// Splitting a cluster where objects touch. Euclidean clustering joins a mug and a brick that stand
// against each other; what separates them is the shape of the join. Surfaces of one object meet at
// convex edges (a box's faces) or continue smoothly (a cylinder), while two objects side by side meet
// in a concave crease or at a step where one hides the other. This follows the idea of LCCP (Stein et
// al., "Object partitioning using local convexity", CVPR 2014) on small cubes instead of supervoxels:
// each occupied cube gets a plane fitted to its points, neighbouring cubes are joined when the
// surface between them is convex or smooth, and the connected groups of cubes are the segments.
#include <vector>

#include "viewpose/core/point_cloud.hpp"
#include "viewpose/segment/clusters.hpp"

namespace viewpose {

struct ConvexSegmentOptions {
  float cell_m = 0.015f;              ///< cube edge: a patch this size is taken as locally planar
  float smooth_angle_deg = 12.0f;     ///< normals closer than this: a smooth continuation, or noise
  float convex_margin = 0.02f;        ///< (n1 - n2) . d above this counts as convex
  float step_cosine = 0.6f;           ///< a smooth join needs |n . d| below this: not a step between parallel faces
  /// Cubes whose plane the camera sees this close to edge-on (degrees between the normal and the
  /// line of sight) join nothing: such planes are mostly mixed pixels strung along a depth step,
  /// and their normals point either way.
  float max_incidence_deg = 75.0f;
  float max_fold_deg = 120.0f;        ///< faces folding more than this are not one object's convex edge
  /// Fewer points give no trustworthy plane (mixed pixels at a step fill cubes thinly); such cubes
  /// join nothing. Measured on a simulated brick against a mug: 4 let mixed cubes bridge the two.
  std::size_t min_cell_points = 8;
  std::size_t min_points = 100;       ///< smaller segments are dropped
};

/// The convex (or smooth) parts of `cloud` (one cluster, in the camera frame, viewed from the
/// origin), as indices into it, largest first. Points in cubes with too few points, and segments
/// below min_points, belong to no segment.
std::vector<Cluster> convex_segments(const PointCloud& cloud, const ConvexSegmentOptions& options = {});

}  // namespace viewpose
