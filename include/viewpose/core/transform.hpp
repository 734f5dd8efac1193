#pragma once
// Rigid transforms are named by their frames: T_target_source maps coordinates expressed in frame
// `source` into frame `target`. T_camera_object takes a point on the object (object frame, metres)
// to where the camera sees it. Composition reads right to left: T_a_c = T_a_b * T_b_c.
#include <Eigen/Geometry>

#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

using Transform = Eigen::Isometry3d;

/// A rigid transform from a rotation matrix and a translation in metres.
Transform make_transform(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);

/// The angle in degrees of the rotation that takes R_a onto R_b (0 to 180).
double rotation_difference_deg(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b);

/// True when R is a rotation matrix (orthonormal, determinant +1) within `tolerance`.
bool is_rotation(const Eigen::Matrix3d& R, double tolerance = 1e-4);

/// `cloud` with its points and normals expressed in frame target, given T_target_source.
PointCloud transformed(const PointCloud& cloud, const Transform& T_target_source);

}  // namespace viewpose
