#include "viewpose/core/transform.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Eigenvalues>

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

NearRotation nearest_rotation(const Eigen::Matrix3d& M) {
  NearRotation out;
  if (!M.allFinite()) return out;
  // The polar decomposition M = R P with P = (M^T M)^(1/2): R is the nearest rotation when det M > 0,
  // and P's eigenvalues, the singular values of M, say how far M is from orthonormal.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(M.transpose() * M);
  const Eigen::Vector3d lambda = eig.eigenvalues();
  if (eig.info() != Eigen::Success || !(lambda.minCoeff() > 0)) return out;
  const Eigen::Vector3d sigma = lambda.cwiseSqrt();
  out.singular_values = sigma.reverse();  // largest first
  out.deviation = (sigma.array() - 1.0).abs().maxCoeff();
  if (M.determinant() < 0) {
    out.kind = NearRotation::Kind::Reflection;
  } else if (out.deviation > kMaxRotationRounding) {
    out.kind = NearRotation::Kind::NotRigid;
  } else if (out.deviation <= 1e-12) {
    // Orthonormal to double precision: taken exactly as given, so that rotations read back from
    // files we wrote at full precision stay bit for bit what they were (bop --resume rewrites the
    // rows it read; the correction would move their last digits).
    out.R = M;
    out.kind = NearRotation::Kind::Rotation;
  } else {
    const Eigen::Matrix3d& V = eig.eigenvectors();
    out.R = M * V * sigma.cwiseInverse().asDiagonal() * V.transpose();
    out.kind = NearRotation::Kind::Rotation;
  }
  return out;
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
