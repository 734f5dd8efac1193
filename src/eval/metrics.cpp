#include "viewpose/eval/metrics.hpp"

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

}  // namespace viewpose
