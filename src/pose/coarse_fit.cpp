#include "viewpose/pose/coarse_fit.hpp"

#include <algorithm>
#include <vector>

namespace viewpose {

double overlap(std::span<const Eigen::Vector3f> points, const Transform& T_grid_points, const OccupancyGrid& grid,
               std::size_t max_points) {
  if (points.empty() || grid.empty() || max_points == 0) return 0;
  const std::size_t n = std::min(points.size(), max_points);
  const Eigen::Matrix3f R = T_grid_points.linear().cast<float>();
  const Eigen::Vector3f t = T_grid_points.translation().cast<float>();
  int sum = 0;  // in halves
  for (std::size_t k = 0; k < n; ++k) {
    // The k-th of n evenly spread: points.size() * k / n, without overflow for any size here.
    const Eigen::Vector3f& p = points[points.size() * k / n];
    sum += grid.level(R * p + t);
  }
  return 0.5 * static_cast<double>(sum) / static_cast<double>(n);
}

double coarse_fit(const CoarseFitInputs& in, const Transform& T_camera_view, const Transform& T_camera_object,
                  std::size_t max_points) {
  if (!in.region_grid || !in.model_grid) return 0;
  const double region_on_model = overlap(in.region_points, T_camera_object.inverse(), *in.model_grid, max_points);
  const double view_on_region = overlap(in.view_points, T_camera_view, *in.region_grid, max_points);
  return std::min(region_on_model, view_on_region);
}

double coarse_fit_facing(std::span<const Eigen::Vector3f> region_points, const OccupancyGrid& region_grid,
                         std::span<const Eigen::Vector3f> model_points, std::span<const Eigen::Vector3f> model_normals,
                         const OccupancyGrid& model_grid, const Transform& T_camera_object, std::size_t max_points) {
  const Eigen::Matrix3f R = T_camera_object.linear().cast<float>();
  const Eigen::Vector3f t = T_camera_object.translation().cast<float>();
  std::vector<Eigen::Vector3f> facing;  // object frame
  for (std::size_t i = 0; i < model_points.size() && i < model_normals.size(); ++i) {
    if ((R * model_normals[i]).dot(R * model_points[i] + t) < 0) facing.push_back(model_points[i]);
  }
  if (facing.empty()) return 0;
  const double region_on_model = overlap(region_points, T_camera_object.inverse(), model_grid, max_points);
  const double model_on_region = overlap(facing, T_camera_object, region_grid, max_points);
  return std::min(region_on_model, model_on_region);
}

}  // namespace viewpose
