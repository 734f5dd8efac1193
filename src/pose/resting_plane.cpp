#include "viewpose/pose/resting_plane.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace viewpose {

std::optional<Eigen::Vector3d> resting_plane_up(std::span<const Eigen::Vector4f> planes, std::span<const Eigen::Vector3f> model_points,
                                                const Transform& T_camera_object, float touch_m) {
  if (model_points.empty() || !(touch_m >= 0)) return std::nullopt;
  const Eigen::Matrix3f R = T_camera_object.linear().cast<float>();
  const Eigen::Vector3f t = T_camera_object.translation().cast<float>();
  const Eigen::Vector3d default_up = Eigen::Vector3d(0, -1, -1).normalized();
  std::optional<Eigen::Vector3d> best;
  double best_alignment = -std::numeric_limits<double>::infinity();
  for (const Eigen::Vector4f& plane : planes) {
    const Eigen::Vector3f n = plane.head<3>();
    if (!(std::abs(n.norm() - 1.0f) < 1e-3f)) continue;  // not a plane (or not finite)
    // The model's lowest point above the plane: n.(R p + t) + d = (R^T n).p + n.t + d.
    const Eigen::Vector3f n_object = R.transpose() * n;
    const float offset = n.dot(t) + plane.w();
    float lowest = std::numeric_limits<float>::infinity();
    for (const Eigen::Vector3f& p : model_points) lowest = std::min(lowest, n_object.dot(p));
    if (!(std::abs(lowest + offset) <= touch_m)) continue;
    const Eigen::Vector3d up = n.cast<double>().normalized();
    const double alignment = up.dot(default_up);
    if (alignment > best_alignment) best_alignment = alignment, best = up;
  }
  return best;
}

}  // namespace viewpose
