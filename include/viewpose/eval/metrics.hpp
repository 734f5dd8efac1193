#pragma once
// Pose error metrics of the BOP benchmark (Hodan et al.), on model points in metres.
#include <span>

#include <Eigen/Core>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/transform.hpp"

namespace viewpose {

/// ADD: mean distance between the model points moved by the estimate and by the truth.
double add_error(const Transform& T_estimate, const Transform& T_truth, std::span<const Eigen::Vector3f> model_points);

/// MSSD (BOP 2019): the largest distance between a model point under the estimate and under the
/// truth, at the best of the model's symmetries (object-frame transforms; include the identity).
double mssd_error(const Transform& T_estimate, const Transform& T_truth, std::span<const Eigen::Vector3f> model_points,
                  std::span<const Transform> symmetries);

/// MSPD (BOP 2019): the largest distance in pixels between a model point's projections through K
/// under the estimate and under the truth, at the best of the model's symmetries (as mssd_error).
/// Points at or behind the camera's plane under either pose count as infinitely far.
double mspd_error(const Transform& T_estimate, const Transform& T_truth, std::span<const Eigen::Vector3f> model_points,
                  std::span<const Transform> symmetries, const CameraIntrinsics& K);

/// Angle of R_estimate R_truth^T, degrees.
double rotation_error_deg(const Eigen::Matrix3d& R_estimate, const Eigen::Matrix3d& R_truth);

/// ADD-S: mean distance from each model point under the estimate to the nearest model point under
/// the truth (for symmetric objects, where ADD would punish an equivalent pose).
double add_s_error(const Transform& T_estimate, const Transform& T_truth, std::span<const Eigen::Vector3f> model_points);

}  // namespace viewpose
