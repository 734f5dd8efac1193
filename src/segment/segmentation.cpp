#include "viewpose/segment/segmentation.hpp"

#include "viewpose/segment/voxel_grid.hpp"

#include "viewpose/core/stopwatch.hpp"

namespace viewpose {

Segmentation segment_scene(const PointCloud& frame, const SegmentOptions& options, SegmentTimes* times) {
  Segmentation s;
  // Planes first, on the frame as measured (they are searched for in a sample of it), so that only
  // what stands on them is voxelized: a table is most of a frame.
  auto t = Clock::now();
  PlaneRemoval planes = remove_large_planes(frame, options.planes);
  s.planes = std::move(planes.removed);
  if (times) times->planes_ms += ms_since(t);
  t = Clock::now();
  if (options.max_depth_m > 0) {
    std::erase_if(planes.remaining, [&](std::uint32_t i) { return !(frame.points[i].z() <= options.max_depth_m); });
  }
  s.points = voxel_downsample(cluster_points(frame, planes.remaining), options.voxel_m);
  if (times) times->downsample_ms += ms_since(t);
  t = Clock::now();
  std::vector<std::uint32_t> all(s.points.size());
  for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  s.clusters = euclidean_clusters(s.points, all, options.clusters);
  if (times) times->clusters_ms += ms_since(t);
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
