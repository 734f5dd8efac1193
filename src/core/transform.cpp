#include "viewpose/core/transform.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace viewpose {

Transform make_transform(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Transform T = Transform::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

double rotation_difference_deg(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b) {
  const double c = std::clamp(((R_a.transpose() * R_b).trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * 180.0 / std::numbers::pi;
}

bool is_rotation(const Eigen::Matrix3d& R, double tolerance) {
  return R.allFinite() && (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < tolerance &&
         std::abs(R.determinant() - 1.0) < tolerance;
}

PointCloud transformed(const PointCloud& cloud, const Transform& T_target_source) {
  PointCloud out = cloud;
  const Eigen::Matrix3f R = T_target_source.linear().cast<float>();
  const Eigen::Vector3f t = T_target_source.translation().cast<float>();
  for (auto& p : out.points) p = R * p + t;  // NaN stays NaN
  for (auto& n : out.normals) n = R * n;
  return out;
}

}  // namespace viewpose
