#pragma once
// The thesis's preprocessing of a frame: voxel grid, removal of large planes, Euclidean clusters.
// Each cluster is a candidate object, handed to describe().
#include <vector>

#include "viewpose/core/point_cloud.hpp"
#include "viewpose/segment/clusters.hpp"
#include "viewpose/segment/planes.hpp"

namespace viewpose {

struct SegmentOptions {
  float voxel_m = 0.003f;  ///< thesis: 3 mm
  PlaneOptions planes;
  ClusterOptions clusters;
};

struct Segmentation {
  PointCloud points;              ///< the voxelized frame
  std::vector<Plane> planes;      ///< removed planes (indices into points)
  std::vector<Cluster> clusters;  ///< candidate objects (indices into points), largest first
};

/// Milliseconds spent in each part of segment_scene().
struct SegmentTimes {
  double downsample_ms = 0, planes_ms = 0, clusters_ms = 0;
};

Segmentation segment_scene(const PointCloud& frame, const SegmentOptions& options = {}, SegmentTimes* times = nullptr);

/// The points of one cluster as their own cloud.
PointCloud cluster_points(const PointCloud& points, const Cluster& cluster);

}  // namespace viewpose
