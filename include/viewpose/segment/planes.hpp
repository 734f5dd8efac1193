#pragma once
// Removal of large planes (tables, walls, floors) by RANSAC, as the thesis does before clustering,
// keeping objects that merely have flat faces: a plane is removed only when its largest connected
// patch covers enough area *and* spans, in both directions, more than any object would. (The
// thesis removed every plane above a point count, which needs the object's size and, on shelves of
// boxes, removes the boxes' coplanar tops.) Planes are searched for in an even sample of the
// cloud, so that the time does not grow with the sensor's resolution; every point is then tested
// against the planes found.
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

struct PlaneOptions {
  float distance_threshold_m = 0.01f;  ///< inlier band (thesis: about 1 cm)
  int max_iterations = 500;            ///< RANSAC samples at most (stops earlier at 99 % confidence)
  /// Planes whose largest connected patch covers less than this stay (0.01 m2: 1000 points of a
  /// 3 mm voxel grid). Counted in cells of the inlier band's width that hold a sampled point: where
  /// the sample is sparser than the cells it counts less than the true area, never more.
  float min_area_m2 = 0.01f;
  float min_extent_m = 0.30f;          ///< planes narrower than this in either direction (object faces) stay
  /// Planes are searched for among at most this many points, evenly spread over the cloud (a
  /// square lattice of pixels for an organized one: every third pixel of every third row of a VGA
  /// frame, 1 cm apart at 1.7 m).
  std::size_t max_sample_points = 40000;
  int max_planes = 5;
  std::uint64_t seed = 1;
};

/// Where a plane was seen. Its equation is unbounded; a table ends at its edge, and the top of a box
/// beside an object is not under the object. The cells (of the inlier band's width, in the plane's
/// own 2-D coordinates) that its large connected patches cover, among the points it was searched
/// in: a patch counts when it covers PlaneOptions::min_area_m2, as the largest must for the plane
/// to be removed at all.
struct PlanePatch {
  Eigen::Vector3f axis_u = Eigen::Vector3f::Zero(), axis_v = Eigen::Vector3f::Zero();  ///< in-plane unit axes
  Eigen::Vector2f origin = Eigen::Vector2f::Zero();  ///< the first cell's corner, (axis_u.p, axis_v.p)
  float cell_m = 0;
  int width = 0, height = 0;
  std::vector<std::uint8_t> covered;  ///< width x height, row after row; 1 where a large patch is

  /// Whether `p`, on or near the plane, falls in a covered cell or beside one (its 8 neighbours:
  /// the sample's rows lie a few cells apart on a far table seen at a slant). False for an empty patch.
  bool covers(const Eigen::Vector3f& p) const;
};

struct Plane {
  Eigen::Vector4f coefficients = Eigen::Vector4f::Zero();  ///< unit normal n and d, n.p + d = 0; n faces the origin
  std::vector<std::uint32_t> inliers;  ///< every point of the cloud within the band, ascending
  float extent_m = 0;  ///< smaller in-plane spread (2nd to 98th percentile) of the largest connected patch
  float area_m2 = 0;   ///< area of the largest connected patch
  PlanePatch patch;    ///< where it was seen (remove_large_planes fills it; fit_plane does not)
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
