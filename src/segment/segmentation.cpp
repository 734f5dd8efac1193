#include "viewpose/segment/segmentation.hpp"

#include "viewpose/segment/voxel_grid.hpp"

namespace viewpose {

Segmentation segment_scene(const PointCloud& frame, const SegmentOptions& options) {
  Segmentation s;
  s.points = voxel_downsample(frame, options.voxel_m);
  PlaneRemoval planes = remove_large_planes(s.points, options.planes);
  s.planes = std::move(planes.removed);
  s.clusters = euclidean_clusters(s.points, planes.remaining, options.clusters);
  return s;
}

PointCloud cluster_points(const PointCloud& points, const Cluster& cluster) {
  PointCloud out;
  out.points.reserve(cluster.size());
  for (std::uint32_t i : cluster) out.points.push_back(points.points[i]);
  if (!points.labels.empty()) {
    for (std::uint32_t i : cluster) out.labels.push_back(points.labels[i]);
  }
  out.width = static_cast<int>(out.points.size());
  return out;
}

}  // namespace viewpose
