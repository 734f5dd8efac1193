#include "viewpose/pose/through_planes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace viewpose {

ObservedPlanes::ObservedPlanes(std::span<const Plane> planes, const PointCloud& frame, const CameraIntrinsics& K, int cell_px)
    : K_(K), cell_px_(std::max(1, cell_px)) {
  if (K.width <= 0 || K.height <= 0 || !(K.fx > 0) || !(K.fy > 0)) return;
  cols_ = (K.width + cell_px_ - 1) / cell_px_;
  rows_ = (K.height + cell_px_ - 1) / cell_px_;
  seen_.assign(static_cast<std::size_t>(cols_) * static_cast<std::size_t>(rows_), 0);
  // (At most 255 planes are told apart; a segmentation removes a handful.)
  const std::size_t n = std::min<std::size_t>(planes.size(), std::numeric_limits<std::uint8_t>::max());
  for (std::size_t k = 0; k < n; ++k) {
    planes_.push_back(planes[k].coefficients);
    const auto label = static_cast<std::uint8_t>(k + 1);
    for (const std::uint32_t i : planes[k].inliers) {
      if (i >= frame.points.size()) continue;
      const Eigen::Vector3f& p = frame.points[i];
      if (!p.allFinite() || !(p.z() > 0)) continue;
      const Eigen::Vector2d uv = K.project(p.cast<double>());
      const double cu = std::floor(uv.x() / cell_px_), cv = std::floor(uv.y() / cell_px_);
      if (!(cu >= 0 && cu < cols_ && cv >= 0 && cv < rows_)) continue;
      std::uint8_t& cell = seen_[static_cast<std::size_t>(cv) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(cu)];
      if (cell == 0) cell = label;
    }
  }
}

double ObservedPlanes::share_inside(std::span<const Eigen::Vector3f> model_points, const Transform& T_camera_object, float margin_m) const {
  if (planes_.empty() || model_points.empty()) return 0;
  const Eigen::Matrix3f R = T_camera_object.linear().cast<float>();
  const Eigen::Vector3f t = T_camera_object.translation().cast<float>();
  // Per plane: the points inside it where it was seen, and those in front of it.
  std::vector<std::size_t> inside(planes_.size(), 0), in_front(planes_.size(), 0);
  std::size_t counted = 0;
  for (const Eigen::Vector3f& m : model_points) {
    if (!m.allFinite()) continue;
    ++counted;
    const Eigen::Vector3f p = R * m + t;
    for (std::size_t k = 0; k < planes_.size(); ++k) {
      const Eigen::Vector3f n = planes_[k].head<3>();
      const float s = n.dot(p) + planes_[k].w();  // > 0: the camera's side
      if (s > margin_m) {
        ++in_front[k];
        continue;
      }
      if (!(s < -margin_m)) continue;
      const Eigen::Vector3f foot = p - s * n;
      if (!(foot.z() > 0)) continue;
      const Eigen::Vector2d uv = K_.project(foot.cast<double>());
      const double cu = std::floor(uv.x() / cell_px_), cv = std::floor(uv.y() / cell_px_);
      if (!(cu >= 0 && cu < cols_ && cv >= 0 && cv < rows_)) continue;
      inside[k] += seen_[static_cast<std::size_t>(cv) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(cu)] == k + 1;
    }
  }
  // Only a model on both sides of a plane is in it: one wholly behind it is under a table or a
  // shelf's board (a thin surface), seen past its edge.
  std::size_t worst = 0;
  for (std::size_t k = 0; k < planes_.size(); ++k) {
    if (in_front[k] > 0) worst = std::max(worst, inside[k]);
  }
  return counted ? static_cast<double>(worst) / static_cast<double>(counted) : 0.0;
}

}  // namespace viewpose
