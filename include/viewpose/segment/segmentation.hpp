#pragma once
// The thesis's preprocessing of a frame: removal of large planes, voxel grid, Euclidean clusters.
// Each cluster is a candidate object, handed to describe(). (The thesis voxelized first; removing
// the planes first, from a sample of the frame, leaves a tenth of the points to voxelize, and the
// same voxels.)
#include <vector>

#include "viewpose/core/point_cloud.hpp"
#include "viewpose/segment/clusters.hpp"
#include "viewpose/segment/planes.hpp"

namespace viewpose {

struct SegmentOptions {
  float voxel_m = 0.003f;  ///< thesis: 3 mm
  /// What stands on the planes farther than this (depth, metres) is left out of the clusters: a
  /// Kinect's or Xtion's depth there is centimetres of noise, and verification gives no verdict on
  /// poses past 3.5 m (VerifyOptions::max_depth_m). A far room's wall, cabinets and clutter were
  /// most of an office frame's points and its segmentation's time. (0: no limit.)
  float max_depth_m = 4.0f;
  PlaneOptions planes;
  ClusterOptions clusters;
};

struct Segmentation {
  PointCloud points;              ///< what is left of the frame once the planes are removed, voxelized
  std::vector<Plane> planes;      ///< removed planes (their inliers index the input frame)
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
