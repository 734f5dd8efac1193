#include "viewpose/pose/resting_plane.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace viewpose {

std::optional<Eigen::Vector3d> resting_plane_up(std::span<const Eigen::Vector4f> planes, std::span<const Eigen::Vector3f> model_points,
                                                const Transform& T_camera_object, std::span<const Eigen::Vector3d> standing_axes,
                                                float touch_m) {
  if (model_points.empty() || standing_axes.empty() || !(touch_m >= 0)) return std::nullopt;
  const double min_alignment = std::cos(30.0 * M_PI / 180.0);
  const Eigen::Matrix3f R = T_camera_object.linear().cast<float>();
  const Eigen::Vector3f t = T_camera_object.translation().cast<float>();
  std::optional<Eigen::Vector3d> best;
  double best_alignment = 0;
  for (const Eigen::Vector4f& plane : planes) {
    const Eigen::Vector3f n = plane.head<3>();
    if (!(std::abs(n.norm() - 1.0f) < 1e-3f) || !std::isfinite(plane.w())) continue;  // not a plane
    // The axis nearest the normal, either way (checked first: it is the cheaper test).
    const Eigen::Vector3d n_object = T_camera_object.linear().transpose() * n.cast<double>();
    double alignment = 0;
    for (const Eigen::Vector3d& axis : standing_axes) alignment = std::max(alignment, std::abs(axis.dot(n_object)));
    if (!(alignment >= min_alignment) || (best && !(alignment > best_alignment))) continue;
    // The model's lowest point above the plane: n.(R p + t) + d = (R^T n).p + n.t + d.
    const Eigen::Vector3f n_model = R.transpose() * n;
    float lowest = std::numeric_limits<float>::infinity();
    for (const Eigen::Vector3f& p : model_points) lowest = std::min(lowest, n_model.dot(p));
    if (!(std::abs(lowest + n.dot(t) + plane.w()) <= touch_m)) continue;
    best_alignment = alignment;
    best = n.cast<double>().normalized();
  }
  return best;
}

}  // namespace viewpose
