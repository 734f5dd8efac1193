#pragma once
// Voxel-grid downsampling as PCL's VoxelGrid: one point per occupied cube, at the centroid of the
// points inside it.
#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

/// An unorganized cloud with one point per occupied `leaf_m` cube (non-finite points dropped).
/// Normals are averaged and renormalized; labels and colours are those of the voxel's first point.
PointCloud voxel_downsample(const PointCloud& cloud, float leaf_m);

}  // namespace viewpose
