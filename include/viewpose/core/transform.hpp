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

/// A 3x3 matrix read from a file, taken as the rotation it was meant to be. Files store rotations
/// to a few digits (LM-O's ground truth is off orthonormal by up to 2e-3), so a matrix whose
/// singular values are within `kMaxRotationRounding` of 1 is a rotation with rounding in it, and
/// its nearest rotation (in the Frobenius norm: U V^T of its SVD) is what it meant. A reflection
/// (negative determinant), or a matrix scaled or sheared by more than that, is no rounding.
struct NearRotation {
  enum class Kind { Rotation, Reflection, NotRigid };
  Kind kind = Kind::NotRigid;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  ///< the nearest rotation (when kind is Rotation)
  double deviation = 0;  ///< largest |singular value - 1|: how far the matrix is from orthonormal
  Eigen::Vector3d singular_values = Eigen::Vector3d::Ones();
};
/// Largest |singular value - 1| that rounding explains (a matrix written to three digits is off by
/// up to about 2e-3).
inline constexpr double kMaxRotationRounding = 0.01;
/// Deviations up to this are the last digit of a file's numbers, and are taken without a word;
/// above it, readers say (once per file) that they took the nearest rotation.
inline constexpr double kSilentRotationRounding = 1e-5;
NearRotation nearest_rotation(const Eigen::Matrix3d& M);

/// `cloud` with its points and normals expressed in frame target, given T_target_source.
PointCloud transformed(const PointCloud& cloud, const Transform& T_target_source);

}  // namespace viewpose
