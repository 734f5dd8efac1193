#include "viewpose/pose/points_on_model.hpp"

#include <algorithm>
#include <cmath>

#include "viewpose/segment/segmentation.hpp"

namespace viewpose {

std::vector<NearModel> near_model(std::span<const Eigen::Vector3f> points, const IcpTarget& model,
                                  const Transform& T_camera_object, float reach_m, const VerifyOptions& verify,
                                  const IcpOptions& icp) {
  std::vector<NearModel> nearness(points.size(), NearModel::far);
  if (model.points.empty() || !(reach_m > 0)) return nearness;
  const Transform T_object_camera = T_camera_object.inverse();
  // The grid's own sizes, whoever made it: a cell's point is at most a cell diagonal farther than
  // the nearest, and outside the grid a point is farther than its margin from every model point.
  const NearestGrid* grid = model.grid(icp.grid_cell_m, icp.reach_m());
  const float slack = grid ? std::sqrt(3.0f) * grid->cell_m() : 0.0f;
  const bool outside_is_far = grid && grid->margin_m() >= reach_m;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p_camera = points[i];
    if (!p_camera.allFinite()) continue;
    const float tolerance = std::min(reach_m, depth_tolerance(p_camera.z(), verify));
    const Eigen::Vector3f p_object = (T_object_camera * p_camera.cast<double>()).cast<float>();
    std::uint32_t index = 0;
    float d2 = 0;
    bool found = grid && grid->nearest(p_object, index, d2);
    if (grid && !found && outside_is_far) continue;
    if (found && d2 > (reach_m + slack) * (reach_m + slack)) continue;
    // The grid's distance is to a model point, so at least the nearest's: within the tolerance it
    // decides; beyond it the tree says exactly.
    if (!found || d2 > tolerance * tolerance) found = model.tree.nearest(p_object, index, d2);
    if (!found || d2 > reach_m * reach_m) continue;
    nearness[i] = d2 <= tolerance * tolerance ? NearModel::on : NearModel::near;
  }
  return nearness;
}

std::vector<char> on_model(std::span<const Eigen::Vector3f> points, const IcpTarget& model, const Transform& T_camera_object,
                           const VerifyOptions& verify, const IcpOptions& icp) {
  std::vector<char> on(points.size(), 0);
  if (model.points.empty()) return on;
  const Transform T_object_camera = T_camera_object.inverse();
  // As near_model: the grid's own slack and margin. No tolerance exceeds max_tolerance_m, so
  // outside a grid whose margin reaches that far no point is on the model.
  const NearestGrid* grid = model.grid(icp.grid_cell_m, icp.reach_m());
  const float slack = grid ? std::sqrt(3.0f) * grid->cell_m() : 0.0f;
  const bool outside_is_off = grid && grid->margin_m() >= verify.max_tolerance_m;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p_camera = points[i];
    if (!p_camera.allFinite()) continue;
    const float tolerance = depth_tolerance(p_camera.z(), verify);
    const Eigen::Vector3f p_object = (T_object_camera * p_camera.cast<double>()).cast<float>();
    std::uint32_t index = 0;
    float d2 = 0;
    const bool found = grid && grid->nearest(p_object, index, d2);
    if (grid && !found && outside_is_off) continue;
    if (found && d2 > (tolerance + slack) * (tolerance + slack)) continue;
    if (found && d2 <= tolerance * tolerance) {
      on[i] = 1;
      continue;
    }
    on[i] = model.tree.nearest(p_object, index, d2) && d2 <= tolerance * tolerance;
  }
  return on;
}

PointCloud piece_on_model(const PointCloud& points, const IcpTarget& model, const Transform& T_camera_object,
                          float reach_m, const VerifyOptions& verify, const IcpOptions& icp,
                          const ClusterOptions& clusters) {
  const std::vector<NearModel> nearness = near_model(points.points, model, T_camera_object, reach_m, verify, icp);
  std::vector<std::uint32_t> within;
  for (std::uint32_t i = 0; i < nearness.size(); ++i) {
    if (nearness[i] != NearModel::far) within.push_back(i);
  }
  if (within.size() < clusters.min_points) return {};
  const std::vector<Cluster> pieces = euclidean_clusters(points, within, clusters);  // (indices into `points`)
  if (pieces.empty()) return {};
  // Each piece's points on the model, counted once; the first of the best (most on, then largest).
  std::size_t best = 0, best_on = 0;
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const auto on = static_cast<std::size_t>(
        std::count_if(pieces[k].begin(), pieces[k].end(), [&](std::uint32_t i) { return nearness[i] == NearModel::on; }));
    if (k == 0 || on > best_on || (on == best_on && pieces[k].size() > pieces[best].size())) best = k, best_on = on;
  }
  return cluster_points(points, pieces[best]);
}

}  // namespace viewpose
