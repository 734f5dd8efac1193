#pragma once
// Removal of large planes (tables, walls, floors) by RANSAC, as the thesis does before clustering,
// keeping objects that merely have flat faces: a plane is removed only when it has enough inliers
// *and* its largest connected patch spans, in both directions, more than any object would. (The thesis removed every
// plane above a point count, which needs the object's size and, on shelves of boxes, removes the
// boxes' coplanar tops.)
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

struct PlaneOptions {
  float distance_threshold_m = 0.01f;  ///< inlier band (thesis: about 1 cm)
  int max_iterations = 500;            ///< RANSAC samples at most (stops earlier at 99 % confidence)
  std::size_t min_inliers = 1000;      ///< smaller planes stay
  float min_extent_m = 0.30f;          ///< planes narrower than this in either direction (object faces) stay
  int max_planes = 5;
  std::uint64_t seed = 1;
};

struct Plane {
  Eigen::Vector4f coefficients = Eigen::Vector4f::Zero();  ///< unit normal n and d, n.p + d = 0; n faces the origin
  std::vector<std::uint32_t> inliers;
  float extent_m = 0;  ///< smaller in-plane spread (2nd to 98th percentile) of the largest connected patch
};

/// The best plane among the points `indices` of `points` (RANSAC, then a least-squares refit on
/// its inliers). No inliers when there are fewer than 3 points.
Plane fit_plane(std::span<const Eigen::Vector3f> points, std::span<const std::uint32_t> indices, const PlaneOptions& options);

struct PlaneRemoval {
  std::vector<std::uint32_t> remaining;  ///< finite points not on a removed plane
  std::vector<Plane> removed;
};
PlaneRemoval remove_large_planes(const PointCloud& cloud, const PlaneOptions& options = {});

}  // namespace viewpose
