#include "viewpose/core/point_cloud.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

PointCloud PointCloud::from_points(std::vector<Eigen::Vector3f> pts) {
  PointCloud cloud;
  cloud.width = static_cast<int>(pts.size());
  cloud.height = 1;
  cloud.points = std::move(pts);
  return cloud;
}

std::size_t PointCloud::count_finite() const {
  std::size_t n = 0;
  for (const auto& p : points) n += p.allFinite() ? 1 : 0;
  return n;
}

void PointCloud::check_consistent() const {
  const std::size_t n = points.size();
  if (width < 0 || height < 1 || static_cast<std::size_t>(width) * static_cast<std::size_t>(height) != n) {
    throw Error(fmt::format("point cloud: {}x{} grid does not hold its {} points", width, height, n));
  }
  auto check = [n](std::size_t got, const char* what) {
    if (got != 0 && got != n) throw Error(fmt::format("point cloud: {} {} for {} points", got, what, n));
  };
  check(normals.size(), "normals");
  check(curvature.size(), "curvatures");
  check(rgba.size(), "colours");
  check(labels.size(), "labels");
}

void BoundingBox::extend(const Eigen::Vector3f& p) {
  if (empty) {
    min = max = p;
    empty = false;
  } else {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
}

BoundingBox bounding_box(std::span<const Eigen::Vector3f> points) {
  BoundingBox box;
  for (const auto& p : points) {
    if (p.allFinite()) box.extend(p);
  }
  return box;
}

PrincipalAxes principal_axes(std::span<const Eigen::Vector3f> points) {
  PrincipalAxes a;
  std::vector<Eigen::Vector3d> finite;
  finite.reserve(points.size());
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    finite.push_back(p.cast<double>());
    a.mean += finite.back();
  }
  if (finite.size() < 2) return {};
  a.mean /= static_cast<double>(finite.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& p : finite) covariance += (p - a.mean) * (p - a.mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  // The solver orders its eigenvalues ascending: the widest spread is its last column.
  for (int k = 0; k < 3; ++k) a.axes.col(k) = solver.eigenvectors().col(2 - k);
  if (a.axes.determinant() < 0) a.axes.col(2) *= -1.0;
  for (int k = 0; k < 3; ++k) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto& p : finite) {
      const double v = a.axes.col(k).dot(p - a.mean);
      lo = std::min(lo, v), hi = std::max(hi, v);
    }
    a.extent[k] = hi - lo;
  }
  return a;
}

double core_width(std::span<const Eigen::Vector3f> points, double share) {
  const PrincipalAxes axes = principal_axes(points);
  std::vector<Eigen::Vector3d> finite;
  finite.reserve(points.size());
  for (const auto& p : points) {
    if (p.allFinite()) finite.push_back(p.cast<double>());
  }
  if (finite.size() < 2) return 0.0;
  // The window of the k nearest-together projections, k = the share (at least 2 points).
  const auto k = std::clamp<std::size_t>(static_cast<std::size_t>(std::ceil(share * static_cast<double>(finite.size()))), 2,
                                         finite.size());
  std::vector<double> along(finite.size());
  double widest = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d u = axes.axes.col(axis);
    for (std::size_t i = 0; i < finite.size(); ++i) along[i] = u.dot(finite[i]);
    std::sort(along.begin(), along.end());
    double shortest = along.back() - along.front();
    for (std::size_t i = 0; i + k <= along.size(); ++i) shortest = std::min(shortest, along[i + k - 1] - along[i]);
    widest = std::max(widest, shortest);
  }
  return widest;
}

}  // namespace viewpose
