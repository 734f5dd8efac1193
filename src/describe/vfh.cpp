#include "viewpose/describe/vfh.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace viewpose {

// Single precision throughout, in PCL's order of operations, so that bins agree with PCL's.
bool pair_features(const Eigen::Vector3f& p1, const Eigen::Vector3f& n1, const Eigen::Vector3f& p2,
                   const Eigen::Vector3f& n2, float& f1, float& f2, float& f3, float& f4) {
  Eigen::Vector3f d = p2 - p1;
  f4 = d.norm();
  if (f4 == 0.0f) {
    f1 = f2 = f3 = f4 = 0.0f;
    return false;
  }
  Eigen::Vector3f u = n1, other = n2;
  const float a1 = n1.dot(d) / f4, a2 = n2.dot(d) / f4;
  // The source is the point whose normal makes the smaller angle with the connecting line.
  if (std::acos(std::fabs(a1)) > std::acos(std::fabs(a2))) {
    u = n2;
    other = n1;
    d = -d;
    f3 = -a2;
  } else {
    f3 = a1;
  }
  Eigen::Vector3f v = d.cross(u);
  const float v_norm = v.norm();
  if (v_norm == 0.0f) {
    f1 = f2 = f3 = f4 = 0.0f;
    return false;
  }
  v /= v_norm;
  const Eigen::Vector3f w = u.cross(v);
  f2 = v.dot(other);
  f1 = std::atan2(w.dot(other), u.dot(other));
  return true;
}

Vfh compute_vfh(std::span<const Eigen::Vector3f> points, std::span<const Eigen::Vector3f> normals, const VfhOptions& o) {
  Vfh h{};
  std::vector<std::size_t> valid;
  valid.reserve(points.size());
  for (std::size_t i = 0; i < points.size() && i < normals.size(); ++i) {
    if (points[i].allFinite() && normals[i].allFinite()) valid.push_back(i);
  }
  const std::size_t n = valid.size();
  if (n < 2) return h;

  Eigen::Vector3f centroid = Eigen::Vector3f::Zero(), mean_normal = Eigen::Vector3f::Zero();
  for (std::size_t i : valid) {
    centroid += points[i];
    mean_normal += normals[i];
  }
  centroid /= static_cast<float>(n);
  mean_normal /= static_cast<float>(n);
  if (!o.pcl_compatible && mean_normal.norm() > 0) mean_normal.normalize();

  // Extended FPFH between the centroid and every point.
  const double incr = o.normalize_bins ? 100.0 / static_cast<double>(n - 1) : 1.0;
  const float size_incr = o.size_component ? static_cast<float>(incr) : 0.0f;
  const float d_pi = 1.0f / (2.0f * static_cast<float>(M_PI));
  double max_distance = 0.0;
  for (std::size_t i : valid) max_distance = std::max(max_distance, static_cast<double>((points[i] - centroid).norm()));
  // PCL subtracts a point with w = 0 from its w = 1 centroid: the homogeneous 1 joins the norm.
  double distance_factor = o.pcl_compatible ? std::sqrt(max_distance * max_distance + 1.0) : max_distance;
  if (!o.normalize_distances || !(distance_factor > 0)) distance_factor = 1.0;
  const auto clamp45 = [](int b) { return std::clamp(b, 0, 44); };
  const auto angle_bin = [&](float f) { return clamp45(static_cast<int>(std::floor(45 * ((f + M_PI) * d_pi)))); };
  const auto cosine_bin = [&](float f) {
    return o.pcl_compatible ? angle_bin(f) : clamp45(static_cast<int>(std::floor(45 * (f + 1.0) * 0.5)));
  };
  for (std::size_t i : valid) {
    float f1, f2, f3, f4;
    if (!pair_features(centroid, mean_normal, points[i], normals[i], f1, f2, f3, f4)) continue;
    h[static_cast<std::size_t>(angle_bin(f1))] += static_cast<float>(incr);
    h[45 + static_cast<std::size_t>(cosine_bin(f2))] += static_cast<float>(incr);
    h[90 + static_cast<std::size_t>(cosine_bin(f3))] += static_cast<float>(incr);
    const int b4 = o.normalize_distances ? static_cast<int>(std::floor(45 * (f4 / distance_factor)))
                                         : static_cast<int>(std::round(f4 * 100));
    h[135 + static_cast<std::size_t>(clamp45(b4))] += size_incr;
  }

  // Viewpoint component: the angle of every normal with the direction to the viewpoint.
  Eigen::Vector3f to_viewpoint = o.viewpoint - centroid;
  const float norm = o.pcl_compatible ? std::sqrt(to_viewpoint.squaredNorm() + 1.0f) : to_viewpoint.norm();
  if (norm > 0) to_viewpoint /= norm;
  const double vp_incr = o.normalize_bins ? 100.0 / static_cast<double>(n) : 1.0;
  for (std::size_t i : valid) {
    const double alpha = (normals[i].dot(to_viewpoint) + 1.0) * 0.5;
    const int bin = std::clamp(static_cast<int>(std::floor(alpha * 128.0)), 0, 127);
    h[180 + static_cast<std::size_t>(bin)] += static_cast<float>(vp_incr);
  }
  return h;
}

}  // namespace viewpose
