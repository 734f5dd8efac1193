#include "viewpose/core/point_cloud.hpp"

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

BoundingBox bounding_box(const std::vector<Eigen::Vector3f>& points) {
  BoundingBox box;
  for (const auto& p : points) {
    if (p.allFinite()) box.extend(p);
  }
  return box;
}

}  // namespace viewpose
