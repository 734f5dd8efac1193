#pragma once
// Pose error metrics of the BOP benchmark (Hodan et al.), on model points in metres.
#include <span>

#include <Eigen/Core>

#include "viewpose/core/transform.hpp"

namespace viewpose {

/// ADD: mean distance between the model points moved by the estimate and by the truth.
double add_error(const Transform& T_estimate, const Transform& T_truth, std::span<const Eigen::Vector3f> model_points);

/// ADD-S: mean distance from each model point under the estimate to the nearest model point under
/// the truth (for symmetric objects, where ADD would punish an equivalent pose).
double add_s_error(const Transform& T_estimate, const Transform& T_truth, std::span<const Eigen::Vector3f> model_points);

}  // namespace viewpose
