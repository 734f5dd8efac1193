#pragma once
// One description of a cluster of points seen from the camera: normals, VFH, CRH and centroid.
// Scene clusters and database views go through this same function.
#include "viewpose/core/point_cloud.hpp"
#include "viewpose/describe/crh.hpp"
#include "viewpose/describe/normals.hpp"
#include "viewpose/describe/vfh.hpp"

namespace viewpose {

struct DescribeOptions {
  NormalOptions normals;  ///< radius 1.5 cm by default
  VfhOptions vfh;         ///< PCL-compatible 3d_rec_framework VFH by default
};

struct Description {
  Vfh vfh{};
  Crh crh{};
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  ///< mean of the points, camera frame
  PointCloud cloud;  ///< the points with their normals (points without a normal are dropped)
};

/// Milliseconds spent in each part of describe().
struct DescribeTimes {
  double normals_ms = 0, vfh_ms = 0, crh_ms = 0;
};

/// Describes `points` (camera frame, metres; already voxelized as the caller wants).
Description describe(PointCloud points, const DescribeOptions& options = {}, DescribeTimes* times = nullptr);

}  // namespace viewpose
