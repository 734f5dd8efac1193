#pragma once
// A point cloud in metres. Organized clouds (height > 1) keep the image grid of the frame they came
// from: point (u, v) is points[v * width + u], and pixels without a measurement hold NaN.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Geometry>  // cross products and rotations are used wherever points are

namespace viewpose {

struct PointCloud {
  std::vector<Eigen::Vector3f> points;  ///< metres; NaN where there is no measurement
  std::vector<Eigen::Vector3f> normals;  ///< empty, or one unit normal per point
  std::vector<float> curvature;          ///< empty, or one per point
  std::vector<std::uint32_t> rgba;       ///< empty, or one per point, packed 0xAARRGGBB as PCL does
  std::vector<std::uint32_t> labels;     ///< empty, or one per point
  int width = 0;   ///< points per row (the point count when unorganized)
  int height = 1;  ///< rows; 1 = unorganized

  /// An unorganized cloud holding `pts`.
  static PointCloud from_points(std::vector<Eigen::Vector3f> pts);

  std::size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
  bool organized() const { return height > 1; }
  bool has_normals() const { return !normals.empty(); }
  /// Points whose three coordinates are finite.
  std::size_t count_finite() const;
  /// Throws viewpose::Error when width x height or an attribute's length disagrees with the points.
  void check_consistent() const;
};

/// Axis-aligned box over finite points or vertices; `empty` when there are none.
struct BoundingBox {
  Eigen::Vector3f min = Eigen::Vector3f::Constant(0.0f);
  Eigen::Vector3f max = Eigen::Vector3f::Constant(0.0f);
  bool empty = true;

  Eigen::Vector3f size() const { return empty ? Eigen::Vector3f::Zero() : Eigen::Vector3f(max - min); }
  float diagonal() const { return size().norm(); }
  void extend(const Eigen::Vector3f& p);
};

BoundingBox bounding_box(std::span<const Eigen::Vector3f> points);

/// A point set's principal axes: the columns of `axes` (unit, right-handed), widest spread first,
/// through `mean`; `extent[k]`, the points' full extent along axis k.
struct PrincipalAxes {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d extent = Eigen::Vector3d::Zero();
};

/// Of the finite points (identity axes and zero extents for fewer than two).
PrincipalAxes principal_axes(std::span<const Eigen::Vector3f> points);

/// The widest, over the points' three principal axes, of the shortest interval holding `share` of
/// their projections (finite points only; 0 for fewer than two). No ball narrower than this holds
/// `share` of the points: along any axis, the points in a ball of diameter D project into D.
/// Outliers beyond the share do not widen it, as they widen a bounding box.
double core_width(std::span<const Eigen::Vector3f> points, double share);

}  // namespace viewpose
