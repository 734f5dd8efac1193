#pragma once
// Which pieces of a frame are cut apart by the sensor's missing depth. A structured-light sensor
// returns nothing on a mug's rim, a dark band of print or a shiny edge, and one object then comes
// out of segmentation as pieces more than a cluster's gap apart. In the image, such pieces are
// joined by a path of unmeasured pixels. That is necessary, not sufficient: a structured-light
// sensor's shadow puts missing depth beside most occluding edges, between different things too, so
// the caller bounds the pieces' gap and size as well (SplitOptions::join_gap_m).
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"

namespace viewpose {

struct DepthGap {
  std::uint32_t a = 0, b = 0;  ///< indices of the two pieces, a < b
  int unmeasured_px = 0;       ///< unmeasured pixels on the path found between them (at least 1)
};

/// The pairs of `pieces` (points in the camera frame, e.g. a voxelized cloud's clusters) joined in
/// `depth` by a 4-connected path of at least 1 and at most `max_unmeasured_px` unmeasured pixels
/// (NaN or 0). Each piece stands for the measured pixels near its points' projections (within half
/// of `point_spacing_m` in the image and `depth_tolerance_m` of the point's depth). Every piece
/// grows through unmeasured pixels at once, each pixel going to the piece that reaches it first;
/// where two growths meet, the pair is joined by the path through the meeting point. With two
/// pieces that path is the shortest; with more, a third piece whose growth takes the pixels between
/// two (lying across their band, or only beside it) can hide the pair or lengthen its path: ask for
/// one pair at a time where that matters. Nothing for an image whose size is not K's, or K without
/// focal lengths. Sorted by (a, b).
std::vector<DepthGap> missing_depth_gaps(const DepthImage& depth, const CameraIntrinsics& K,
                                         std::span<const std::span<const Eigen::Vector3f>> pieces, float point_spacing_m,
                                         float depth_tolerance_m, int max_unmeasured_px);

}  // namespace viewpose
