#include "viewpose/eval/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "viewpose/core/kdtree.hpp"

namespace viewpose {

double add_error(const Transform& T_estimate, const Transform& T_truth, std::span<const Eigen::Vector3f> model) {
  if (model.empty()) return 0.0;
  double sum = 0;
  for (const auto& p : model) sum += (T_estimate * p.cast<double>() - T_truth * p.cast<double>()).norm();
  return sum / static_cast<double>(model.size());
}

double add_s_error(const Transform& T_estimate, const Transform& T_truth, std::span<const Eigen::Vector3f> model) {
  if (model.empty()) return 0.0;
  std::vector<Eigen::Vector3f> truth;
  truth.reserve(model.size());
  for (const auto& p : model) truth.push_back((T_truth * p.cast<double>()).cast<float>());
  const KdTree tree(truth);
  double sum = 0;
  for (const auto& p : model) {
    std::uint32_t k;
    float d2;
    tree.nearest((T_estimate * p.cast<double>()).cast<float>(), k, d2);
    sum += std::sqrt(static_cast<double>(d2));
  }
  return sum / static_cast<double>(model.size());
}

double mssd_error(const Transform& T_estimate, const Transform& T_truth, std::span<const Eigen::Vector3f> model,
                  std::span<const Transform> symmetries) {
  if (model.empty()) return 0.0;
  const Transform identity = Transform::Identity();
  if (symmetries.empty()) symmetries = std::span(&identity, 1);
  double best = std::numeric_limits<double>::infinity();
  for (const Transform& S : symmetries) {
    const Transform T_truth_sym = T_truth * S;
    double worst = 0;
    for (const auto& p : model) {
      worst = std::max(worst, (T_estimate * p.cast<double>() - T_truth_sym * p.cast<double>()).norm());
      if (worst >= best) break;  // this symmetry cannot do better
    }
    best = std::min(best, worst);
  }
  return best;
}

double mspd_error(const Transform& T_estimate, const Transform& T_truth, std::span<const Eigen::Vector3f> model,
                  std::span<const Transform> symmetries, const CameraIntrinsics& K) {
  if (model.empty()) return 0.0;
  const Transform identity = Transform::Identity();
  if (symmetries.empty()) symmetries = std::span(&identity, 1);
  constexpr double inf = std::numeric_limits<double>::infinity();
  // The estimate's projections once; the truth's per symmetry.
  std::vector<Eigen::Vector2d> estimate;
  estimate.reserve(model.size());
  for (const auto& p : model) {
    const Eigen::Vector3d c = T_estimate * p.cast<double>();
    estimate.push_back(c.z() > 0 ? K.project(c) : Eigen::Vector2d(inf, inf));
  }
  double best = inf;
  for (const Transform& S : symmetries) {
    const Transform T_truth_sym = T_truth * S;
    double worst = 0;
    for (std::size_t i = 0; i < model.size(); ++i) {
      const Eigen::Vector3d c = T_truth_sym * model[i].cast<double>();
      const double d = c.z() > 0 && std::isfinite(estimate[i].x()) ? (estimate[i] - K.project(c)).norm() : inf;
      worst = std::max(worst, d);
      if (worst >= best) break;  // this symmetry cannot do better
    }
    best = std::min(best, worst);
  }
  return best;
}

double rotation_error_deg(const Eigen::Matrix3d& R_estimate, const Eigen::Matrix3d& R_truth) {
  const double c = std::clamp(((R_estimate * R_truth.transpose()).trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

}  // namespace viewpose
