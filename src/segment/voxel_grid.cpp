#include "viewpose/segment/voxel_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <fmt/format.h>

#include "viewpose/core/cell_grid.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/threads.hpp"

namespace viewpose {

PointCloud voxel_downsample(const PointCloud& cloud, float leaf_m) {
  if (!(leaf_m > 0)) throw Error(fmt::format("voxel grid: leaf size {} must be positive", leaf_m));
  cloud.check_consistent();
  // Points sorted by voxel (core/cell_grid), each voxel a run of them.
  const CellGrid grid = bin_points(cloud.points, {}, leaf_m, 0);
  PointCloud out;
  const bool normals = cloud.has_normals(), labels = !cloud.labels.empty(), colours = !cloud.rgba.empty();
  const std::size_t cells = grid.cells.size();
  out.points.resize(cells);
  if (normals) out.normals.resize(cells);
  if (labels) out.labels.resize(cells);
  if (colours) out.rgba.resize(cells);
  // Each voxel's mean on its own: a frame's voxels on every thread, as its points were binned
  // (inside a parallel region, the caller's thread alone). Each sum runs in the points' order,
  // whatever the threads.
#pragma omp parallel for schedule(dynamic, 4096) if (on_every_thread(cloud.size()))
  for (std::size_t c = 0; c < cells; ++c) {
    const std::size_t a = grid.first[c], b = grid.first[c + 1];
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), nsum = Eigen::Vector3d::Zero();
    for (std::size_t k = a; k < b; ++k) {
      const std::uint32_t i = grid.items[k].second;
      sum += cloud.points[i].cast<double>();
      if (normals && cloud.normals[i].allFinite()) nsum += cloud.normals[i].cast<double>();
    }
    out.points[c] = (sum / static_cast<double>(b - a)).cast<float>();
    if (normals) out.normals[c] = nsum.norm() > 0 ? Eigen::Vector3f(nsum.normalized().cast<float>()) : Eigen::Vector3f::Constant(NAN);
    if (labels) out.labels[c] = cloud.labels[grid.items[a].second];
    if (colours) out.rgba[c] = cloud.rgba[grid.items[a].second];
  }
  out.width = static_cast<int>(out.points.size());
  out.height = 1;
  return out;
}

}  // namespace viewpose
