#pragma once
// Which pieces of a frame are cut apart by the sensor's missing depth. A structured-light sensor
// returns nothing on a mug's rim, a dark band of print or a shiny edge, and one object then comes
// out of segmentation as pieces more than a cluster's gap apart. In the image, such pieces are
// joined by a path of unmeasured pixels; pieces of different things, or of one far surface broken
// by the sensor's depth steps, meet at measured pixels (a step) or not at all.
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"

namespace viewpose {

struct DepthGap {
  std::uint32_t a = 0, b = 0;  ///< indices of the two pieces, a < b
  int unmeasured_px = 0;       ///< the fewest unmeasured pixels on a path between them (at least 1)
};

/// The pairs of `pieces` (points in the camera frame, e.g. a voxelized cloud's clusters) joined in
/// `depth` by a 4-connected path of at least 1 and at most `max_unmeasured_px` unmeasured pixels.
/// Each piece stands for the measured pixels near its points' projections (within half of
/// `point_spacing_m` in the image and the depth tolerance `depth_tolerance_m` of the point);
/// every piece grows through unmeasured pixels at once, and where two growths meet, the pair is
/// joined by the path through the meeting point (a third piece lying between them on every path
/// hides the pair). Sorted by (a, b).
std::vector<DepthGap> missing_depth_gaps(const DepthImage& depth, const CameraIntrinsics& K,
                                         std::span<const std::span<const Eigen::Vector3f>> pieces, float point_spacing_m,
                                         float depth_tolerance_m, int max_unmeasured_px);

}  // namespace viewpose
